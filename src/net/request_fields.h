#pragma once
// Reading the fields of a step-server request (a JSON tree decoded from msgpack or JSON text):
// each reader refuses a missing or mistyped field with the protocol's error code, as a Failure
// that the server turns into an error reply. Thread: any (pure).
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "net/msgpack_codec.h"
#include "urlab/ops/error.h"

namespace urlab::net::request {

// A request refused with a protocol error code: the operations' own error (urlab/ops/error.h), so
// a field this file refuses and a value an operation refuses reach the client alike.
using Failure = ops::OpError;
using ops::Fail;

inline const Json& Require(const Json& body, const char* field) {
  const auto it = body.find(field);
  if (it == body.end()) Fail("missing_field", std::string("'") + field + "' is required");
  return *it;
}

inline double Number(const Json& v, const char* field) {
  if (!v.is_number()) Fail("bad_value", std::string("'") + field + "' must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) Fail("bad_value", std::string("'") + field + "' must be finite");
  return x;
}

inline std::vector<double> Numbers(const Json& v, const char* field) {
  if (!v.is_array()) Fail("bad_value", std::string("'") + field + "' must be an array");
  std::vector<double> out;
  out.reserve(v.size());
  for (const Json& x : v) out.push_back(Number(x, field));
  return out;
}

// A number as sent, for an operation that checks its range (ops/value_ranges.h: NaN and
// infinities are outside every range, and the operation's message names the field in place).
inline double AnyNumber(const Json& v, const std::string& field) {
  if (!v.is_number()) Fail("bad_value", "'" + field + "' must be a number");
  return v.get<double>();
}
inline std::vector<double> AnyNumbers(const Json& v, const char* field) {
  if (!v.is_array()) Fail("bad_value", std::string("'") + field + "' must be an array");
  std::vector<double> out;
  out.reserve(v.size());
  for (const Json& x : v) out.push_back(AnyNumber(x, field));
  return out;
}

inline bool Bool(const Json& v, const char* field) {
  if (!v.is_boolean()) Fail("bad_value", std::string("'") + field + "' must be true or false");
  return v.get<bool>();
}

inline std::string String(const Json& v, const char* field) {
  if (!v.is_string()) Fail("bad_value", std::string("'") + field + "' must be a string");
  return v.get<std::string>();
}

// The camera operations' map of camera name to value: the request's `cameras` map, or (the 2026
// form) the request's own keys other than the envelope's. `what` names the values in the error.
inline std::vector<std::pair<std::string, const Json*>> CameraEntries(const Json& body,
                                                                      const std::string& what) {
  std::vector<std::pair<std::string, const Json*>> out;
  if (const auto it = body.find("cameras"); it != body.end()) {
    if (!it->is_object()) Fail("bad_value", "cameras must be a map of camera to " + what);
    for (const auto& [name, value] : it->items()) out.emplace_back(name, &value);
    return out;
  }
  for (const auto& [name, value] : body.items()) {
    if (name == "op" || name == "seq" || name == "session_id" || name == "force") continue;
    out.emplace_back(name, &value);
  }
  return out;
}

}  // namespace urlab::net::request
