#pragma once
// Ranges of the numbers an operation takes: the mechanism. The table itself (which field takes
// which range) is data, in value_range_table.cc, and docs/network.md shows it. A value outside
// its range is refused as bad_value (ops::OpError) naming the field and the range, before
// anything of the request is applied; the step server, the topics, the viewer and the CLI all
// reach these checks through the operations.
//
// Thread: pure functions over a constant table; any thread.
#include <mujoco/mujoco.h>

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/commands.h"

namespace urlab::ops {

struct ValueRange {
  const char* field;  // the request field, or a name for a derived quantity ("quaternion norm")
  double min, max;
  bool min_open = false;  // min itself is refused (a range "(min, max]")
  bool integer = false;   // whole numbers only
};

// The table (value_range_table.cc).
std::span<const ValueRange> ValueRanges();
// The range of `field`; a field missing from the table is a programming error (std::logic_error).
const ValueRange& RangeOf(std::string_view field);
// "(0, 1]", "an integer in [1, 10000]".
std::string RangeText(const ValueRange& r);

// Fails with bad_value unless `x` lies in the range of `field` ("{what} must be ..., got x";
// `what` defaults to the field's name).
void CheckRange(double x, std::string_view field, std::string_view what = {});
// Every value of `values` within the range of `field`.
void CheckRanges(const std::vector<double>& values, std::string_view field,
                 std::string_view what = {});

// The quaternions of free and ball joints that `runs` (values written at qpos addresses) cover
// whole must have a norm within the range "quaternion norm" (a zero or garbage quaternion is
// refused; MuJoCo normalises the rest). `what` names the request field in the message.
void CheckQposQuaternions(const mjModel* m, const std::vector<physics::cmd::SetState::Run>& runs,
                          std::string_view what);

}  // namespace urlab::ops
