// The per-pixel gather's sample sequences (direct.h): light points and
// sub-pixel offsets, rotated per pixel (Cranley-Patterson), from the pixel
// index alone.
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

// The rotations' hashes of a pixel's light points and sub-pixel offsets.
uint64_t LightHash(uint32_t pixel) {
  return Mix64(0x9e3779b97f4a7c15ull ^ (uint64_t(pixel) * 0x2545f4914f6cdd1dull));
}
uint64_t OffsetHash(uint32_t pixel) {
  return Mix64(0xd1b54a32d192ed03ull ^ (uint64_t(pixel) * 0x9e3779b97f4a7c15ull));
}

// RadicalInverse in bases 2, 3 (light points) and 5, 7 (offsets) for k <
// kTabled (static storage, filled on first use).
constexpr uint32_t kTabled = DirectPixelOffsets::kTabled;
static_assert(DirectLightSamples::kTabled == kTabled, "one table size");
struct Tables {
  float base[4][kTabled];
  Tables() {
    const uint32_t b[4] = {2, 3, 5, 7};
    for (int i = 0; i < 4; ++i)
      for (uint32_t k = 0; k < kTabled; ++k) base[i][k] = RadicalInverse(k, b[i]);
  }
};
const Tables& GetTables() {
  static const Tables tables;
  return tables;
}

// The pair of bases b0 (table row i) and b1 (row i + 1) at k, rotated.
glm::vec2 Pair(int i, uint32_t b0, uint32_t b1, uint32_t k, uint64_t h, uint64_t h2) {
  if (k < kTabled) {
    const Tables& t = GetTables();
    return glm::vec2(Rotate(t.base[i][k], h), Rotate(t.base[i + 1][k], h2));
  }
  return glm::vec2(Rotate(RadicalInverse(k, b0), h), Rotate(RadicalInverse(k, b1), h2));
}

}  // namespace

glm::vec2 DirectLightSample(uint32_t pixel, uint32_t k) {
  uint64_t h = LightHash(pixel);
  return glm::vec2(Rotate(RadicalInverse(k, 2), h), Rotate(RadicalInverse(k, 3), Mix64(h)));
}

glm::vec2 DirectPixelOffset(uint32_t pixel, uint32_t k) {
  uint64_t h = OffsetHash(pixel);
  return glm::vec2(Rotate(RadicalInverse(k, 5), h), Rotate(RadicalInverse(k, 7), Mix64(h)));
}

DirectLightSamples::DirectLightSamples(uint32_t pixel) : h_(LightHash(pixel)), h2_(Mix64(h_)) {}

glm::vec2 DirectLightSamples::operator()(uint32_t k) const {
  return Pair(0, 2, 3, k, h_, h2_);
}

DirectPixelOffsets::DirectPixelOffsets(uint32_t pixel) : h_(OffsetHash(pixel)), h2_(Mix64(h_)) {}

glm::vec2 DirectPixelOffsets::operator()(uint32_t k) const {
  return Pair(2, 5, 7, k, h_, h2_);
}

}  // namespace vismask
