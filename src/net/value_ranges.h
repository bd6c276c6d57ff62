#pragma once
// Ranges of the numbers clients send to the step server: the table and its checks belong to the
// operations (ops/value_ranges.h, one validation for every path); here only the reading of a
// request field within its range. A value outside its range is refused as bad_value naming the
// field and the range, before anything of the request is applied.
//
// Thread: pure functions over a constant table; any thread.
#include <string_view>

#include "net/msgpack_codec.h"
#include "ops/value_ranges.h"

namespace urlab::net {

using ops::CheckQposQuaternions;
using ops::CheckRange;
using ops::CheckRanges;
using ops::RangeOf;
using ops::RangeText;
using ops::ValueRange;
using ops::ValueRanges;

// A finite number (request::Number) within the range of `field`.
double RangedNumber(const Json& v, std::string_view field, std::string_view what = {});

}  // namespace urlab::net
