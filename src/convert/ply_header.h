#pragma once
// The header of a PLY file, read before assimp sees the file: every element count it declares is
// checked against the bytes the file holds, so a hostile or damaged header ("element vertex
// 1000000000" in a 1 KiB file) is an InputError at its line instead of a gigabyte allocation
// and std::bad_alloc. (Internal.) Thread: any.
#include <cstdint>
#include <string>
#include <string_view>

namespace urlab::convert::internal {

// Throws InputError naming `path` and the header line when the header is malformed (no
// "end_header" in the first 64 KiB, an unknown format or property type, a count that is not a
// whole number) or when the elements it declares need more bytes than follow the header (each
// binary element at least its fixed-size properties and list counts, each ASCII value at least
// two characters). `bytes`: the file's first bytes (at least the header); `file_size`: its size.
void CheckPlyHeader(std::string_view bytes, std::uint64_t file_size, const std::string& path);

// Bytes of a PLY file CheckPlyHeader needs to see (the header's upper bound).
inline constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

}  // namespace urlab::convert::internal
