#pragma once
// Render quality of the viewer: shadows, reflections, the sky and the 3D view's resolution
// scale, from the command line (--shadows, --reflections, --skybox, --render-scale), else the
// scene's `viewer:` section, else defaults chosen to look good under Mesa's software renderer
// too (shadows and reflections on, with a smaller shadow map there; a gradient sky behind the
// scene when the model has no skybox texture of its own).
//
// Threading contract: main thread only (the thread whose GL context is current).
#include <mujoco/mujoco.h>

#include "urlab/viewer/scene_settings.h"
#include "urlab/viewer/viewer.h"

namespace urlab::viewer::internal {

struct RenderQuality {
  bool shadows = true;
  bool reflections = true;
  bool skybox = true;   // the model's skybox texture, or our gradient sky when it has none
  double scale = 1.0;   // 3D view pixels per window pixel (0.25 to 2)
  int shadow_size = 0;  // shadow map size the viewer's model copy uses (0: the model's own)
};

// Shadow map size under a software renderer: a 4096 map (MuJoCo's default) costs most of a
// frame; 1024 still gives clean shadows at window sizes.
inline constexpr int kSoftwareShadowSize = 1024;

RenderQuality ResolveQuality(const ViewerOptions& cli, const QualitySettings& scene,
                             bool software_renderer);

// Puts `q` into the scene's render flags.
void ApplyQuality(const RenderQuality& q, mjvScene* scn);

// True when the model has a skybox texture of its own (mjRND_SKYBOX then draws it).
bool HasSkyboxTexture(const mjModel* m);

// Composed scenes often hold several floors in one plane (each articulation's own world):
// drawn together they fight for the same depth (stripes, worst in the shadow pass). In the
// viewer's copy of the model only, every further plane in the same plane as an earlier one is
// moved 2 mm down along its normal per duplicate. Returns how many were moved.
int SeparateCoplanarPlanes(mjModel* m);

// Draws a vertical gradient into every pixel of `viewport` the scene left empty (depth at the
// far plane), so a model without a skybox is not drawn on black. Call right after mjr_render,
// with the same framebuffer bound.
void DrawGradientSky(const mjrRect& viewport);

}  // namespace urlab::viewer::internal
