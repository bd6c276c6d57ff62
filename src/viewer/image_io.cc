#include "viewer/image_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <filesystem>

#include "urlab/core/error.h"

namespace urlab::viewer::internal {

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

}  // namespace urlab::viewer::internal
