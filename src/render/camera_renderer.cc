#include "render/camera_renderer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>

#include "render/frame_data.h"
#include "urlab/core/error.h"

namespace urlab::render {

namespace {

// Geoms beyond the model's a camera scene may hold (decor is off, so few are needed).
constexpr int kExtraGeoms = 100;

// Copies bottom-up rows of `row` elements each into top-down order.
template <typename T>
void FlipRows(const T* from, int width, int height, int per_pixel, std::vector<T>& to) {
  const std::size_t row = static_cast<std::size_t>(width) * static_cast<std::size_t>(per_pixel);
  to.resize(row * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    std::copy_n(from + static_cast<std::size_t>(height - 1 - y) * row, row,
                to.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * row));
  }
}

}  // namespace

CameraRenderer::CameraRenderer(const mjModel* source, int max_width, int max_height,
                               RenderSettings settings)
    : settings_(settings), max_width_(max_width), max_height_(max_height) {
  if (max_width < 1 || max_height < 1) {
    throw Error(fmt::format("camera renderer: bad image size {}x{}", max_width, max_height));
  }
  model_.reset(mj_copyModel(nullptr, source));
  if (!model_) throw Error("camera renderer: cannot copy the model");
  // The off-screen buffer's size and samples are read by mjr_makeContext.
  model_->vis.global.offwidth = max_width;
  model_->vis.global.offheight = max_height;
  model_->vis.quality.offsamples = settings.samples;
  data_ = physics::MakeData(model_.get());
  mjv_defaultScene(&scene_);
  mjv_defaultCamera(&camera_);
  mjv_defaultOption(&option_);
  mjr_defaultContext(&context_);
  mjv_makeScene(model_.get(), &scene_, model_->ngeom + kExtraGeoms);
  for (int i = 0; i < mjNGROUP; ++i) option_.sitegroup[i] = 0;  // sites are not seen by robots
  scene_.flags[mjRND_SHADOW] = settings.shadows ? 1 : 0;
  scene_.flags[mjRND_REFLECTION] = settings.reflections ? 1 : 0;
  camera_.type = mjCAMERA_FIXED;
  group_of_geom_.assign(static_cast<std::size_t>(model_->ngeom), -1);
  mj_forward(model_.get(), data_.get());
}

CameraRenderer::~CameraRenderer() {
  mjv_freeScene(&scene_);
  if (has_context_) mjr_freeContext(&context_);
}

void CameraRenderer::MakeContext() {
  mjr_makeContext(model_.get(), &context_, mjFONTSCALE_100);
  has_context_ = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  if (context_.currentBuffer != mjFB_OFFSCREEN) {
    throw Error("camera renderer: the OpenGL context has no off-screen framebuffer");
  }
}

void CameraRenderer::ReplaceModelValues(const mjModel* source) {
  // The off-screen size and samples set at construction stay.
  render::ReplaceModelValues(model_.get(), source, has_context_ ? &context_ : nullptr);
}

void CameraRenderer::Update(const physics::StateFrame& frame) {
  CopyFrameToData(model_.get(), data_.get(), frame);
}

void CameraRenderer::SetGeomGroups(std::vector<int> group_of_geom) {
  group_of_geom.resize(static_cast<std::size_t>(model_->ngeom), -1);
  group_of_geom_ = std::move(group_of_geom);
}

void CameraRenderer::Draw(const mjrRect& viewport, bool segment) {
  scene_.flags[mjRND_SEGMENT] = segment ? 1 : 0;
  scene_.flags[mjRND_IDCOLOR] = segment ? 1 : 0;
  mjv_updateScene(model_.get(), data_.get(), &option_, nullptr, &camera_, mjCAT_ALL, &scene_);
  mjr_render(viewport, &scene_, &context_);
}

void CameraRenderer::Render(int camera, int width, int height, const ImageRequest& request,
                            CameraImages& out) {
  if (camera < 0 || camera >= model_->ncam) {
    throw Error(
        fmt::format("camera renderer: no camera {} (the model has {})", camera, model_->ncam));
  }
  mjv_defaultCamera(&camera_);
  camera_.type = mjCAMERA_FIXED;
  camera_.fixedcamid = camera;
  RenderWith(width, height, request, out);
}

