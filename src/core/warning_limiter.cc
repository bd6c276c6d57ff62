#include "core/warning_limiter.h"

#include <cctype>

namespace urlab::internal {

std::string WarningLimiter::KindOf(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  bool in_digits = false;
  for (char c : text) {
    const bool digit = std::isdigit(static_cast<unsigned char>(c)) != 0;
    if (digit && !in_digits) out += '#';
    if (!digit) out += c;
    in_digits = digit;
  }
  return out;
}

bool WarningLimiter::Admit(std::string_view text, Clock::time_point now, std::uint64_t* skipped) {
  auto [it, fresh] = kinds_.try_emplace(KindOf(text));
  Entry& e = it->second;
  if (!fresh && now - e.last < period_) {
    ++e.skipped;
    e.example = std::string(text);
    return false;
  }
  *skipped = e.skipped;
  e.skipped = 0;
  e.last = now;
  return true;
}

std::vector<std::pair<std::string, std::uint64_t>> WarningLimiter::TakeSkipped() {
  std::vector<std::pair<std::string, std::uint64_t>> out;
  for (auto& [kind, e] : kinds_) {
    if (e.skipped == 0) continue;
    out.emplace_back(e.example, e.skipped);
    e.skipped = 0;
  }
  return out;
}

}  // namespace urlab::internal
