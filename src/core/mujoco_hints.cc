#include "urlab/core/mujoco_hints.h"

namespace urlab {

namespace {

struct HintRow {
  const char* fragment;  // found anywhere in MuJoCo's message
  const char* hint;
};

// MuJoCo's messages (mju_error / mju_warning texts) and what to change.
constexpr HintRow kHints[] = {
    {"stack overflow",
     "the model's memory (mjData's arena and stack) is too small: raise it with `size: {memory: "
     "64M}` in the scene or <size memory=\"64M\"/> in the MJCF (e.g. double what it is now)"},
    {"nsufficient arena memory",
     "more contacts and constraints than the model's memory holds: raise `size: {memory: 64M}` "
     "in the scene or <size memory=\"64M\"/> in the MJCF"},
    {"could not allocate",
     "MuJoCo could not allocate the model's memory: lower size.memory (in a scene it is the "
     "largest articulation's)"},
    {"Nan, Inf or huge value",
     "the simulation diverged: try a smaller timestep, check masses, inertias and controller "
     "gains, or run with --reset-on-divergence"},
    {"BADCTRL", "a control value is NaN or huge: check the controller gains and the targets sent"},
};

}  // namespace

std::string MujocoHint(std::string_view message) {
  for (const HintRow& row : kHints) {
    if (message.find(row.fragment) != std::string_view::npos) return row.hint;
  }
  return {};
}

}  // namespace urlab
