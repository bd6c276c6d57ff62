#pragma once
// `urlab bench cameras`: what the off-screen cameras cost on this machine, in one process.
// 1. Frames per second of one camera at width x height for RGB, RGB + depth and segmentation
//    (render and read-back, on a thread prepared like the camera subsystem's).
// 2. Latency from a state to the client: the camera subsystem streaming that camera at `rate`
//    through ZeroMQ to a subscriber in this process; per frame, receive time minus the time the
//    render thread took the state (at most one physics step after the physics thread published
//    it); p50 and p99.
// 3. The physics loop's rate with that camera rendering at `rate` beside it over the loop
//    without (world::RunLoopBench's attach/toggle: alternating trials on the same model).
// Thread: main (starts and stops its own threads).
#include <functional>
#include <string>

#include "urlab/world/scene_file.h"

namespace urlab::camera {

struct CameraBenchOptions {
  std::string camera;  // "articulation/camera"; "" : the first camera of an articulation
  int width = 640, height = 480;
  double fps_seconds = 2;      // per mode
  double latency_seconds = 3;  // streaming
  double rate = 30;            // streaming and the loop ratio
  int loop_steps = 20000, loop_trials = 5;
  std::function<void(const std::string&)> report;  // lines as they come; empty: silent
};

struct CameraBenchResult {
  std::string backend;
  double fps_rgb = 0, fps_rgb_depth = 0, fps_segmentation = 0;
  double latency_p50_ms = 0, latency_p99_ms = 0;
  int latency_samples = 0;
  double loop_ratio = 0;  // loop with the camera / loop without (best of the trials)
  double loop_median_ratio = 0;
};

// Throws InputError for a scene without a camera (or without the one named).
CameraBenchResult RunCameraBench(const world::SceneConfig& scene,
                                 const CameraBenchOptions& options);

}  // namespace urlab::camera
