// `urlab render`: a recording to a video, offline and frame-exact: frame k shows the recorded
// state at k / fps seconds into the recording, however long each frame takes to render. Off-screen
// OpenGL (EGL or OSMesa: no display needed), MuJoCo's renderer from the model the recording
// carries, ffmpeg for the encoding (to a temporary file renamed into place when complete).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <system_error>

#include "app/commands.h"
#include "app/signals.h"
#include "render/camera_renderer.h"
#include "render/gl_context.h"
#include "render/render_thread.h"
#include "render/video_writer.h"
#include "render/view_camera.h"
#include "urlab/core/files.h"
#include "urlab/replay/frame_sampler.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recording.h"

namespace urlab::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RenderArgs {
  std::string file;
  std::string video;
  int fps = 30;
  std::string camera = "free";
  int width = 1280;
  int height = 720;
  bool shadows = false;
};

// The file ffmpeg writes until the video is complete: hidden, beside the file written (`out`,
// links followed), with the extension of the name the user gave (ffmpeg picks the container by
// it).
std::string TemporaryFor(const std::string& out, const std::string& extension) {
  const fs::path p(out);
  return (p.parent_path() / ("." + p.stem().string() + ".urlab-tmp" + extension)).string();
}

int Render(const RenderArgs& args) {
  CurrentInput() = args.file;
  CheckOutputs({{args.video, "--video"}}, {args.file});
  const replay::RecordingReader reader = replay::RecordingReader::Open(args.file, {true});
  if (!reader.problem().empty()) {
    spdlog::warn("{}: {}; rendering the {} readable chunk(s)", args.file, reader.problem(),
                 reader.chunks().size());
  }
  if (reader.info().kind != "recording") {
    throw InputError({args.file, 0}, "not a recording (a " + reader.info().kind + ")");
  }
  const physics::Model model = replay::LoadRecordedModel(reader);
  const render::ViewCamera camera = render::ParseViewCamera(model.get(), args.camera, "--camera");
  replay::FrameSampler sampler(reader);
  const std::uint64_t frames = sampler.FrameCount(static_cast<double>(args.fps));

  render::LimitSoftwareRasterThreads();
  std::unique_ptr<render::OffscreenGl> gl = render::OffscreenGl::Create();
  render::RenderSettings settings;
  settings.shadows = args.shadows;
  render::CameraRenderer renderer(model.get(), args.width, args.height, settings);
  renderer.MakeContext();
  // The output rule (core/files.h): a regular file or nothing (through a symbolic link: its
  // target) gets a temporary beside it, renamed over it once complete; a device or FIFO is
  // written in place by ffmpeg (the user's name keeps the extension ffmpeg goes by).
  const OutputTarget target = ResolveOutput(args.video);
  const bool in_place = target.mode == OutputTarget::Mode::kInPlace;
  const std::string temporary =
      in_place ? args.video : TemporaryFor(target.file, fs::path(args.video).extension().string());
  if (!in_place && !fs::path(target.file).parent_path().empty()) {
    fs::create_directories(fs::path(target.file).parent_path());
  }
  spdlog::info("render: {} -> {}: {} frames at {} frames/s ({:.3f} s recorded), {}x{}, {} ({})",
               args.file, args.video, frames, args.fps, sampler.duration(), args.width, args.height,
               camera.label, gl->Describe());
  SetImmediateExit(false);  // a signal stops the loop, which removes the partial video
  auto discard = [&temporary, in_place] {
    if (in_place) return;  // a device is never removed
    std::error_code ec;
    fs::remove(temporary, ec);
  };
  int status = 0;
  const auto start = Clock::now();
  {
    render::VideoWriter video(temporary, args.width, args.height, args.fps,
                              render::VideoInput::kRgbTopDown);
    render::CameraImages image;
    render::ImageRequest request;
    request.rgb = true;
    auto next_log = start + std::chrono::seconds(2);
    for (std::uint64_t k = 0; k < frames; ++k) {
      if (StopSignal() != 0) break;
      renderer.Update(sampler.At(static_cast<double>(k) / static_cast<double>(args.fps)));
      if (camera.camera >= 0) {
        renderer.Render(camera.camera, args.width, args.height, request, image);
      } else {
        renderer.RenderView(camera.view, args.width, args.height, request, image);
      }
      if (!video.Write(image.rgb.data())) break;
      const auto now = Clock::now();
      if (now >= next_log) {
        const double elapsed = std::chrono::duration<double>(now - start).count();
        const double done = static_cast<double>(k + 1) / static_cast<double>(frames);
        spdlog::info("render: frame {}/{} ({:.0f}%), {:.1f} frames/s, about {:.0f} s left", k + 1,
                     frames, 100 * done, static_cast<double>(k + 1) / elapsed,
                     elapsed / done - elapsed);
        next_log = now + std::chrono::seconds(2);
      }
    }
    const int written = video.frames();
    status = video.Close();
    if (StopSignal() != 0) {
      discard();
      spdlog::warn("render: stopped after {} of {} frames; {} not written", written, frames,
                   args.video);
      return ExitCodeForSignal(StopSignal());
    }
    if (status != 0 || static_cast<std::uint64_t>(written) != frames) {
      discard();
      std::fprintf(stderr, "urlab: error: %s: ffmpeg failed (exit %d) after %d of %llu frames\n",
                   args.video.c_str(), status, written, static_cast<unsigned long long>(frames));
      return 1;
    }
  }
  std::error_code ec;
  if (!in_place) fs::rename(temporary, target.file, ec);
  if (ec) {
    discard();
    throw Error(args.video + ": cannot move the video into place: " + ec.message());
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "wrote %s: %llu frames at %d frames/s (t = 0 to %.3f s of %.3f s recorded) in %.1f s\n",
      args.video.c_str(), static_cast<unsigned long long>(frames), args.fps,
      static_cast<double>(frames - 1) / static_cast<double>(args.fps), sampler.duration(), wall);
  return 0;
}

}  // namespace

void RegisterRenderCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render a recording (.urrec) to a video, offline and frame-exact: frame k shows the "
      "recorded state at k/fps seconds into the recording, however slow the renderer (a 4 s "
      "recording at 30 frames/s is 120 frames). Uses the model the recording carries and "
      "off-screen OpenGL (EGL or OSMesa; no display needed); ffmpeg encodes (.mp4 H.264 or "
      ".webm VP9). The video appears under its name only once complete. Logs progress every "
      "2 s.");
  static RenderArgs args;
  cmd->add_option("RECORDING", args.file, "the recording (.urrec)")->required();
  cmd->add_option("--video", args.video, "the video to write (.mp4 or .webm)")->required();
  cmd->add_option("--fps", args.fps, "frames per second of recorded time (default 30)")
      ->check(CLI::Range(1, 240));
  cmd->add_option("--camera", args.camera,
                  "free (default: the whole scene framed), track:BODY (follow a body), or an MJCF "
                  "camera by name (articulation/camera or its full name)");
  cmd->add_option("--width", args.width, "image width in pixels (default 1280)")
      ->check(CLI::Range(16, 8192));
  cmd->add_option("--height", args.height, "image height in pixels (default 720)")
      ->check(CLI::Range(16, 8192));
  cmd->add_flag("--shadows", args.shadows,
                "render shadows (off by default: they cost a factor of 4 to 10 in software)");
  cmd->callback([&exit_code] { exit_code = Render(args); });
}

}  // namespace urlab::app
