#pragma once
// FrameGate: holds the physics thread at the moments the viewer must capture, so that a
// screenshot at --at T and every frame of --video show exactly the state due, however slow the
// renderer: the simulation waits for the frame, the picture is never late.
//
// - Video at F frames/s: frame k shows the state after n_k = floor(k / (F dt)) steps counted
//   from the step the video began at (dt the timestep): the state at k / F simulated seconds of
//   the recording. When dt > 1 / F one state stands for several frames (written again).
// - Screenshot at T: the first state whose simulation time reaches T (1 ns of slack).
//
// Threading contract
// - Physics thread: BeforeStep, from a pre-step callback (step mutex held): when the state it
//   is about to step from is due and not yet captured, it waits for the main thread, at most
//   kMaxWait per frame (then it logs once and stops waiting: a viewer that no longer draws must
//   not stall the simulation for good).
// - Main thread: Start*, the *Due queries, *Taken, Open. A main thread that waits for the
//   physics thread (Snapshot, WithLockedData) while a frame is due waits until kMaxWait passed.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace urlab::viewer::internal {

class FrameGate {
 public:
  static constexpr std::chrono::seconds kMaxWait{30};

  // Video frames from the state after `first_step` steps on, at `fps` with timestep `dt`.
  void StartVideo(std::uint64_t first_step, double dt, int fps);
  // A screenshot of the first state at time >= `t`.
  void StartShot(double t);

  // Physics thread: before stepping from the state after `step` steps at simulation `time`.
  void BeforeStep(std::uint64_t step, double time);

  // Main thread: how many video frames the state after `step` steps stands for (0: none due).
  // VideoWritten(step) once they are written releases the physics thread.
  int VideoFramesDue(std::uint64_t step) const;
  void VideoWritten(std::uint64_t step);
  // Main thread: the shot is due for a state at `time`; ShotTaken releases the physics thread.
  bool ShotDue(double time) const;
  void ShotTaken();
  // Releases the physics thread for good (the viewer ends).
  void Open();
  // Video frames written so far.
  std::uint64_t video_frames() const;

 private:
  std::uint64_t DueStep(std::uint64_t k) const;  // mutex held
  bool Waiting(std::uint64_t step, double time) const;

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool open_ = false;
  bool video_ = false;
  std::uint64_t first_step_ = 0;
  double steps_per_frame_ = 1;
  std::uint64_t next_frame_ = 0;  // the next video frame to write
  bool shot_ = false;
  double shot_at_ = 0;
  bool shot_taken_ = false;
};

}  // namespace urlab::viewer::internal
