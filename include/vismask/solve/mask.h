// Visibility mask (Arnaldi et al. 1996; Talbot & O'Sullivan): the hemisphere
// over a shooting patch's centre as R x 4R bits, theta in R rows (uniform
// steps from the normal to the horizon), phi in 4R columns (uniform from the
// patch's tangent), one bit per pixel: 1 = open, 0 = occluded. Directions are
// in the patch's local frame (sampling.h's Frame: z = normal).
//
// Method R replaces the hemisphere by one bit per Monte Carlo ray of the
// shot (1 = the ray is still in flight); the same bit array carries it.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"

namespace vismask {

enum class MaskMethod : uint8_t {
  kNone,  // no mask: foreign energy passes other environments' occluders
  kA,     // clear the pixels of form-factor rays that hit
  kB,     // one ray from the centre through every pixel open upstream
  kC,     // pixels the form-factor rays only hit close, only passed stay
          // open; B's centre ray decides the rest (both or neither)
  kR,     // one bit per ray of the shot: exact, no hemisphere
};
const char* MaskMethodName(MaskMethod m);

// Which open pixels Method B casts a centre ray through (--centre-rays).
enum class CentreChoice : uint8_t {
  kAll,   // every open pixel that leads to a neighbour
  kRead,  // only those the shot's rays will read downstream
  kAuto,  // read for shots whose rays downstream are few against the pixels
};
const char* CentreChoiceName(CentreChoice c);

struct MaskShape {
  uint32_t res = 0;   // R; 0 = no hemisphere
  uint32_t rays = 0;  // Method R: one bit per ray of a shot (then res is 0)
  uint32_t pixels() const { return 4 * res * res; }
  uint32_t bits() const { return rays > 0 ? rays : pixels(); }
  bool empty() const { return bits() == 0; }
  uint32_t bytes() const { return (bits() + 7) / 8; }  // what a packet carries
  uint32_t words() const { return (bits() + 63) / 64; }
};

// The shape a run's packets and queue slots carry: nothing for `none`, the
// R x 4R hemisphere for A, B and C, `rays` bits for R.
MaskShape MaskShapeOf(MaskMethod m, uint32_t maskRes, uint32_t rays);

// The pixel of local direction `d` (unit, d.z >= 0).
uint32_t MaskPixel(const glm::vec3& d, uint32_t res);
// The unit local direction through the centre of `pixel`.
glm::vec3 MaskPixelCentre(uint32_t pixel, uint32_t res);

// MaskPixelCentre for one resolution, from tables made once (the sines and
// cosines of R row angles and 4R column angles, in double): the same floats,
// bit for bit, without the trigonometry per pixel. Methods B and C cast a
// ray through every open pixel of every shot that has a downstream
// neighbour, and sin/cos were a fifth of a Method B run's instructions.
// Pixel is MaskPixel from tables of the row and column edges: the same
// pixel for every direction (tests/mask_pixel_test.cpp), without the trig.
class MaskDirections {
 public:
  // Carves the tables for resolution `res` (0: none) from `arena`.
  void Layout(Arena& arena, uint32_t res);
  // Computes them; after Layout on a real arena.
  void Fill();
  uint32_t res() const { return res_; }
  double rowSin(uint32_t row) const { return rowSin_[row]; }
  double rowCos(uint32_t row) const { return rowCos_[row]; }
  glm::vec3 Centre(uint32_t pixel) const { return Centre(pixel / (4 * res_), pixel % (4 * res_)); }
  glm::vec3 Centre(uint32_t row, uint32_t col) const {
    double s = rowSin_[row];
    return glm::vec3(static_cast<float>(s * colCos_[col]), static_cast<float>(s * colSin_[col]),
                     static_cast<float>(rowCos_[row]));
  }
  // MaskPixel(d, res()), exactly: by table where d is clear of every edge,
  // by MaskPixel itself within kEdgeMargin of one. res() > 0.
  uint32_t Pixel(const glm::vec3& d) const;
  // Pixel(d) for d = CosineDirection(u1, u2) (sampling.h), a form-factor
  // ray's local direction, without the quadrant, the division and the
  // column tables: the column is that of the angle 2 pi u2 wherever that
  // angle is clear of the column's edges by kSampleAngleMargin, over ten
  // times what CosineDirection's float arithmetic moves d's angle from it;
  // the row is Pixel's, from d.z. Elsewhere, and for d within 1e-6 of the
  // normal, Pixel(d) itself (tests/mask_pixel_test.cpp).
  uint32_t CosinePixel(float u2, const glm::vec3& d) const;

 private:
  // Pixel's and CosinePixel's row: dz clamped to [0, 1], its row from the
  // tables, and in *clear whether it lies more than kEdgeMargin inside
  // both the row's edges (else only MaskPixel decides it).
  uint32_t RowOf(float dz, bool* clear) const;

