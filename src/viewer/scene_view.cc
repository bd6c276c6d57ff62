#include "viewer/scene_view.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cmath>

#include "render/frame_data.h"
#include "urlab/core/error.h"
#include "viewer/render_quality.h"

namespace urlab::viewer::internal {

SceneView::SceneView(const mjModel* source, int maxgeom) {
  model_.reset(mj_copyModel(nullptr, source));
  if (!model_) throw Error("viewer: cannot copy the model");
  data_ = physics::MakeData(model_.get());
  mjv_defaultScene(&scene_);
  mjv_defaultCamera(&camera_);
  mjv_defaultOption(&option_);
  mjv_defaultPerturb(&perturb_);
  mjr_defaultContext(&context_);
  mjv_makeScene(model_.get(), &scene_, maxgeom);
  mjv_defaultFreeCamera(model_.get(), &camera_);
  mj_forward(model_.get(), data_.get());
}

SceneView::~SceneView() {
  mjv_freeScene(&scene_);
  if (has_context_) mjr_freeContext(&context_);
}

void SceneView::MakeContext(int shadow_size, int off_w, int off_h) {
  mjModel* m = model_.get();
  if (shadow_size > 0) m->vis.quality.shadowsize = std::min(m->vis.quality.shadowsize, shadow_size);
  shadow_size_ = shadow_size;
  // A single-sampled offscreen buffer, so that it can be scaled into the window.
  m->vis.quality.offsamples = 0;
  m->vis.global.offwidth = std::max(m->vis.global.offwidth, off_w);
  m->vis.global.offheight = std::max(m->vis.global.offheight, off_h);
  if (has_context_) mjr_freeContext(&context_);
  mjr_defaultContext(&context_);
  mjr_makeContext(m, &context_, mjFONTSCALE_100);
  has_context_ = true;
  mjr_setBuffer(mjFB_WINDOW, &context_);
}

void SceneView::ReplaceModelValues(const mjModel* source) {
  // Shadow size and offscreen buffer, set by MakeContext, stay.
  render::ReplaceModelValues(model_.get(), source, has_context_ ? &context_ : nullptr);
}

void SceneView::Update(const physics::StateFrame& f) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  // Positions only: what drawing, selection and perturbation read (no dynamics, no collision:
  // contacts come from the physics thread's debug capture).
  render::CopyFrameToData(m, d, f);
  frame_ = f.frame;
  paused_ = f.paused;
}

void SceneView::UpdateScene() {
  mjv_updateScene(model_.get(), data_.get(), &option_, &perturb_, &camera_, mjCAT_ALL, &scene_);
}

void SceneView::Render(const mjrRect& viewport, double scale, bool sky) {
  if (std::abs(scale - 1.0) < 1e-6) {
    mjr_setBuffer(mjFB_WINDOW, &context_);
    mjr_render(viewport, &scene_, &context_);
    if (sky) DrawGradientSky(viewport);
    return;
  }
  const int w = std::max(1, static_cast<int>(std::lround(viewport.width * scale)));
  const int h = std::max(1, static_cast<int>(std::lround(viewport.height * scale)));
  if (w > context_.offWidth || h > context_.offHeight) {
    MakeContext(shadow_size_, w, h);  // the window grew: a larger offscreen buffer
  }
  const mjrRect off = {0, 0, w, h};
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  mjr_render(off, &scene_, &context_);
  if (sky) DrawGradientSky(off);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, context_.offFBO);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, w, h, viewport.left, viewport.bottom, viewport.left + viewport.width,
                    viewport.bottom + viewport.height, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  mjr_setBuffer(mjFB_WINDOW, &context_);
}

void SceneView::ReadPixels(int width, int height, unsigned char* rgb) {
  const mjrRect viewport = {0, 0, width, height};
  mjr_readPixels(rgb, nullptr, viewport, &context_);
}

}  // namespace urlab::viewer::internal
