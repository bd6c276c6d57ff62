#pragma once
// Plots over time (F4): chosen joints' positions, sensor values and actuator forces, sampled
// from each new state frame the viewer draws and shown with MuJoCo's own figure renderer
// (mjr_figure) in the viewport's lower right. A reset or any jump back in time starts the
// plot again.
//
// Threading contract: main thread only.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "urlab/physics/state_frame.h"

namespace urlab::viewer::internal {

enum class SignalKind { kJoint, kSensor, kActuatorForce };

struct Signal {
  SignalKind kind = SignalKind::kJoint;
  int index = 0;  // qpos address (joint), sensordata address (sensor), actuator id
  std::string name;
};

class Plots {
 public:
  static constexpr int kMaxChosen = 8;
  static constexpr int kMaxPoints = mjMAXLINEPNT;

  Plots();
  ~Plots();
  // Lists what can be plotted: 1-dof joints, every sensor value, every actuator's force.
  void Configure(const mjModel* m);
  const std::vector<Signal>& available() const { return available_; }
  bool chosen(int signal) const;
  // Chooses a signal (at most kMaxChosen); false when the plot is full.
  bool Choose(int signal, bool on);
  int num_chosen() const { return static_cast<int>(lines_.size()); }
  // Adds the frame's values (once per frame; a jump back in time clears the lines).
  void Sample(const physics::StateFrame& frame);
  // Points held per chosen line (the same for all).
  int points() const { return points_; }
  // The newest value of chosen line `line`.
  double last(int line) const;
  void Clear();
  // Draws the figure into `viewport` (framebuffer pixels).
  void Draw(const mjrRect& viewport, const mjrContext* con);

 private:
  struct Line {
    int signal = 0;
    std::vector<float> t, v;  // ring of the last kMaxPoints samples, oldest first
  };
  std::vector<Signal> available_;
  std::vector<Line> lines_;
  std::unique_ptr<mjvFigure> figure_;
  std::uint64_t last_frame_ = 0;
  double last_time_ = -1;
  int points_ = 0;
};

}  // namespace urlab::viewer::internal
