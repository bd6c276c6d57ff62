"""The step server's shared-memory channel (docs/network.md, "Shared memory"), client side.

One file mapped by the server and this client: the request and reply bytes are the same msgpack
as over ZeroMQ. The client writes a request and its sequence number, sends one datagram to the
server's wake socket only if the server said it sleeps, then spins on the reply's sequence word
for about as long as the recent round trips took (spin_budget: the channel's wait policy, the
same rules as src/wire/shm_wait.h) and, after that, sleeps on it with a futex (through ctypes),
checking every 50 ms that the server still holds its lock on the file.

Linux on x86_64 only (the futex system call number and the fence below are x86_64's); elsewhere
available() is False and the client stays on ZeroMQ.
"""
import ctypes
import fcntl
import mmap
import os
import platform
import socket
import struct
import threading
import time

# Offsets of the header (src/wire/shm_channel.h).
_MAGIC = b"URLABSHM"
_VERSION = 1
_HEADER = 4096
_REQUEST_CAPACITY, _REPLY_CAPACITY, _GENERATION = 16, 24, 32
_CLIENT_PID, _CLIENT_ATTACHED, _SERVER_CLOSED, _CLIENT_CLOSED = 44, 48, 52, 56
_SERVER_SLEEPING, _CLIENT_WAITING = 64, 128
_REQUEST_SEQ, _REQUEST_LEN, _REPLY_SEQ, _REPLY_LEN = 192, 200, 256, 264
_WAKE_NAME, _WAKE_NAME_BYTES = 320, 108

_SYS_FUTEX = 202  # x86_64
_FUTEX_WAIT = 0
_SLICE = 0.05  # seconds asleep on the reply word between liveness checks
_F_OFD_GETLK, _F_OFD_SETLK = 36, 37
_F_WRLCK, _F_UNLCK = 1, 2


# The wait policy (src/wire/shm_wait.h: the same rules and numbers), in seconds.
MIN_SPIN, SHORT_WAIT, SLACK, MAX_SPIN = 30e-6, 100e-6, 50e-6, 3e-3


def spin_budget(expected, spare_core):
    """How long to spin for a partner expected to take `expected` seconds before sleeping: a
    short wait (up to SHORT_WAIT) three times over; a longer one up to MAX_SPIN (expected x 5/4 +
    SLACK) when spare_core() says a core is free for the spinner, else not at all (it would take
    the core of the servers it waits for); beyond MAX_SPIN, or nothing expected yet, MIN_SPIN."""
    if expected <= 0 or expected > MAX_SPIN:
        return MIN_SPIN
    if expected <= SHORT_WAIT:
        return max(MIN_SPIN, 3 * expected)
    if not spare_core():
        return 0.0
    return min(MAX_SPIN, expected * 1.25 + SLACK)


_loadavg = None
_CORES = os.cpu_count() or 1


def spare_core(waking=0):
    """True when the machine has no more runnable threads (this one among them), plus `waking`
    threads about to run (a batched server's stepping threads beyond the one that reads the
    request: asleep between requests, woken by this one), than CPUs (/proc/loadavg's
    "runnable/total"); False when it cannot tell."""
    global _loadavg
    try:
        if _loadavg is None:
            _loadavg = os.open("/proc/loadavg", os.O_RDONLY | os.O_CLOEXEC)
        runnable = int(os.pread(_loadavg, 128, 0).split()[3].split(b"/")[0])
    except (OSError, ValueError, IndexError):
        return False
    return runnable + waking <= _CORES


class ShmError(ConnectionError):
    """The channel cannot be attached, or the server closed it or died."""


def available():
    return platform.system() == "Linux" and platform.machine() in ("x86_64", "AMD64")


def _flock(kind, byte):
    # struct flock on x86_64: short type, short whence, off_t start, off_t len, pid_t pid (32 bytes)
    return struct.pack("hhqqi4x", kind, os.SEEK_SET, byte, 1, 0)


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


_libc = None


def _syscall():
    global _libc
    if _libc is None:
        _libc = ctypes.CDLL(None, use_errno=True)
        _libc.syscall.restype = ctypes.c_long
    return _libc.syscall


