// Image output: tone mapping, PNG (stb_image_write, compressed by zlib with
// every allocation served from an arena region) and PFM (linear float RGB).
// Nothing here allocates from the heap.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "vismask/core/os.h"
#include "vismask/core/span.h"
#include "vismask/core/status.h"

namespace vismask {

// Bytes of scratch the PNG encoder needs for a width x height RGB image,
// whatever its content (a bound from the encoder's allocations and zlib's
// documented memory use and deflateBound).
size_t PngScratchBytes(int width, int height);

// Encodes `rgb` (row 0 at the top, 3 bytes a pixel) as PNG into `file`,
// using only `scratch`. False with *why (os::kWhyBytes) on failure.
bool WritePng(os::OutFile* file, int width, int height, Span<const uint8_t> rgb,
              Span<uint8_t> scratch, char* why);

// Writes `color` (row 0 at the top) as a little-endian PFM ("PF", scale -1,
// rows bottom to top).
bool WritePfm(os::OutFile* file, int width, int height, Span<const glm::vec3> color);

// A PFM image read at init (heap): RGB floats, row 0 at the top.
struct PfmImage {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;  // 3 per pixel
};
// Reads a colour PFM ("PF"), either byte order. Errors name the file. The
// header is checked against the bytes that follow it before the pixels are
// allocated; a NaN or Inf pixel is refused.
Status ReadPfm(const std::string& path, PfmImage* image);
// ReadPfm on the file's bytes already in memory (errors name `name`): the
// same parser and checks, which ReadPfm is with the file read whole (the
// fuzz target tests/fuzz/image_fuzz.cpp feeds it arbitrary bytes).
Status ReadPfmFromBytes(const std::string& name, const std::string& bytes, PfmImage* image);

// An 8-bit greyscale PGM ("P5", maxval <= 255) read at init (heap): one byte
// a pixel, row 0 at the top. Errors name the file.
struct PgmImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
};
Status ReadPgm(const std::string& path, PgmImage* image);
// ReadPgm on bytes in memory, as ReadPfmFromBytes.
Status ReadPgmFromBytes(const std::string& name, const std::string& bytes, PgmImage* image);

// How far image `a` is from image `b` (same size, floats in any layout as
// long as both share it): the relative RMSE sqrt(sum (a-b)^2 / sum b^2) over
// every value (inf if b is all zero and a is not, 0 if both are), and the
// largest absolute difference. Summed in double, in index order.
// With `exclude` (one byte a pixel, a and b then RGB, 3 floats a pixel):
// the pixels where it is nonzero are left out of both sums and of the
// largest difference, and counted in excludedPixels.
struct ImageError {
  double relativeRmse = 0.0;
  double maxAbs = 0.0;
  size_t excludedPixels = 0;
};
ImageError CompareImages(Span<const float> a, Span<const float> b,
                         Span<const uint8_t> exclude = Span<const uint8_t>());

// An exposure that maps the log-average luminance of the covered pixels
// (mask[i] != 0) to middle grey. 1 if nothing is covered.
float AutoExposure(Span<const glm::vec3> color, Span<const uint32_t> coverage, uint32_t emptyId);

// color * exposure, clamped to [0, 1], sRGB-encoded to 8 bits.
void ToneMap(Span<const glm::vec3> color, float exposure, Span<uint8_t> rgb);

}  // namespace vismask
