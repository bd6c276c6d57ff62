#pragma once
// Batched environments (world::BatchSubsystem): the one validation of a batch step's arrays,
// for every front end that steps a batch (the step server's batch_step, the in-process batch of
// src/embed). Nothing is stepped when it throws.
//
// Thread: any (reads the batch's fixed sizes only).
#include <cstdint>
#include <span>
#include <vector>

#include "urlab/ops/error.h"
#include "urlab/world/batch_subsystem.h"

namespace urlab::ops {

// `actions` must hold envs x nu values (dim_mismatch), each finite (bad_value naming its
// environment and actuator) and within the actions' range (bad_value); `reset` none, or one flag
// per environment (dim_mismatch). Throws OpError.
void CheckBatchStep(const world::BatchSubsystem& batch, const std::vector<double>& actions,
                    std::span<const std::uint8_t> reset);

}  // namespace urlab::ops
