#include "urlab/ops/batch.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "ops/value_ranges.h"

namespace urlab::ops {

void CheckBatchStep(const world::BatchSubsystem& batch, const std::vector<double>& actions,
                    std::span<const std::uint8_t> reset) {
  const std::size_t envs = static_cast<std::size_t>(batch.envs());
  const std::size_t expected = envs * static_cast<std::size_t>(batch.action_size());
  if (actions.size() != expected) {
    Fail("dim_mismatch", "actions hold " + std::to_string(actions.size()) + " values, expected " +
                             std::to_string(expected) + " (" + std::to_string(envs) +
                             " environments x " + std::to_string(batch.action_size()) +
                             " actuators)");
  }
  for (std::size_t i = 0; i < actions.size(); ++i) {
    if (!std::isfinite(actions[i])) {
      const std::size_t nu = static_cast<std::size_t>(std::max(1, batch.action_size()));
      Fail("bad_value", "actions: environment " + std::to_string(i / nu) + ", actuator " +
                            std::to_string(i % nu) + " is not a finite number");
    }
  }
  CheckRanges(actions, "actions");
  if (!reset.empty() && reset.size() != envs) {
    Fail("dim_mismatch", "reset holds " + std::to_string(reset.size()) +
                             " flags, expected one per environment (" + std::to_string(envs) + ")");
  }
}

}  // namespace urlab::ops
