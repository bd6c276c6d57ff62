#include "net/msgpack_codec.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace urlab::net {

namespace {

struct Refused {
  const char* why;
};

Json ToJson(const msgpack::object& o) {
  switch (o.type) {
    case msgpack::type::NIL:
      return Json();
    case msgpack::type::BOOLEAN:
      return Json(o.via.boolean);
    case msgpack::type::POSITIVE_INTEGER:
      return Json(o.via.u64);
    case msgpack::type::NEGATIVE_INTEGER:
      return Json(o.via.i64);
    case msgpack::type::FLOAT32:
    case msgpack::type::FLOAT64:
      return Json(o.via.f64);
    case msgpack::type::STR:
      return Json(std::string(o.via.str.ptr, o.via.str.size));
    case msgpack::type::BIN: {
      const auto* p = reinterpret_cast<const std::uint8_t*>(o.via.bin.ptr);
      return Json::binary(std::vector<std::uint8_t>(p, p + o.via.bin.size));
    }
    case msgpack::type::ARRAY: {
      Json a = Json::array();
      for (std::uint32_t i = 0; i < o.via.array.size; ++i) a.push_back(ToJson(o.via.array.ptr[i]));
      return a;
    }
    case msgpack::type::MAP: {
      Json m = Json::object();
      for (std::uint32_t i = 0; i < o.via.map.size; ++i) {
        const msgpack::object_kv& kv = o.via.map.ptr[i];
        if (kv.key.type != msgpack::type::STR) throw Refused{"map keys must be strings"};
        // A repeated key keeps its last value, as JSON parsers do.
        m[std::string(kv.key.via.str.ptr, kv.key.via.str.size)] = ToJson(kv.val);
      }
      return m;
    }
    default:
      throw Refused{"ext values are not used by this protocol"};
  }
}

}  // namespace

std::optional<Json> DecodeMsgpack(const void* data, std::size_t size, std::string* error) {
  // Each element takes at least one byte, so no count can honestly exceed the size: the limits
  // stop a header that claims millions of items from allocating before the bytes run out.
  const std::size_t n = std::max<std::size_t>(size, 1);
  const msgpack::unpack_limit limit(n, n, n, n, n, kMaxMsgpackDepth);
  std::size_t offset = 0;
  try {
    msgpack::object_handle h =
        msgpack::unpack(static_cast<const char*>(data), size, offset, nullptr, nullptr, limit);
    if (offset != size) {
      *error = "trailing bytes after the message";
      return std::nullopt;
    }
    return ToJson(h.get());
  } catch (const Refused& r) {
    *error = r.why;
  } catch (const msgpack::insufficient_bytes&) {
    *error = "truncated";
  } catch (const msgpack::depth_size_overflow&) {
    *error = "nested too deeply";
  } catch (const msgpack::size_overflow&) {
    *error = "a count is larger than the message";
  } catch (const std::exception& e) {
    *error = e.what();
  }
  return std::nullopt;
}

void MsgpackWriter::Double(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  char b[9];
  b[0] = static_cast<char>(0xcb);
  for (int i = 0; i < 8; ++i) b[1 + i] = static_cast<char>(bits >> (56 - 8 * i));  // big-endian
  buffer_.write(b, sizeof(b));
}

void MsgpackWriter::Str(std::string_view s) {
  packer_.pack_str(static_cast<std::uint32_t>(s.size()));
  packer_.pack_str_body(s.data(), static_cast<std::uint32_t>(s.size()));
}

void MsgpackWriter::Bin(const void* data, std::size_t size) {
  packer_.pack_bin(static_cast<std::uint32_t>(size));
  packer_.pack_bin_body(static_cast<const char*>(data), static_cast<std::uint32_t>(size));
}

void MsgpackWriter::Doubles(const double* v, std::size_t n, bool binary) {
  if (binary) {
    Bin(v, n * sizeof(double));  // little-endian f64 (x86-64, arm64)
    return;
  }
  Array(n);
  for (std::size_t i = 0; i < n; ++i) Double(v[i]);
}

void MsgpackWriter::Value(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null:
    case Json::value_t::discarded:
      return Nil();
    case Json::value_t::boolean:
      return Bool(v.get<bool>());
    case Json::value_t::number_integer:
      return Int(v.get<std::int64_t>());
    case Json::value_t::number_unsigned:
      return UInt(v.get<std::uint64_t>());
    case Json::value_t::number_float:
      return Double(v.get<double>());
    case Json::value_t::string:
      return Str(v.get_ref<const std::string&>());
    case Json::value_t::binary: {
      const auto& b = v.get_binary();
      return Bin(b.data(), b.size());
    }
    case Json::value_t::array:
      Array(v.size());
      for (const Json& x : v) Value(x);
      return;
    case Json::value_t::object:
      Map(v.size());
      for (const auto& [k, x] : v.items()) {
        Key(k);
        Value(x);
      }
      return;
  }
}

}  // namespace urlab::net
