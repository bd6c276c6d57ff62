#include "viewer/image_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <stb_image.h>
#include <stb_image_write.h>
#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <filesystem>

#include "urlab/core/error.h"

namespace urlab::viewer::internal {

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

Image FromBottomUp(int width, int height, const std::uint8_t* rgb) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgb.resize(static_cast<std::size_t>(3 * width * height));
  const std::size_t row = static_cast<std::size_t>(3 * width);
  for (int y = 0; y < height; ++y) {
    std::copy_n(rgb + static_cast<std::size_t>(height - 1 - y) * row, row,
                img.rgb.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * row));
  }
  return img;
}

void WritePng(const std::string& path, const Image& image) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(p.parent_path(), ec);
  }
  if (!stbi_write_png(path.c_str(), image.width, image.height, 3, image.rgb.data(),
                      3 * image.width)) {
    throw Error(path + ": cannot write the screenshot");
  }
}

Image ReadImage(const std::string& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 3);
  if (!data) throw Error(path + ": cannot read the image");
  Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(data, data + static_cast<std::size_t>(3 * w * h));
  stbi_image_free(data);
  return img;
}

VideoWriter::VideoWriter(const std::string& path, int width, int height, int fps)
    : path_(path), width_(width), height_(height) {
  const std::string ext = std::filesystem::path(path).extension().string();
  const auto* format = std::find_if(std::begin(kVideoFormats), std::end(kVideoFormats),
                                    [&](const VideoFormat& f) { return ext == f.extension; });
  if (format == std::end(kVideoFormats)) {
    throw Error(path + ": the video must be .mp4 (H.264) or .webm (VP9)");
  }
  const std::string command = fmt::format(
      "ffmpeg -y -loglevel error -f rawvideo -pix_fmt rgb24 -s {}x{} -r {} -i - -vf vflip {} {}",
      width, height, fps, format->codec_args, ShellQuote(path));
  std::signal(SIGPIPE, SIG_IGN);  // a dead ffmpeg makes fwrite fail instead of killing us
  pipe_ = ::popen(command.c_str(), "w");
  if (!pipe_) throw Error(path + ": cannot start ffmpeg (is the ffmpeg package installed?)");
}

VideoWriter::~VideoWriter() { Close(); }

bool VideoWriter::Write(const std::uint8_t* rgb) {
  if (!pipe_ || failed_) return false;
  const std::size_t n = static_cast<std::size_t>(3 * width_ * height_);
  if (std::fwrite(rgb, 1, n, pipe_) != n) {
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

}  // namespace urlab::viewer::internal
