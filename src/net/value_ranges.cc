#include "net/value_ranges.h"

#include "net/request_fields.h"

namespace urlab::net {

double RangedNumber(const Json& v, std::string_view field, std::string_view what) {
  const std::string name(what.empty() ? field : what);
  const double x = request::Number(v, name.c_str());
  CheckRange(x, field, name);
  return x;
}

}  // namespace urlab::net