void CameraRenderer::RenderView(const mjvCamera& view, int width, int height,
                                const ImageRequest& request, CameraImages& out) {
  camera_ = view;
  RenderWith(width, height, request, out);
}

void CameraRenderer::RenderWith(int width, int height, const ImageRequest& request,
                                CameraImages& out) {
  if (width < 1 || height < 1 || width > max_width_ || height > max_height_) {
    throw Error(fmt::format("camera renderer: {}x{} is outside the off-screen buffer {}x{}", width,
                            height, max_width_, max_height_));
  }
  if (!has_context_) throw Error("camera renderer: MakeContext was not called");
  out.width = width;
  out.height = height;
  const mjrRect viewport = {0, 0, width, height};
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (request.rgb || request.depth) {
    Draw(viewport, false);
    scratch_rgb_.resize(3 * pixels);
    scratch_depth_.resize(pixels);
    mjr_readPixels(request.rgb ? scratch_rgb_.data() : nullptr,
                   request.depth ? scratch_depth_.data() : nullptr, viewport, &context_);
    if (request.rgb) FlipRows(scratch_rgb_.data(), width, height, 3, out.rgb);
    if (request.depth) {
      // The depth buffer holds z in [0, 1] of a perspective projection with near and far planes
      // n and f: the distance along the optical axis is n / (1 - z (1 - n / f)).
      const double extent = model_->stat.extent;
      const double n = model_->vis.map.znear * extent;
      const double f = model_->vis.map.zfar * extent;
      for (float& z : scratch_depth_) {
        z = static_cast<float>(n / (1.0 - static_cast<double>(z) * (1.0 - n / f)));
      }
      FlipRows(scratch_depth_.data(), width, height, 1, out.depth);
    }
  }
  if (request.segmentation) {
    Draw(viewport, true);
    scratch_rgb_.resize(3 * pixels);
    mjr_readPixels(scratch_rgb_.data(), nullptr, viewport, &context_);
    out.geom_ids.resize(pixels);
    out.group_ids.resize(pixels);
    for (int y = 0; y < height; ++y) {
      const std::uint8_t* row =
          scratch_rgb_.data() + 3 * static_cast<std::size_t>(height - 1 - y) * width;
      for (int x = 0; x < width; ++x) {
        const std::uint8_t* p = row + 3 * x;
        // MuJoCo's id colour: the scene geom's index + 1 in R, G, B (low byte first).
        const int seg = p[0] | (p[1] << 8) | (p[2] << 16);
        int geom = -1;
        if (seg > 0 && seg <= scene_.ngeom) {
          const mjvGeom& g = scene_.geoms[seg - 1];
          if (g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < model_->ngeom) geom = g.objid;
        }
        const std::size_t i = static_cast<std::size_t>(y) * width + x;
        out.geom_ids[i] = geom;
        out.group_ids[i] = geom < 0 ? -1 : group_of_geom_[static_cast<std::size_t>(geom)];
      }
    }
  }
}

void IdColor(std::int32_t id, std::uint8_t bgra[4]) {
  const std::uint32_t v = id < 0 ? 0u : static_cast<std::uint32_t>(id) + 1u;
  bgra[0] = static_cast<std::uint8_t>(v & 0xFF);
  bgra[1] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
  bgra[2] = static_cast<std::uint8_t>((v >> 16) & 0xFF);
  bgra[3] = 255;
}

std::int32_t DecodeIdColor(const std::uint8_t bgra[4]) {
  const std::int32_t v = bgra[0] | (bgra[1] << 8) | (bgra[2] << 16);
  return v - 1;
}

void RgbToBgra(const std::vector<std::uint8_t>& rgb, std::vector<std::uint8_t>& bgra) {
  const std::size_t n = rgb.size() / 3;
  bgra.resize(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    bgra[4 * i] = rgb[3 * i + 2];
    bgra[4 * i + 1] = rgb[3 * i + 1];
    bgra[4 * i + 2] = rgb[3 * i];
    bgra[4 * i + 3] = 255;
  }
}

void IdsToBgra(const std::vector<std::int32_t>& ids, std::vector<std::uint8_t>& bgra) {
  bgra.resize(4 * ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) IdColor(ids[i], &bgra[4 * i]);
}

}  // namespace urlab::render
