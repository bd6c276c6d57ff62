#include "net/base64.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace urlab::net {

std::string Base64Encode(const void* data, std::size_t size) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= size; i += 3) {
    const std::uint32_t n = (p[i] << 16) | (p[i + 1] << 8) | p[i + 2];
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += kAlphabet[n & 63];
  }
  if (const std::size_t rest = size - i; rest > 0) {
    const std::uint32_t n = (p[i] << 16) | (rest == 2 ? p[i + 1] << 8 : 0);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += rest == 2 ? kAlphabet[(n >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

namespace {

Json Encoded(const Json& bytes) {
  const auto& b = bytes.get_binary();
  return Base64Encode(b.data(), b.size());
}

bool AllBinary(const Json& v) {
  if (!v.is_object() || v.empty()) return false;
  for (const auto& item : v) {
    if (!item.is_binary()) return false;
  }
  return true;
}

}  // namespace

void BinaryToBase64(Json& v) {
  if (v.is_array()) {
    for (Json& item : v) {
      if (item.is_binary()) {
        item = Encoded(item);
      } else {
        BinaryToBase64(item);
      }
    }
    return;
  }
  if (!v.is_object()) return;
  bool any = false;
  for (const auto& [key, value] : v.items()) {
    if (value.is_binary() || AllBinary(value)) any = true;
  }
  if (!any) {
    for (auto& item : v) BinaryToBase64(item);
    return;
  }
  // Rebuild the object so the renamed fields keep their places.
  Json out = Json::object();
  for (auto& [key, value] : v.items()) {
    if (value.is_binary()) {
      out[key + "_base64"] = Encoded(value);
    } else if (AllBinary(value)) {
      Json encoded = Json::object();
      for (auto& [name, bytes] : value.items()) encoded[name] = Encoded(bytes);
      out[key + "_base64"] = std::move(encoded);
    } else {
      BinaryToBase64(value);
      out[key] = std::move(value);
    }
  }
  v = std::move(out);
}

}  // namespace urlab::net
