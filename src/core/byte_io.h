#pragma once
// Little binary writer and bounds-checked reader for our own file formats (internal): the
// convert layer's cache files and replay recordings. Values are written in host byte order
// (little-endian on every machine we build for). The reader treats its bytes as untrusted:
// every read is checked and throws urlab::Error("<what> ends early (needs N more bytes at byte
// P)") instead of reading past the end. Thread: plain values.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::internal {

class ByteWriter {
 public:
  template <typename T>
  void Put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void PutBytes(std::string_view s) { out_.append(s); }
  void PutString(std::string_view s) {
    Put(static_cast<std::uint32_t>(s.size()));
    out_.append(s);
  }
  void PutDoubles(const std::vector<double>& v) {
    if (!v.empty()) out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string what) : in_(bytes), what_(std::move(what)) {}
  template <typename T>
  T Get() {
    static_assert(std::is_trivially_copyable_v<T>);
    Need(sizeof(T));
    T v;
    std::memcpy(&v, in_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string_view GetBytes(std::uint64_t n) {
    Need(n);
    const std::string_view s = in_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  // A string written by PutString, refused when longer than `max`.
  std::string GetString(std::size_t max) {
    const auto n = Get<std::uint32_t>();
    if (n > max) throw Error(what_ + ": string too long");
    return std::string(GetBytes(n));
  }
  void GetDoubles(std::vector<double>* out, std::size_t n) {
    NeedItems(n, sizeof(double));
    out->resize(n);
    if (n) std::memcpy(out->data(), in_.data() + pos_, n * sizeof(double));
    pos_ += n * sizeof(double);
  }
  // Throws unless `count` items of `size` bytes each can still follow (no overflow).
  void NeedItems(std::uint64_t count, std::size_t size) const {
    if (count > remaining() / size) Fail(count * size);
  }
  std::size_t remaining() const { return in_.size() - pos_; }
  std::size_t position() const { return pos_; }
  bool done() const { return pos_ == in_.size(); }

 private:
  void Need(std::uint64_t n) const {
    if (n > remaining()) Fail(n);
  }
  [[noreturn]] void Fail(std::uint64_t n) const {
    throw Error(what_ + " ends early (needs " + std::to_string(n) + " more bytes at byte " +
                std::to_string(pos_) + ")");
  }
  std::string_view in_;
  std::size_t pos_ = 0;
  std::string what_;
};

}  // namespace urlab::internal
