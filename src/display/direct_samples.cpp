// The per-pixel gather's sample sequences (direct.h): light points and
// sub-pixel offsets, rotated per pixel (Cranley-Patterson), from the pixel
// index alone.
#include <algorithm>
#include <cmath>
#include <glm/vec2.hpp>

#include "vismask/display/direct.h"
#include "vismask/solve/rng.h"

namespace vismask {

namespace {

// Radical inverse in base b of k.
float RadicalInverse(uint32_t k, uint32_t b) {
  float inv = 1.0f / static_cast<float>(b), f = inv, r = 0.0f;
  while (k > 0) {
    r += f * static_cast<float>(k % b);
    k /= b;
    f *= inv;
  }
  return r;
}

float Rotate(float x, uint64_t bits) {
  float s = static_cast<float>(bits >> 40) * (1.0f / 16777216.0f);
  float y = x + s;
  y = y >= 1.0f ? y - 1.0f : y;
  return y < 1.0f ? y : 0.99999994f;
}

// The bases of the light points (2, 3) and of the sub-pixel offsets (5, 7).
constexpr uint32_t kBases[4] = {2, 3, 5, 7};

// The rotations' hash of a pixel's light points, or of its sub-pixel offsets.
uint64_t PixelHash(uint32_t pixel, DirectPixelSequence::Kind kind) {
  return kind == DirectPixelSequence::Kind::kLight
             ? Mix64(0x9e3779b97f4a7c15ull ^ (uint64_t(pixel) * 0x2545f4914f6cdd1dull))
             : Mix64(0xd1b54a32d192ed03ull ^ (uint64_t(pixel) * 0x9e3779b97f4a7c15ull));
}

// Point k of the bases from kBases[row] on, rotated by h and h2.
glm::vec2 Point(int row, uint32_t k, uint64_t h, uint64_t h2) {
  return glm::vec2(Rotate(RadicalInverse(k, kBases[row]), h),
                   Rotate(RadicalInverse(k, kBases[row + 1]), h2));
}

// RadicalInverse in each of kBases for k < kTabled (static storage, filled
// on first use).
constexpr uint32_t kTabled = DirectPixelSequence::kTabled;
struct Tables {
  float base[4][kTabled];
  Tables() {
    for (int i = 0; i < 4; ++i)
      for (uint32_t k = 0; k < kTabled; ++k) base[i][k] = RadicalInverse(k, kBases[i]);
  }
};
const Tables& GetTables() {
  static const Tables tables;
  return tables;
}

}  // namespace

uint32_t PartSamples(uint32_t samples, float cover) {
  const float share =
      std::ceil(static_cast<float>(samples) * std::fmin(std::fmax(cover, 0.0f), 1.0f));
  return std::max(std::min(kMinPartSamples, samples), static_cast<uint32_t>(share));
}

glm::vec2 DirectLightSample(uint32_t pixel, uint32_t k) {
  const uint64_t h = PixelHash(pixel, DirectPixelSequence::Kind::kLight);
  return Point(0, k, h, Mix64(h));
}

glm::vec2 DirectPixelOffset(uint32_t pixel, uint32_t k) {
  const uint64_t h = PixelHash(pixel, DirectPixelSequence::Kind::kOffset);
  return Point(2, k, h, Mix64(h));
}

DirectPixelSequence::DirectPixelSequence(uint32_t pixel, Kind kind)
    : row_(kind == Kind::kLight ? 0 : 2), h_(PixelHash(pixel, kind)), h2_(Mix64(h_)) {}

glm::vec2 DirectPixelSequence::operator()(uint32_t k) const {
  if (k >= kTabled) return Point(row_, k, h_, h2_);
  const Tables& t = GetTables();
  return glm::vec2(Rotate(t.base[row_][k], h_), Rotate(t.base[row_ + 1][k], h2_));
}

}  // namespace vismask
