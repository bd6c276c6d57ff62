#include "urlab/core/error.h"

namespace urlab {

std::string SourceLocation::str() const {
  if (file.empty()) return line > 0 ? "line " + std::to_string(line) : std::string();
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

namespace {
std::string Compose(const SourceLocation& where, const std::string& message) {
  const std::string w = where.str();
  return w.empty() ? message : w + ": " + message;
}
}  // namespace

InputError::InputError(SourceLocation where, const std::string& message)
    : Error(Compose(where, message)), where_(std::move(where)), message_(message) {}

}  // namespace urlab
