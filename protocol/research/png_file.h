#pragma once
// PNG files of RGB8 images (core/render's Image), compressed with zlib. The writer emits the
// minimal valid file: signature, IHDR (8-bit truecolour, not interlaced), one IDAT of
// filter-0 scanlines, IEND. The reader decodes 8-bit greyscale, RGB and RGBA, non-interlaced
// files with any scanline filter (enough for the project's own files and tests); alpha is
// dropped, grey is expanded to RGB.
#include <string>

#include "core/render/software_rasterizer.h"

namespace skinstream {

// Throws FileError when the file cannot be written or the image is empty or inconsistent.
void write_png(const std::string& path, const render::Image& image);

// Throws FileError for a missing file, a bad signature, a CRC mismatch, a truncated or
// corrupt stream, or an unsupported kind of PNG (named in the message).
render::Image read_png(const std::string& path);

}  // namespace skinstream