class ShmChannel:
    """One attached channel. Not thread-safe (one request in flight, like a REQ socket)."""

    def __init__(self, path, generation):
        if not available():
            raise ShmError("shared memory: this platform is not supported (Linux x86_64 only)")
        try:
            self._fd = os.open(path, os.O_RDWR | os.O_CLOEXEC | os.O_NOFOLLOW)
        except OSError as e:
            raise ShmError(f"shared memory {path}: cannot open: {e.strerror}") from None
        self._mm = None
        self._words = []
        self._wake = None
        self._attached_here = False  # only an attached client marks the channel closed
        try:
            self._attach(path, generation)
        except BaseException:
            self.close()
            raise

    def _attach(self, path, generation):
        st = os.fstat(self._fd)
        if st.st_uid != os.geteuid():
            raise ShmError(f"shared memory {path}: owned by another user")
        if st.st_size < _HEADER:
            raise ShmError(f"shared memory {path}: shorter than its header")
        self._mm = mmap.mmap(self._fd, st.st_size, mmap.MAP_SHARED,
                             mmap.PROT_READ | mmap.PROT_WRITE)
        mm = self._mm
        if mm[0:8] != _MAGIC:
            raise ShmError(f"shared memory {path}: no URLab channel header")
        version, = struct.unpack_from("<I", mm, 8)
        if version != _VERSION:
            raise ShmError(f"shared memory {path}: channel version {version}, this client speaks "
                           f"{_VERSION}")
        self._req_cap, self._rep_cap, gen = struct.unpack_from("<QQQ", mm, _REQUEST_CAPACITY)
        if _HEADER + self._req_cap + self._rep_cap != st.st_size:
            raise ShmError(f"shared memory {path}: its sizes do not add up to the file's")
        if gen != generation:
            raise ShmError(f"shared memory {path}: another channel than the one offered")
        if not self._locked(0):
            raise ShmError(f"shared memory {path}: its server is gone")
        word = lambda t, off: self._keep(t.from_buffer(mm, off))  # noqa: E731
        self._attached = word(ctypes.c_uint32, _CLIENT_ATTACHED)
        if self._attached.value != 0:
            raise ShmError(f"shared memory {path}: another client attached already")
        try:
            fcntl.fcntl(self._fd, _F_OFD_SETLK, _flock(_F_WRLCK, 1))
        except OSError:
            raise ShmError(f"shared memory {path}: another client attached already") from None
        self._server_closed = word(ctypes.c_uint32, _SERVER_CLOSED)
        self._client_closed = word(ctypes.c_uint32, _CLIENT_CLOSED)
        self._sleeping = word(ctypes.c_uint32, _SERVER_SLEEPING)
        self._waiting = word(ctypes.c_uint32, _CLIENT_WAITING)
        self._req_seq = word(ctypes.c_uint32, _REQUEST_SEQ)
        self._req_len = word(ctypes.c_uint64, _REQUEST_LEN)
        self._rep_seq = word(ctypes.c_uint32, _REPLY_SEQ)
        self._rep_len = word(ctypes.c_uint64, _REPLY_LEN)
        self._rep_seq_addr = ctypes.c_void_p(ctypes.addressof(self._rep_seq))
        name = bytes(mm[_WAKE_NAME:_WAKE_NAME + _WAKE_NAME_BYTES]).split(b"\0", 1)[0]
        self._wake = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self._wake.setblocking(False)
        self._wake.connect(b"\0" + name)
        self._seq = self._req_seq.value
        self._fence = threading.Lock()
        self._view = memoryview(mm)
        self._rtt = 0.0002
        # The server threads one request keeps busy (a batched server's stepping threads): the
        # spin below counts those not running yet as taking a core (spare_core).
        self.partner_threads = 1
        self.path = path
        struct.pack_into("<I", mm, _CLIENT_PID, os.getpid())
        self._attached.value = 1
        self._attached_here = True

    def _keep(self, w):
        self._words.append(w)
        return w

    def _locked(self, byte):
        got = fcntl.fcntl(self._fd, _F_OFD_GETLK, _flock(_F_WRLCK, byte))
        return struct.unpack("hhqqi4x", got)[0] != _F_UNLCK

    def server_gone(self):
        return self._server_closed.value != 0 or not self._locked(0)

    def request(self, payload, timeout):
        """Sends `payload` (bytes) and returns a memoryview of the reply's bytes in the mapping,
        valid until the next request (release it before close())."""
        return self.wait(self.post(payload), timeout)

    def post(self, payload):
        """The first half of request(): writes the request and wakes the server; returns the
        request's sequence number for wait() (one request in flight at a time)."""
        n = len(payload)
        self._fits(n)
        self._view[_HEADER:_HEADER + n] = payload
        return self._publish(n)

    def post_parts(self, head, body):
        """post() of the bytes `head` followed by `body` (a flat byte memoryview, e.g. of a
        C-contiguous numpy array), each copied once, straight into the request slot."""
        h = len(head)
        n = h + body.nbytes
        self._fits(n)
        view = self._view
        view[_HEADER:_HEADER + h] = head
        view[_HEADER + h:_HEADER + n] = body
        return self._publish(n)

    def _fits(self, n):
        if n > self._req_cap:
            raise ShmError(f"shared memory {self.path}: a request of {n} bytes "
                           f"(capacity {self._req_cap})")

    def _publish(self, n):
        self._req_len.value = n
        seq = (self._seq + 1) & 0xFFFFFFFF or 1
        self._seq = seq
        self._req_seq.value = seq
        # A full fence between the store above and the load below (Dekker with the server's
        # "sleeping" flag): a lock operation is a locked instruction, a full fence on x86_64.
        with self._fence:
            pass
        if self._sleeping.value:
            try:
                self._wake.send(b"\1")
            except OSError:
                pass  # a wake-up is pending already, or the server is gone (seen in wait)
        self._posted = time.perf_counter()
        return seq

    def _spare_core(self):
        return spare_core(self.partner_threads - 1)

    def wait(self, seq, timeout):
        """The second half of request(): the reply to request `seq` as a memoryview."""
        start = self._posted
        rep_seq = self._rep_seq
        if rep_seq.value != seq:
            # Spin about as long as the server is still expected to take (what is left of its
            # recent round trip since the request was posted), then sleep on the word (the wait
            # policy: spin_budget). A driver that handled another server's reply meanwhile thus
            # waits for this one with a short spin, not a sleep. A turn that took long means this
            # process lost its core (a busy machine): then spinning only delays the server, so
            # sleep at once.
            now = time.perf_counter()
            spin_until = now + spin_budget(self._rtt - (now - start), self._spare_core)
            turns = 0
            while rep_seq.value != seq:
                before, now = now, time.perf_counter()
                if now >= spin_until or now - before > 200e-6:
                    break
                turns += 1
                if turns % 64 == 0:
                    os.sched_yield()  # let a server thread waiting for this core run
            if rep_seq.value != seq:
                self._sleep(seq, start + timeout)
        self._rtt = 0.8 * self._rtt + 0.2 * (time.perf_counter() - start)
        length = self._rep_len.value
        if length > self._rep_cap:
            raise ShmError(f"shared memory {self.path}: a reply beyond bounds")
        at = _HEADER + self._req_cap
        return self._view[at:at + length]

    def _sleep(self, seq, deadline):
        syscall = _syscall()
        ts = _Timespec()
        while True:
            self._waiting.value = 1
            with self._fence:
                pass
            seen = self._rep_seq.value
            if seen != seq:
                left = min(_SLICE, deadline - time.perf_counter())
                if left > 0:
                    ts.tv_sec = int(left)
                    ts.tv_nsec = int((left - int(left)) * 1e9)
                    syscall(ctypes.c_long(_SYS_FUTEX), self._rep_seq_addr,
                            ctypes.c_long(_FUTEX_WAIT), ctypes.c_long(seen), ctypes.byref(ts),
                            None, ctypes.c_long(0))
            self._waiting.value = 0
            if self._rep_seq.value == seq:
                return
            if self.server_gone():
                raise ShmError(f"shared memory {self.path}: the server closed the channel or died")
            if time.perf_counter() >= deadline:
                raise TimeoutError(f"shared memory {self.path}: no reply within the timeout")

    def close(self):
        """Tells the server this side is closed and unmaps the file."""
        if self._mm is not None and self._attached_here:
            # (A refused attach leaves the header alone: the channel is another client's.)
            self._client_closed.value = 1
            self._attached_here = False
        if getattr(self, "_view", None) is not None:
            self._view.release()
            self._view = None
        self._words = []
        for name in ("_attached", "_server_closed", "_client_closed", "_sleeping", "_waiting",
                     "_req_seq", "_req_len", "_rep_seq", "_rep_len"):
            if hasattr(self, name):
                delattr(self, name)
        if self._mm is not None:
            try:
                self._mm.close()
            except BufferError:
                pass  # a reply view is still held by the caller: the mapping goes with it
            self._mm = None
        if self._wake is not None:
            self._wake.close()
            self._wake = None
        if self._fd >= 0:
            os.close(self._fd)  # drops this side's lock
            self._fd = -1
