#pragma once
// Rate limit for repeated log lines (MuJoCo warnings): the first line of a kind is logged, then
// at most one per period, carrying the count of those left out. A "kind" is the text with every
// run of digits replaced, so "... Time = 0.1230." and "... Time = 0.1240." are one kind.
// Thread: not synchronised; the owner locks.
#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace urlab::internal {

class WarningLimiter {
 public:
  using Clock = std::chrono::steady_clock;

  explicit WarningLimiter(Clock::duration period = std::chrono::seconds(1)) : period_(period) {}

  // True when `text` should be logged now; *skipped is then the number of lines of its kind left
  // out since the last one logged.
  bool Admit(std::string_view text, Clock::time_point now, std::uint64_t* skipped);

  // Kinds with lines left out since their last logged line: (an example text, count); resets
  // the counts.
  std::vector<std::pair<std::string, std::uint64_t>> TakeSkipped();

  // The kind of `text`: digits runs replaced by '#'.
  static std::string KindOf(std::string_view text);

 private:
  struct Entry {
    Clock::time_point last{};
    std::uint64_t skipped = 0;
    std::string example;
  };
  Clock::duration period_;
  std::unordered_map<std::string, Entry> kinds_;
};

}  // namespace urlab::internal
