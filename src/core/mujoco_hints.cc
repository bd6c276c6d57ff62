#include "urlab/core/mujoco_hints.h"

namespace urlab {

namespace {

struct HintRow {
  const char* fragment;  // found anywhere in MuJoCo's message
  const char* hint;
};

// MuJoCo 2.2.2's messages (mju_error / mju_warning texts) and what to change.
constexpr HintRow kHints[] = {
    {"Stack overflow",
     "the mjData stack is too small for this model: raise it with `size: {nstack: N}` in the "
     "scene or <size nstack=\"N\"/> in the MJCF (e.g. double what it is now)"},
    {"could not create mjData",
     "MuJoCo could not allocate the model's memory: lower size.nstack, njmax or nconmax (in a "
     "scene they add up over the articulations)"},
    {"Could not allocate mjData stack",
     "size.nstack (or njmax/nconmax) asks for more memory than the machine gives: lower it"},
    {"contact buffer is full",
     "more contacts than memory was reserved for: raise `size: {nconmax: N}` in the scene or "
     "<size nconmax=\"N\"/> in the MJCF"},
    {"constraint buffer is full",
     "more constraints than memory was reserved for: raise `size: {njmax: N}` in the scene or "
     "<size njmax=\"N\"/> in the MJCF"},
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
