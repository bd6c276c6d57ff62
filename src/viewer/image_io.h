#pragma once
// Writing the viewer's frames out: PNG screenshots (stb_image_write) and video through an ffmpeg
// process reading raw RGB frames on a pipe (H.264 .mp4 or VP9 .webm).
//
// Threading contract: each object on one thread (the viewer's main thread).
#include <cstdint>
#include <cstdio>
#include <string>

#include "urlab/viewer/viewer.h"

namespace urlab::viewer::internal {

// Flips bottom-up RGB rows (as OpenGL reads them) into a top-down Image.
Image FromBottomUp(int width, int height, const std::uint8_t* rgb);
// Writes `image` as a PNG; throws Error naming the path when it cannot.
void WritePng(const std::string& path, const Image& image);
// Reads a PNG (or any format stb_image reads) as RGB; throws Error naming the path.
Image ReadImage(const std::string& path);

class VideoWriter {
 public:
  // Starts ffmpeg writing `path` (.mp4: H.264, .webm: VP9) from width x height RGB frames at
  // `fps`. Throws Error for another extension or when ffmpeg cannot start.
  VideoWriter(const std::string& path, int width, int height, int fps);
  ~VideoWriter();  // Close()
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  // Appends one frame of bottom-up RGB rows (its size must be the one given at construction).
  // False once ffmpeg has gone (the error is logged once).
  bool Write(const std::uint8_t* rgb);
  // Ends the stream and waits for ffmpeg; returns its exit status (0: the file is complete).
  int Close();
  int frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int width_, height_;
  std::FILE* pipe_ = nullptr;
  int frames_ = 0;
  bool failed_ = false;
};

}  // namespace urlab::viewer::internal
