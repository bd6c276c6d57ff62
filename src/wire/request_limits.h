#pragma once
// Limits on what the step server decodes from a client, shared by the decoders and by their
// fuzz targets (fuzz/step_request_fuzz.cc reports kMaxRequestBytes as its largest input, so a
// fuzzing run reaches the limits and everything below them).
//
// Thread: constants and pure functions; any thread.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace urlab::wire {

using Json = nlohmann::ordered_json;

// A request larger than this is refused (bad_request) before it is decoded.
inline constexpr std::size_t kMaxRequestBytes = std::size_t{1} << 20;
// Nesting deeper than this is refused, in msgpack and in JSON text alike (a request is a map of
// maps of arrays at most; `seq` is echoed, so its depth must be bounded too).
inline constexpr std::size_t kMaxRequestDepth = 32;

// True when the JSON text `text` nests arrays and objects at most `max_depth` deep. A lexical
// scan (brackets outside strings), no allocation and no recursion, so it is safe on any input;
// text that is not JSON at all is left for the parser to refuse.
bool JsonDepthWithin(std::string_view text, std::size_t max_depth);

// Decodes one JSON text (an object or anything else; the caller checks the type) under the depth
// limit. On failure returns nothing and says why in *error ("not valid JSON", "nested more than
// 32 deep").
std::optional<Json> DecodeJsonRequest(std::string_view text, std::string* error,
                                      std::size_t max_depth = kMaxRequestDepth);

}  // namespace urlab::wire
