#pragma once
// Batched-environment benchmark shared by bench/bench_batch and `urlab bench batch`: a Batch of N
// copies of a model stepped by K threads against a bare single-thread mj_step loop doing the same
// work (N episodes of the same length, one after another, from the same reset state with the
// same actions), in one process. Trials alternate bare and batch so both see the same machine.
// Thread: main (the batch starts and stops its own workers).
#include <functional>
#include <string>
#include <vector>

#include "urlab/physics/model.h"

namespace urlab::physics {

struct BatchBenchOptions {
  std::vector<int> envs = {1, 16, 64, 256};
  int threads = 2;
  int env_steps = 20000;  // environment steps per trial (each environment runs env_steps / N)
  int min_steps = 50;     // at least this many steps per environment
  int trials = 5;
  // Receives the report lines (one per trial and per N); empty: silent.
  std::function<void(const std::string&)> report;
};

struct BatchBenchPoint {
  int envs = 0;
  int steps = 0;           // per environment per trial
  double bare_rate = 0;    // best bare steps per second
  double batch_rate = 0;   // best aggregate environment steps per second
  double ratio = 0;        // batch_rate / bare_rate
  bool identical = false;  // the batch ended where the bare loop did, bit for bit
};

std::vector<BatchBenchPoint> RunBatchBench(const Model& model, const BatchBenchOptions& options);

}  // namespace urlab::physics
