#pragma once
// Little binary writer/reader for the convert layer's cache files (internal). The reader treats
// its bytes as untrusted: every read is bounds-checked and throws urlab::Error("<what>:
// truncated") instead of reading past the end. Thread: plain values.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

#include "urlab/core/error.h"

namespace urlab::convert::internal {

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
  std::string_view GetBytes(std::size_t n) {
    Need(n);
    const std::string_view s = in_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string GetString(std::size_t max) {
    const auto n = Get<std::uint32_t>();
    if (n > max) throw Error(what_ + ": string too long");
    return std::string(GetBytes(n));
  }
  // Throws unless `count` items of `size` bytes each can still follow.
  void NeedItems(std::uint64_t count, std::size_t size) {
    if (count > (in_.size() - pos_) / size) throw Error(what_ + ": truncated");
  }
  std::size_t remaining() const { return in_.size() - pos_; }
  std::size_t position() const { return pos_; }

 private:
  void Need(std::size_t n) {
    if (n > in_.size() - pos_) throw Error(what_ + ": truncated");
  }
  std::string_view in_;
  std::size_t pos_ = 0;
  std::string what_;
};

}  // namespace urlab::convert::internal
