#pragma once
// Writing camera frames to a video through an ffmpeg process reading raw frames on a pipe
// (H.264 .mp4 or VP9 .webm), for the viewer (bottom-up RGB rows, as mjr_readPixels gives them),
// the cameras (top-down BGRA rows, the wire's) and `urlab render` (top-down RGB rows).
//
// Threading contract: each object on one thread.
#include <cstdint>
#include <cstdio>
#include <string>

namespace urlab::render {

enum class VideoInput {
  kRgbBottomUp,  // 3 bytes per pixel, rows bottom-up (glReadPixels, mjr_readPixels)
  kBgraTopDown,  // 4 bytes per pixel, rows top-down (camera streams)
  kRgbTopDown,   // 3 bytes per pixel, rows top-down (CameraRenderer images)
};

class VideoWriter {
 public:
  // Starts ffmpeg writing `path` (.mp4: H.264, .webm: VP9) from width x height frames at `fps`.
  // Throws Error for another extension or when ffmpeg cannot start.
  VideoWriter(const std::string& path, int width, int height, int fps,
              VideoInput input = VideoInput::kRgbBottomUp);
  ~VideoWriter();  // Close()
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  // Appends one frame (its size must be the one given at construction). False once ffmpeg has
  // gone (the error is logged once).
  bool Write(const std::uint8_t* pixels);
  // Ends the stream and waits for ffmpeg; returns its exit status (0: the file is complete).
  int Close();
  int frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int width_, height_;
  VideoInput input_;
  std::FILE* pipe_ = nullptr;
  int frames_ = 0;
  bool failed_ = false;
};

}  // namespace urlab::render
