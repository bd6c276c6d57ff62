#include "net/base64.h"

#include <cstdint>
#include <string>
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

// Maps whose values are bytes (file contents; per-name vectors with binary arrays): the map
// itself is renamed, even when empty, so a key never depends on what a reply holds. Any other
// map is a structure (e.g. an articulation's observation) whose own fields are renamed.
bool IsBytesMap(const std::string& key, const Json& v) {
  static constexpr const char* kBytesMaps[] = {"vfs_assets", "sensors", "xpos", "xquat"};
  if (!v.is_object()) return false;
  bool named = false;
  for (const char* k : kBytesMaps) named = named || key == k;
  if (!named) return false;
  for (const auto& item : v) {
    if (!item.is_binary()) return false;  // (sensors as lists of numbers: not bytes)
  }
  return key == "vfs_assets" || !v.empty();
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
    if (value.is_binary() || IsBytesMap(key, value)) any = true;
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
    } else if (IsBytesMap(key, value)) {
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
