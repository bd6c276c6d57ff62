// Every command kind declared once: its name, its validation (at submission, on the caller's
// thread) and its application (inside StepCore::Advance), side by side. A new command is a struct
// in commands.h, an alternative of the Command variant and one Kind<> entry here; the compiler
// refuses a Command alternative without an entry.
#include <cmath>
#include <string>
#include <type_traits>
#include <variant>

#include "urlab/core/error.h"
#include "urlab/physics/step_core.h"

namespace urlab::physics {

// What applying a command may touch of the core besides mjModel/mjData.
struct CommandAccess {
  StepCore& core;
  mjModel* m;
  mjData* d;
  double before;  // simulation time before the command

  void Event(EngineEventKind kind, std::string message) {
    core.in_divergence_ = false;
    core.Emit({kind, before, std::move(message)});
  }
  void AddOneShot(const cmd::ApplyForce& f) { core.one_shot_.push_back(f); }
  void DropOneShots() { core.one_shot_.clear(); }
  void SetPaused(bool paused) { core.SetPaused(paused); }
  void OptionsChanged() { core.timestep_.store(m->opt.timestep, std::memory_order_relaxed); }
  void ModelReplaced() {
    OptionsChanged();
    core.model_generation_.fetch_add(1, std::memory_order_release);
  }
};

namespace {

bool AllFinite(const mjtNum* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}
void CheckRange(const char* what, int adr, std::size_t n, int size) {
  if (adr < 0 || n == 0 || static_cast<std::size_t>(adr) + n > static_cast<std::size_t>(size)) {
    throw Error(std::string(what) + ": " + std::to_string(n) + " value(s) at address " +
                std::to_string(adr) + " do not fit the model's " + std::to_string(size));
  }
}
void CheckFinite(const char* what, const mjtNum* v, std::size_t n) {
  if (!AllFinite(v, n)) throw Error(std::string(what) + ": non-finite value");
}
void CheckFunction(const char* what, bool set) {
  if (!set) throw Error(std::string(what) + ": empty function");
}

// Kind<T>: kName, Validate(const T&, const mjModel*) and Apply(T&, CommandAccess&), which
// returns the Discontinuity flags the command caused.
template <typename T>
struct Kind;

template <>
struct Kind<cmd::Reset> {
  static constexpr const char* kName = "reset";
  static void Validate(const cmd::Reset&, const mjModel*) {}
  static std::uint32_t Apply(cmd::Reset&, CommandAccess& a) {
    mj_resetData(a.m, a.d);
    mj_forward(a.m, a.d);
    a.Event(EngineEventKind::kReset, "reset");
    return kDiscontinuityReset;
  }
};

template <>
struct Kind<cmd::ResetKeyframe> {
  static constexpr const char* kName = "reset_keyframe";
  static void Validate(const cmd::ResetKeyframe& c, const mjModel* m) {
    if (c.key < 0 || c.key >= m->nkey) {
      throw Error("ResetToKeyframe: keyframe id " + std::to_string(c.key) +
                  " out of range (model has " + std::to_string(m->nkey) + ")");
    }
  }
  static std::uint32_t Apply(cmd::ResetKeyframe& c, CommandAccess& a) {
    mj_resetDataKeyframe(a.m, a.d, c.key);
    mj_forward(a.m, a.d);
    std::string msg = "reset to keyframe " + std::to_string(c.key);
    if (const char* name = mj_id2name(a.m, mjOBJ_KEY, c.key); name && name[0]) {
      msg += " '" + std::string(name) + "'";
    }
    a.Event(EngineEventKind::kReset, std::move(msg));
    return kDiscontinuityReset;
  }
};

template <>
struct Kind<cmd::ResetCustom> {
  static constexpr const char* kName = "reset_custom";
  static void Validate(const cmd::ResetCustom& c, const mjModel*) {
    if (!c.fn) throw Error("ResetWith: empty reset function");
  }
  static std::uint32_t Apply(cmd::ResetCustom& c, CommandAccess& a) {
    c.fn(a.m, a.d);
    mj_forward(a.m, a.d);
    a.Event(EngineEventKind::kReset, c.label.empty() ? "custom reset" : c.label);
    return kDiscontinuityReset;
  }
};

template <>
struct Kind<cmd::Restore> {
  static constexpr const char* kName = "restore";
  static void Validate(const cmd::Restore& c, const mjModel* m) {
    const StateLayout expected = StateLayout::Of(m);
    if (!(c.state.layout == expected)) {
      throw StateError("Restore: state has " + c.state.layout.str() + ", model has " +
                       expected.str());
    }
    if (!c.state.IsConsistent())
      throw StateError("Restore: state arrays do not match their layout");
  }
  static std::uint32_t Apply(cmd::Restore& c, CommandAccess& a) {
    RestoreState(a.m, a.d, c.state);
    a.Event(EngineEventKind::kRestored, "restored state at t=" + std::to_string(c.state.time));
    return kDiscontinuityRestore;
  }
};

template <>
struct Kind<cmd::SetQpos> {
  static constexpr const char* kName = "set_qpos";
  static void Validate(const cmd::SetQpos& c, const mjModel* m) {
    CheckRange("SetQpos", c.adr, c.values.size(), m->nq);
    CheckFinite("SetQpos", c.values.data(), c.values.size());
  }
  static std::uint32_t Apply(cmd::SetQpos& c, CommandAccess& a) {
    std::copy(c.values.begin(), c.values.end(), a.d->qpos + c.adr);
    mj_forward(a.m, a.d);
    return kDiscontinuitySetState;
  }
};

template <>
struct Kind<cmd::SetQvel> {
  static constexpr const char* kName = "set_qvel";
  static void Validate(const cmd::SetQvel& c, const mjModel* m) {
    CheckRange("SetQvel", c.adr, c.values.size(), m->nv);
    CheckFinite("SetQvel", c.values.data(), c.values.size());
  }
  static std::uint32_t Apply(cmd::SetQvel& c, CommandAccess& a) {
    std::copy(c.values.begin(), c.values.end(), a.d->qvel + c.adr);
    mj_forward(a.m, a.d);
    return kDiscontinuitySetState;
  }
};

template <>
struct Kind<cmd::SetMocap> {
  static constexpr const char* kName = "set_mocap";
  static void Validate(const cmd::SetMocap& c, const mjModel* m) {
    CheckRange("SetMocap", c.mocap_id, 1, m->nmocap);
    CheckFinite("SetMocap", c.pos.data(), 3);
    CheckFinite("SetMocap", c.quat.data(), 4);
    if (mju_norm(c.quat.data(), 4) < 1e-12) throw Error("SetMocap: zero quaternion");
  }
  static std::uint32_t Apply(cmd::SetMocap& c, CommandAccess& a) {
    mju_copy3(a.d->mocap_pos + 3 * c.mocap_id, c.pos.data());
    mju_copy4(a.d->mocap_quat + 4 * c.mocap_id, c.quat.data());
    mju_normalize4(a.d->mocap_quat + 4 * c.mocap_id);
    return kNoDiscontinuity;
  }
};

template <>
struct Kind<cmd::ApplyForce> {
  static constexpr const char* kName = "apply_force";
  static void Validate(const cmd::ApplyForce& c, const mjModel* m) {
    CheckRange("ApplyForce", c.body, 1, m->nbody);
    if (c.steps < 1) throw Error("ApplyForce: steps must be at least 1");
    CheckFinite("ApplyForce", c.force.data(), 3);
    CheckFinite("ApplyForce", c.torque.data(), 3);
  }
  static std::uint32_t Apply(cmd::ApplyForce& c, CommandAccess& a) {
    a.AddOneShot(c);  // added right before the next step, removed after it
    return kNoDiscontinuity;
  }
};

template <>
struct Kind<cmd::SetOptions> {
  static constexpr const char* kName = "set_options";
  static void Validate(const cmd::SetOptions& c, const mjModel*) {
    CheckFunction("SetOptions", static_cast<bool>(c.fn));
  }
  static std::uint32_t Apply(cmd::SetOptions& c, CommandAccess& a) {
    const mjOption saved = a.m->opt;
    c.fn(a.m->opt);
    if (!(a.m->opt.timestep > 0) || !std::isfinite(a.m->opt.timestep)) {
      a.m->opt = saved;
      throw Error("SetOptions: timestep must be a positive finite number");
    }
    a.OptionsChanged();
    return kDiscontinuityOptions;
  }
};

template <>
struct Kind<cmd::SetPaused> {
  static constexpr const char* kName = "set_paused";
  static void Validate(const cmd::SetPaused&, const mjModel*) {}
  static std::uint32_t Apply(cmd::SetPaused& c, CommandAccess& a) {
    a.SetPaused(c.paused);
    return kNoDiscontinuity;
  }
};

template <>
struct Kind<cmd::Step> {
  static constexpr const char* kName = "step";
  static void Validate(const cmd::Step& c, const mjModel*) {
    if (c.n < 1 || c.n > 10'000'000) {
      throw Error("Step: n must be 1..10000000 (got " + std::to_string(c.n) + ")");
    }
  }
  // A step command opens a window of iterations (StepCore::ApplyPendingCommands); it is never
  // applied as a single change.
  static std::uint32_t Apply(cmd::Step&, CommandAccess&) { return kNoDiscontinuity; }
};

template <>
struct Kind<cmd::Forward> {
  static constexpr const char* kName = "forward";
  static void Validate(const cmd::Forward&, const mjModel*) {}
  static std::uint32_t Apply(cmd::Forward&, CommandAccess& a) {
    mj_forward(a.m, a.d);
    return kNoDiscontinuity;
  }
};

template <>
struct Kind<cmd::SetState> {
  static constexpr const char* kName = "set_state";
  static void Validate(const cmd::SetState& c, const mjModel* m) {
    const auto runs = [&](const char* what, const auto& rs, int size) {
      for (const auto& run : rs) {
        CheckRange(what, run.adr, run.values.size(), size);
        CheckFinite(what, run.values.data(), run.values.size());
      }
    };
    runs("SetState qpos", c.qpos, m->nq);
    runs("SetState qvel", c.qvel, m->nv);
    runs("SetState ctrl", c.ctrl, m->nu);
    if (c.time && !std::isfinite(*c.time)) throw Error("SetState: non-finite time");
  }
  static std::uint32_t Apply(cmd::SetState& c, CommandAccess& a) {
    for (const auto& run : c.qpos)
      std::copy(run.values.begin(), run.values.end(), a.d->qpos + run.adr);
    for (const auto& run : c.qvel)
      std::copy(run.values.begin(), run.values.end(), a.d->qvel + run.adr);
    for (const auto& run : c.ctrl)
      std::copy(run.values.begin(), run.values.end(), a.d->ctrl + run.adr);
    if (c.time) a.d->time = *c.time;
    mj_forward(a.m, a.d);
    return kDiscontinuitySetState;
  }
};

template <>
struct Kind<cmd::Inspect> {
  static constexpr const char* kName = "inspect";
  static void Validate(const cmd::Inspect& c, const mjModel*) {
    CheckFunction("Inspect", static_cast<bool>(c.fn));
  }
  static std::uint32_t Apply(cmd::Inspect& c, CommandAccess& a) {
    c.fn(a.m, a.d);
    return kNoDiscontinuity;
  }
};

template <>
struct Kind<cmd::ReplaceModel> {
  static constexpr const char* kName = "replace_model";
  static void Validate(const cmd::ReplaceModel& c, const mjModel* m) {
    if (!c.model || !*c.model) throw Error("ReplaceModel: no model");
    const std::string difference = InPlaceDifference(m, c.model->get());
    if (!difference.empty()) {
      throw Error("ReplaceModel: the new model differs in structure (" + difference + ")");
    }
  }
  static std::uint32_t Apply(cmd::ReplaceModel& c, CommandAccess& a) {
    const mjOption in_effect = a.m->opt;
    CopyModelValuesInPlace(a.m, c.model->get());
    if (c.keep_options) a.m->opt = in_effect;
    mj_forward(a.m, a.d);  // positions, inertias, sensors: from the new values, same state
    a.ModelReplaced();
    return kDiscontinuityOptions;  // the options may have changed with the rest
  }
};

}  // namespace

const char* CommandName(const Command& c) {
  return std::visit([](const auto& x) { return Kind<std::decay_t<decltype(x)>>::kName; }, c);
}

void ValidateCommand(const Command& c, const mjModel* m) {
  std::visit([m](const auto& x) { Kind<std::decay_t<decltype(x)>>::Validate(x, m); }, c);
}

std::uint32_t ApplyCommand(Command& c, StepCore& core) {
  CommandAccess a{core, core.mutable_model(), core.data(), core.data()->time};
  const std::uint32_t what =
      std::visit([&a](auto& x) { return Kind<std::decay_t<decltype(x)>>::Apply(x, a); }, c);
  // A reset or restore also cancels forces still waiting for their step.
  if (what & (kDiscontinuityReset | kDiscontinuityRestore)) a.DropOneShots();
  return what;
}

}  // namespace urlab::physics
