"""Observation and action spaces shaped like gymnasium's, without requiring it.

When gymnasium is importable, Box and Dict are gymnasium.spaces.Box and gymnasium.spaces.Dict
(so a UrlabEnv passes gymnasium's checks and wrappers); otherwise they are the small classes
below, with the same constructor arguments and the parts of the API a learning loop uses:
shape, dtype, low/high, sample(), contains() (and `in`), seed(), and for Dict the mapping of
names to subspaces.
"""
from collections import OrderedDict

import numpy as np

try:  # pragma: no cover - depends on the machine
    from gymnasium import spaces as _gym_spaces
except ImportError:
    _gym_spaces = None


class _Space:
    def __init__(self, shape, dtype, seed=None):
        self._shape = None if shape is None else tuple(shape)
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = None
        if seed is not None:
            self.seed(seed)

    @property
    def shape(self):
        return self._shape

    @property
    def np_random(self):
        if self._np_random is None:
            self.seed()
        return self._np_random

    def seed(self, seed=None):
        self._np_random = np.random.default_rng(seed)
        return [seed]

    def __contains__(self, x):
        return self.contains(x)


class OwnBox(_Space):
    """A box in R^n: low <= x <= high elementwise (bounds may be infinite)."""

    def __init__(self, low, high, shape=None, dtype=np.float64, seed=None):
        dtype = np.dtype(dtype)
        if shape is None:
            shape = np.broadcast(np.asarray(low), np.asarray(high)).shape
        shape = tuple(int(n) for n in shape)
        self.low = np.broadcast_to(np.asarray(low, dtype=dtype), shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=dtype), shape).copy()
        if np.any(self.low > self.high):
            raise ValueError(f"Box: low > high somewhere (low {self.low}, high {self.high})")
        super().__init__(shape, dtype, seed)

    def is_bounded(self, manner="both"):
        below, above = bool(np.all(np.isfinite(self.low))), bool(np.all(np.isfinite(self.high)))
        return {"both": below and above, "below": below, "above": above}[manner]

    def sample(self):
        """Uniform on a bounded interval, exponential on a half-open one, normal when unbounded
        (gymnasium's documented rule)."""
        rng = self.np_random
        low, high = self.low.astype(np.float64), self.high.astype(np.float64)
        out = np.empty(self.shape, dtype=np.float64)
        lo_ok, hi_ok = np.isfinite(low), np.isfinite(high)
        both, none = lo_ok & hi_ok, ~lo_ok & ~hi_ok
        only_lo, only_hi = lo_ok & ~hi_ok, ~lo_ok & hi_ok
        out[both] = rng.uniform(low[both], high[both])
        out[none] = rng.normal(size=int(none.sum()))
        out[only_lo] = low[only_lo] + rng.exponential(size=int(only_lo.sum()))
        out[only_hi] = high[only_hi] - rng.exponential(size=int(only_hi.sum()))
        if np.issubdtype(self.dtype, np.integer):
            out = np.floor(out)
        return out.astype(self.dtype)

    def contains(self, x):
        if not isinstance(x, np.ndarray):
            try:
                x = np.asarray(x, dtype=self.dtype)
            except (ValueError, TypeError):
                return False
        return bool(x.shape == self.shape and np.can_cast(x.dtype, self.dtype) and
                    np.all(x >= self.low) and np.all(x <= self.high))

    def __repr__(self):
        return f"Box({self.low.min() if self.low.size else 0}, " \
               f"{self.high.max() if self.high.size else 0}, {self.shape}, {self.dtype})"

    def __eq__(self, other):
        return isinstance(other, OwnBox) and self.shape == other.shape and \
            self.dtype == other.dtype and np.array_equal(self.low, other.low) and \
            np.array_equal(self.high, other.high)


class OwnDict(_Space):
    """A dictionary of named subspaces (kept in the order given)."""

    def __init__(self, spaces=None, seed=None, **more):
        spaces = OrderedDict(spaces or {})
        spaces.update(more)
        self.spaces = spaces
        super().__init__(None, None, None)
        if seed is not None:
            self.seed(seed)

    def seed(self, seed=None):
        rng = np.random.default_rng(seed)
        seeds = [seed]
        for space in self.spaces.values():
            seeds += space.seed(int(rng.integers(2**31)))
        self._np_random = rng
        return seeds

    def sample(self):
        return OrderedDict((k, s.sample()) for k, s in self.spaces.items())

    def contains(self, x):
        if not isinstance(x, dict) or set(x) != set(self.spaces):
            return False
        return all(s.contains(x[k]) for k, s in self.spaces.items())

    def __getitem__(self, key):
        return self.spaces[key]

    def __iter__(self):
        return iter(self.spaces)

    def __len__(self):
        return len(self.spaces)

    def keys(self):
        return self.spaces.keys()

    def items(self):
        return self.spaces.items()

    def values(self):
        return self.spaces.values()

    def __repr__(self):
        return "Dict(" + ", ".join(f"{k!r}: {s}" for k, s in self.spaces.items()) + ")"

    def __eq__(self, other):
        return isinstance(other, OwnDict) and self.spaces == other.spaces


if _gym_spaces is not None:  # pragma: no cover - depends on the machine
    Box, Dict = _gym_spaces.Box, _gym_spaces.Dict
else:
    Box, Dict = OwnBox, OwnDict


def batch_space(space, n):
    """The space of n stacked samples of `space` (a leading axis of n), like gymnasium's
    vector envs' observation_space / action_space."""
    if isinstance(space, (OwnDict,) + ((_gym_spaces.Dict,) if _gym_spaces else ())):
        return Dict(OrderedDict((k, batch_space(s, n)) for k, s in space.items()))
    low = np.broadcast_to(space.low, (n,) + space.shape)
    high = np.broadcast_to(space.high, (n,) + space.shape)
    return Box(low=low.copy(), high=high.copy(), dtype=space.dtype)
