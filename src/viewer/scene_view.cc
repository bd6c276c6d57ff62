#include "viewer/scene_view.h"

#include "render/frame_data.h"
#include "urlab/core/error.h"

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

void SceneView::MakeContext() {
  mjr_makeContext(model_.get(), &context_, mjFONTSCALE_100);
  has_context_ = true;
  mjr_setBuffer(mjFB_WINDOW, &context_);
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

void SceneView::Render(int width, int height) {
  const mjrRect viewport = {0, 0, width, height};
  mjr_render(viewport, &scene_, &context_);
}

void SceneView::ReadPixels(int width, int height, unsigned char* rgb) {
  const mjrRect viewport = {0, 0, width, height};
  mjr_readPixels(rgb, nullptr, viewport, &context_);
}

}  // namespace urlab::viewer::internal