  uint32_t res_ = 0;
  Span<double> rowSin_, rowCos_, colCos_, colSin_;
  // Row edges: cos(k pi/2R), k = 0..R, falling; [0] = 2 and [R] = -1 stop
  // the search. rowBin_[b]: the row of z just below (b + 1) / rowBins_.
  Span<double> rowEdge_;
  Span<uint32_t> rowBin_;
  // Column edges within a quadrant, in p = b / (a + b) of the quadrant's
  // (a, b), p_j = sin / (sin + cos) of j pi/2R, rising: [0] = 0, [R] = 1,
  // [R + 1] = 2. colBin_[b]: the column of p = b / colBins_.
  Span<double> colEdge_;
  Span<uint32_t> colBin_;
  uint32_t rowBins_ = 0, colBins_ = 0;      // powers of two: z * bins is exact
  double rowScale_ = 0.0, colScale_ = 0.0;  // the same, as doubles
  // CosinePixel: 4R, and kSampleAngleMargin in columns.
  double columns_ = 0.0, columnMargin_ = 0.0;
};

// The set bits of `w`. The builtin where the target has an instruction for
// it (aarch64, x86-64 with POPCNT); on baseline x86-64 the builtin calls
// libgcc's __popcountdi2, so the same count comes from sums of halves, inline.
inline uint32_t PopCount(uint64_t w) {
#if defined(__POPCNT__) || defined(__aarch64__)
  return static_cast<uint32_t>(__builtin_popcountll(w));
#else
  w = w - ((w >> 1) & 0x5555555555555555ull);
  w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
  w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<uint32_t>((w * 0x0101010101010101ull) >> 56);
#endif
}

// The index of the lowest set bit of `w`, which must not be 0 (a single
// instruction on x86-64 and aarch64: bsf/tzcnt, rbit + clz).
inline uint32_t CountTrailingZeros(uint64_t w) {
  return static_cast<uint32_t>(__builtin_ctzll(w));
}

// A mask over 64-bit words (bit p of word p / 64): `res` rows of a
// hemisphere, or (PerRay) one bit per ray.
class MaskBits {
 public:
  MaskBits() = default;
  MaskBits(Span<uint64_t> words, uint32_t res) : words_(words), res_(res), bits_(4 * res * res) {}
  MaskBits(Span<uint64_t> words, const MaskShape& shape)
      : words_(words), res_(shape.res), bits_(shape.bits()) {}
  static MaskBits PerRay(Span<uint64_t> words, uint32_t rays) {
    return MaskBits(words, MaskShape{0, rays});
  }

  uint32_t res() const { return res_; }
  uint32_t bits() const { return bits_; }
  void SetAllOpen();
  void SetAllClosed();
  // Closes every pixel from `begin` on (word by word).
  void CloseFrom(uint32_t begin);
  // Closes the words that hold pixels [0, end): at least those pixels.
  void ClosePrefix(uint32_t end);
  bool IsOpen(uint32_t p) const { return (words_[p >> 6] >> (p & 63)) & 1u; }
  void Close(uint32_t p) { words_[p >> 6] &= ~(uint64_t(1) << (p & 63)); }
  void Open(uint32_t p) { words_[p >> 6] |= uint64_t(1) << (p & 63); }
  // Keeps a pixel open only if it is open in `other` too.
  void And(const MaskBits& other);
  // Opens the pixels open in `other` (this |= other).
  void Or(const MaskBits& other);
  // Closes the pixels open in `other` (this &= ~other).
  void AndNot(const MaskBits& other);
  void CopyFrom(const MaskBits& other);
  // The cosine-weighted fraction of the hemisphere that is open: the share of
  // a patch's power its open pixels carry. Per ray: the share of rays open.
  double OpenFraction() const;
  uint32_t CountOpen() const;
  // The open pixels among [begin, end).
  uint32_t CountOpen(uint32_t begin, uint32_t end) const;
  // Packing to and from the packet's ceil(bits / 8) bytes (little-endian).
  // With `used`, only the first `used` bits travel (Method R: the shot's
  // rays): Pack writes their bytes (0 past `used` in the last) and leaves
  // the rest of `out` as it was; Unpack reads only their bytes into the
  // words that hold them and leaves later words as they were, so a caller
  // reads only the first `used` bits (OrPrefix, CountOpen(0, used)).
  void Pack(uint8_t* out, uint32_t used = ~0u) const;
  void Unpack(const uint8_t* in, uint32_t used = ~0u);
  // Or over the words that hold pixels [0, used).
  void OrPrefix(const MaskBits& other, uint32_t used);
  Span<uint64_t> words() const { return words_; }

 private:
  Span<uint64_t> words_;
  uint32_t res_ = 0;
  uint32_t bits_ = 0;
};

}  // namespace vismask
