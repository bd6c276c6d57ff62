#include "wire/request_limits.h"

namespace urlab::wire {

bool JsonDepthWithin(std::string_view text, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    switch (c) {
      case '"':
        in_string = true;
        break;
      case '[':
      case '{':
        if (++depth > max_depth) return false;
        break;
      case ']':
      case '}':
        if (depth > 0) --depth;  // unbalanced text is the parser's to refuse
        break;
      default:
        break;
    }
  }
  return true;
}

std::optional<Json> DecodeJsonRequest(std::string_view text, std::string* error,
                                      std::size_t max_depth) {
  if (!JsonDepthWithin(text, max_depth)) {
    *error = "nested more than " + std::to_string(max_depth) + " deep";
    return std::nullopt;
  }
  Json body = Json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (body.is_discarded()) {
    *error = "not valid JSON";
    return std::nullopt;
  }
  return body;
}

}  // namespace urlab::wire
