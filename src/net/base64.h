#pragma once
// Base64 (RFC 4648, with padding) for the step server's JSON sessions, where bytes cannot travel
// as they are: a field holding bytes, or one of the maps of bytes (vfs_assets; sensors, xpos,
// xquat with binary arrays), is renamed `<field>_base64` and carries base64 text instead
// (docs/protocol.md). Thread: any (pure).
#include <cstddef>
#include <string>

#include "net/msgpack_codec.h"

namespace urlab::net {

std::string Base64Encode(const void* data, std::size_t size);

// Rewrites every bytes value inside `v` as above (recursively); bytes inside an array become
// base64 strings in place.
void BinaryToBase64(Json& v);

}  // namespace urlab::net
