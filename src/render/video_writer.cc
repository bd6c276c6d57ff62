#include "render/video_writer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <iterator>

#include "urlab/core/error.h"

namespace urlab::render {

namespace {

// The encoder per container: the one table of what the video writer accepts.
struct VideoFormat {
  const char* extension;
  const char* codec_args;
};
constexpr VideoFormat kVideoFormats[] = {
    {".mp4", "-c:v libx264 -preset veryfast -pix_fmt yuv420p"},
    {".webm", "-c:v libvpx-vp9 -deadline realtime -cpu-used 8 -pix_fmt yuv420p"},
};

// ffmpeg's input options per layout.
struct InputFormat {
  VideoInput input;
  const char* pix_fmt;
  const char* filter;  // "" for none
  int bytes_per_pixel;
};
constexpr InputFormat kInputFormats[] = {
    {VideoInput::kRgbBottomUp, "rgb24", "-vf vflip", 3},
    {VideoInput::kBgraTopDown, "bgra", "", 4},
    {VideoInput::kRgbTopDown, "rgb24", "", 3},
};

const InputFormat& FormatOf(VideoInput input) {
  return *std::find_if(std::begin(kInputFormats), std::end(kInputFormats),
                       [&](const InputFormat& f) { return f.input == input; });
}

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

}  // namespace

VideoWriter::VideoWriter(const std::string& path, int width, int height, int fps, VideoInput input)
    : path_(path), width_(width), height_(height), input_(input) {
  const std::string ext = std::filesystem::path(path).extension().string();
  const auto* format = std::find_if(std::begin(kVideoFormats), std::end(kVideoFormats),
                                    [&](const VideoFormat& f) { return ext == f.extension; });
  if (format == std::end(kVideoFormats)) {
    throw Error(path + ": the video must be .mp4 (H.264) or .webm (VP9)");
  }
  const InputFormat& in = FormatOf(input);
  const std::string command =
      fmt::format("ffmpeg -y -loglevel error -f rawvideo -pix_fmt {} -s {}x{} -r {} -i - {} {} {}",
                  in.pix_fmt, width, height, fps, in.filter, format->codec_args, ShellQuote(path));
  std::signal(SIGPIPE, SIG_IGN);  // a dead ffmpeg makes fwrite fail instead of killing us
  pipe_ = ::popen(command.c_str(), "w");
  if (!pipe_) throw Error(path + ": cannot start ffmpeg (is the ffmpeg package installed?)");
}

VideoWriter::~VideoWriter() { Close(); }

bool VideoWriter::Write(const std::uint8_t* pixels) {
  if (!pipe_ || failed_) return false;
  const std::size_t n = static_cast<std::size_t>(FormatOf(input_).bytes_per_pixel) *
                        static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  if (std::fwrite(pixels, 1, n, pipe_) != n) {
    failed_ = true;
    spdlog::error("{}: ffmpeg stopped taking frames after {}", path_, frames_);
    return false;
  }
  ++frames_;
  return true;
}

int VideoWriter::Close() {
  if (!pipe_) return 0;
  const int status = ::pclose(pipe_);
  pipe_ = nullptr;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace urlab::render
