#pragma once
// SceneView: what the viewer draws from: its own copy of the compiled model, its own mjData
// filled from state frames (never the physics thread's), and MuJoCo's abstract scene, camera,
// visual options, perturbation and GPU context.
//
// Threading contract: main thread only (the thread whose GL context is current).
#include <mujoco/mujoco.h>

#include "urlab/physics/model.h"
#include "urlab/physics/state_frame.h"

namespace urlab::viewer::internal {

class SceneView {
 public:
  // Copies `source` (call while the physics thread does not run: its options may change there).
  // `maxgeom` bounds the scene's geoms (the model's and the debug drawing's).
  SceneView(const mjModel* source, int maxgeom);
  ~SceneView();
  SceneView(const SceneView&) = delete;
  SceneView& operator=(const SceneView&) = delete;

  // Uploads the model to the GPU; a GL context must be current. `shadow_size` (0: the model's)
  // and an offscreen buffer of at least `off_w` x `off_h` pixels (for a render scale) are set
  // in the viewer's copy first. Called again, it makes a new context.
  void MakeContext(int shadow_size = 0, int off_w = 0, int off_h = 0);
  // Takes the values of `source` (the running model after a ReplaceModel command: the same
  // structure) into the viewer's copy, keeping the viewer's own visual settings, and uploads its
  // textures, meshes and heightfields again when a context was made. `source` is not the
  // engine's live model (a copy taken on the physics thread).
  void ReplaceModelValues(const mjModel* source);
  // Copies the frame's state (time, qpos, qvel, act, ctrl, mocap poses, applied forces) into the
  // viewer's mjData and recomputes positions (kinematics, camera and light poses, tendons).
  void Update(const physics::StateFrame& frame);
  // mjv_updateScene from the viewer's data.
  void UpdateScene();
  // Draws the scene into `viewport` of the window's back buffer (framebuffer pixels, bottom-left
  // origin). With `scale` != 1 it is drawn at scale times the resolution offscreen and scaled
  // into the viewport. `sky`: a gradient where nothing was drawn (render_quality.h).
  void Render(const mjrRect& viewport, double scale = 1.0, bool sky = false);
  // Reads the window's back buffer (bottom-up RGB rows).
  void ReadPixels(int width, int height, unsigned char* rgb);

  mjModel* model() { return model_.get(); }
  mjData* data() { return data_.get(); }
  mjvScene& scene() { return scene_; }
  mjvCamera& camera() { return camera_; }
  mjvOption& option() { return option_; }
  mjvPerturb& perturb() { return perturb_; }
  mjrContext& context() { return context_; }
  // The frame number of the last Update (0 before the first).
  std::uint64_t frame() const { return frame_; }
  bool paused() const { return paused_; }

 private:
  physics::ModelPtr model_;
  physics::DataPtr data_;
  mjvScene scene_;
  mjvCamera camera_;
  mjvOption option_;
  mjvPerturb perturb_;
  mjrContext context_;
  bool has_context_ = false;
  int shadow_size_ = 0;
  std::uint64_t frame_ = 0;
  bool paused_ = false;
};

}  // namespace urlab::viewer::internal
