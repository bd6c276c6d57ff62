#pragma once
// CameraRenderer: renders the model's own (MJCF) cameras off-screen from a copy of the compiled
// model and an mjData of its own filled from state frames, as the viewer's SceneView does for its
// window: colour (RGB), depth linearised to metres, and segmentation by geom and by group (the
// caller's geom -> group table, e.g. articulations for instance masks). Images are top-down rows.
//
// Rendering defaults favour software rendering (llvmpipe): shadows, reflections and multisampling
// off (shadows cost a factor of 4 to 10 there); RenderSettings turns them back on.
//
// Threading contract: one thread (the one whose OffscreenGl context is current), after
// construction, which may happen on another thread while nobody else uses the source model.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <vector>

#include "urlab/physics/model.h"
#include "urlab/physics/state_frame.h"

namespace urlab::render {

struct RenderSettings {
  bool shadows = false;
  bool reflections = false;
  int samples = 0;  // multisampling of the off-screen buffer (segmentation edges blend when > 0)
};

// What one render pass produces; only the parts asked for are sized.
struct ImageRequest {
  bool rgb = false;
  bool depth = false;
  bool segmentation = false;  // fills both geom_ids and group_ids
};

struct CameraImages {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;        // 3 bytes per pixel, top-down rows
  std::vector<float> depth;             // metres along the optical axis
  std::vector<std::int32_t> geom_ids;   // MuJoCo geom id, -1 for background and non-geoms
  std::vector<std::int32_t> group_ids;  // the geom's group (see SetGeomGroups), -1 when none
};

class CameraRenderer {
 public:
  // Copies `source` (call while nobody changes its options); the off-screen buffer is sized
  // max_width x max_height, the largest image any camera asks for.
  CameraRenderer(const mjModel* source, int max_width, int max_height, RenderSettings settings);
  ~CameraRenderer();
  CameraRenderer(const CameraRenderer&) = delete;
  CameraRenderer& operator=(const CameraRenderer&) = delete;

  // Uploads the model to the GPU; an OffscreenGl context must be current.
  void MakeContext();
  // Copies the frame's state into the renderer's mjData and recomputes positions.
  void Update(const physics::StateFrame& frame);
  // Takes the values of `source` (a copy of the running model after a ReplaceModel command: the
  // same structure), keeping the renderer's off-screen settings, and uploads textures, meshes
  // and heightfields again when a context was made (it must be current). Update follows.
  void ReplaceModelValues(const mjModel* source);
  // Per geom id, the group reported by segmentation (-1: none); default all -1.
  void SetGeomGroups(std::vector<int> group_of_geom);
  // Renders MJCF camera `camera` at width x height (at most the off-screen size) into `out`.
  // Throws Error for a bad camera id or size.
  void Render(int camera, int width, int height, const ImageRequest& request, CameraImages& out);
  // Renders from `view` (a free or tracking camera, render/view_camera.h) instead of an MJCF
  // camera, with the same requests and limits.
  void RenderView(const mjvCamera& view, int width, int height, const ImageRequest& request,
                  CameraImages& out);

  mjModel* model() { return model_.get(); }
  mjData* data() { return data_.get(); }
  int max_width() const { return max_width_; }
  int max_height() const { return max_height_; }

 private:
  void Draw(const mjrRect& viewport, bool segment);
  void RenderWith(int width, int height, const ImageRequest& request, CameraImages& out);

  physics::ModelPtr model_;
  physics::DataPtr data_;
  RenderSettings settings_;
  int max_width_, max_height_;
  mjvScene scene_;
  mjvCamera camera_;
  mjvOption option_;
  mjrContext context_;
  bool has_context_ = false;
  std::vector<int> group_of_geom_;
  std::vector<std::uint8_t> scratch_rgb_;
  std::vector<float> scratch_depth_;
};

// ---- Wire conversions (docs/protocol.md: B, G, R, A bytes per pixel) ----

// The colour an id travels as in a segmentation image: id + 1 in the low three bytes (B, G, R),
// A = 255; id -1 (background) is black. DecodeIdColor inverts it.
void IdColor(std::int32_t id, std::uint8_t bgra[4]);
std::int32_t DecodeIdColor(const std::uint8_t bgra[4]);
// RGB rows to BGRA rows; ids to BGRA rows.
void RgbToBgra(const std::vector<std::uint8_t>& rgb, std::vector<std::uint8_t>& bgra);
void IdsToBgra(const std::vector<std::int32_t>& ids, std::vector<std::uint8_t>& bgra);

}  // namespace urlab::render
