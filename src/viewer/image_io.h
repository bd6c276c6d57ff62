#pragma once
// Writing the viewer's frames out as PNG screenshots (stb_image_write) and reading images back.
// Video goes through render::VideoWriter (src/render/video_writer.h).
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

}  // namespace urlab::viewer::internal
