#pragma once
// Polling wait for threaded tests: the condition is what is asserted, the timeout only bounds a
// failing test (never a measurement). The default bound is generous: a machine shared by other
// test runs and builds can starve a thread for seconds, and a passing test never waits it out.
#include <chrono>
#include <thread>

namespace urlab::testing {

// Waits (polling every millisecond) until `pred` holds or `timeout` passes; returns pred().
template <typename Pred>
bool WaitFor(Pred pred, std::chrono::milliseconds timeout = std::chrono::milliseconds(60000)) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!pred() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return pred();
}

}  // namespace urlab::testing
