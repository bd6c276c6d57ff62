#pragma once
// msgpack through Debian's msgpack-cxx: a request is decoded into a JSON tree (the step server's
// handlers read fields by name) under size and depth limits; replies and observations are
// encoded directly into a byte buffer, without building a tree first.
//
// Threading: none (each instance belongs to one thread).
#define MSGPACK_NO_BOOST 1
#include <cstddef>
#include <cstdint>
#include <msgpack.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "wire/request_limits.h"

namespace urlab::net {

using Json = nlohmann::ordered_json;

// Nesting deeper than this is refused: the step server's request limit (request_limits.h).
inline constexpr std::size_t kMaxMsgpackDepth = wire::kMaxRequestDepth;

// Decodes exactly one msgpack value from `data`. On failure returns nothing and says why in
// *error ("truncated", "trailing bytes", "map keys must be strings", ...). Map keys must be
// strings; ext values are refused; bin becomes a JSON binary value.
std::optional<Json> DecodeMsgpack(const void* data, std::size_t size, std::string* error);

class MsgpackWriter {
 public:
  MsgpackWriter() : packer_(buffer_) {}
  MsgpackWriter(const MsgpackWriter&) = delete;
  MsgpackWriter& operator=(const MsgpackWriter&) = delete;

  void Clear() { buffer_.clear(); }
  const char* data() const { return buffer_.data(); }
  std::size_t size() const { return buffer_.size(); }

  void Map(std::size_t entries) { packer_.pack_map(static_cast<std::uint32_t>(entries)); }
  void Array(std::size_t items) { packer_.pack_array(static_cast<std::uint32_t>(items)); }
  void Key(std::string_view k) { Str(k); }
  void Str(std::string_view s);
  // Always a float 64 (msgpack-cxx's pack_double writes whole numbers as integers, which would
  // change a value's type between two steps and lose the sign of -0.0).
  void Double(double v);
  void Int(std::int64_t v) { packer_.pack_int64(v); }
  void UInt(std::uint64_t v) { packer_.pack_uint64(v); }
  void Bool(bool v) { v ? packer_.pack_true() : packer_.pack_false(); }
  void Nil() { packer_.pack_nil(); }
  void Bin(const void* data, std::size_t size);
  // A numeric vector: an array of f64, or packed little-endian f64 bytes (bin) when `binary`.
  void Doubles(const double* v, std::size_t n, bool binary);
  // Any JSON value (numbers keep their kind: integers stay integers).
  void Value(const Json& v);

 private:
  msgpack::sbuffer buffer_;
  msgpack::packer<msgpack::sbuffer> packer_;
};

}  // namespace urlab::net
