// Visibility mask (Arnaldi et al. 1996; Talbot & O'Sullivan): the hemisphere
// over a shooting patch's centre as R x 4R bits, theta in R rows (uniform
// steps from the normal to the horizon), phi in 4R columns (uniform from the
// patch's tangent), one bit per pixel: 1 = open, 0 = occluded. Directions are
// in the patch's local frame (sampling.h's Frame: z = normal).
#pragma once
#include <cstdint>

#include <glm/vec3.hpp>

#include "vismask/span.h"

namespace vismask {

enum class MaskMethod : uint8_t {
  kNone,  // no mask: foreign energy passes other environments' occluders
  kA,     // clear the pixels of form-factor rays that hit
  kB,     // one ray from the centre through every pixel open upstream
};
const char* MaskMethodName(MaskMethod m);

struct MaskShape {
  uint32_t res = 0;  // R; 0 = no mask
  uint32_t pixels() const { return 4 * res * res; }
  uint32_t bytes() const { return (pixels() + 7) / 8; }  // what a packet carries
  uint32_t words() const { return (pixels() + 63) / 64; }
};

// The pixel of local direction `d` (unit, d.z >= 0).
uint32_t MaskPixel(const glm::vec3& d, uint32_t res);
// The unit local direction through the centre of `pixel`.
glm::vec3 MaskPixelCentre(uint32_t pixel, uint32_t res);

// A mask over 64-bit words (bit p of word p / 64), `res` rows.
class MaskBits {
 public:
  MaskBits() = default;
  MaskBits(Span<uint64_t> words, uint32_t res) : words_(words), res_(res) {}

  uint32_t res() const { return res_; }
  void SetAllOpen();
  bool IsOpen(uint32_t p) const { return (words_[p >> 6] >> (p & 63)) & 1u; }
  void Close(uint32_t p) { words_[p >> 6] &= ~(uint64_t(1) << (p & 63)); }
  // Keeps a pixel open only if it is open in `other` too.
  void And(const MaskBits& other);
  void CopyFrom(const MaskBits& other);
  // The cosine-weighted fraction of the hemisphere that is open: the share of
  // a patch's power its open pixels carry.
  double OpenFraction() const;
  uint32_t CountOpen() const;
  // Packing to and from the packet's ceil(4R^2 / 8) bytes (little-endian).
  void Pack(uint8_t* out) const;
  void Unpack(const uint8_t* in);
  Span<uint64_t> words() const { return words_; }

 private:
  Span<uint64_t> words_;
  uint32_t res_ = 0;
};

}  // namespace vismask
