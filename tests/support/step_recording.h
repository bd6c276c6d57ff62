#pragma once
// Recordings for tests, made without the wall clock: the engine's thread is not running and the
// test steps it on its own thread (PhysicsEngine::StepSync), so a recording holds exactly the
// steps asked for, and the chunks fall where the steps say, however loaded the machine.
// Header-only: for the test executables that link urlab_replay.
//
// Threading contract: test thread only (the recorder's writer thread is the recorder's own).
#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "support/wait.h"
#include "urlab/physics/engine.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"

namespace urlab::testing {

// A recorder on an engine the test steps. Construct it before adding the callbacks that should
// run after the recorder's (as a subsystem's begin-play would), then Start, Step, Finish.
class StepRecording {
 public:
  explicit StepRecording(physics::PhysicsEngine& engine,
                         replay::RecorderSource source = {{"arm"}, "", ""},
                         std::size_t ring_frames = 1 << 14)
      : engine_(engine), recorder_(engine, std::move(source), ring_frames) {}

  // Starts recording to options.path (the next step captures the start keyframe).
  void Start(replay::RecorderOptions options) {
    path_ = options.path;
    recorder_.Start(std::move(options));
  }
  // Runs `steps` steps, then waits (bounded) until the writer has taken every one of them, so
  // that the keyframes it asks for land on the next steps, as they would in a paced run.
  void Step(int steps) {
    engine_.StepSync(steps);
    stepped_ += static_cast<std::uint64_t>(steps);
    EXPECT_TRUE(WaitFor([&] { return recorder_.status().frames >= stepped_; }))
        << "the recorder's writer took " << recorder_.status().frames << " of " << stepped_
        << " steps";
  }
  // Finishes the file; returns its path.
  std::string Finish() {
    recorder_.Stop();
    return path_;
  }
  replay::Recorder& recorder() { return recorder_; }

 private:
  physics::PhysicsEngine& engine_;
  replay::Recorder recorder_;
  std::string path_;
  std::uint64_t stepped_ = 0;
};

// Records `steps` steps of `engine` into options.path; returns the path.
inline std::string RecordSteps(physics::PhysicsEngine& engine, replay::RecorderOptions options,
                               int steps, replay::RecorderSource source = {{"arm"}, "", ""}) {
  StepRecording recording(engine, std::move(source));
  recording.Start(std::move(options));
  recording.Step(steps);
  return recording.Finish();
}

// The frames of a chunk's records, in order (its keyframes, markers and gaps left out).
inline std::vector<replay::Frame> FramesOf(const std::vector<replay::Record>& records) {
  std::vector<replay::Frame> frames;
  for (const replay::Record& r : records) {
    if (const auto* f = std::get_if<replay::Frame>(&r)) frames.push_back(*f);
  }
  return frames;
}

}  // namespace urlab::testing
