#include "vismask/solve/mask.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "vismask/core/enum_name.h"
#include "vismask/core/fast_trig.h"

namespace vismask {

namespace {
constexpr double kHalfPi = 1.5707963267948966;
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

const char* MaskMethodName(MaskMethod m) {
  static constexpr const char* kNames[] = {"none", "A", "B", "C", "R"};
  return EnumName<MaskMethod::kR>(m, kNames);
}

const char* CentreChoiceName(CentreChoice c) {
  static constexpr const char* kNames[] = {"all", "read", "auto"};
  return EnumName<CentreChoice::kAuto>(c, kNames);
}

MaskShape MaskShapeOf(MaskMethod m, uint32_t maskRes, uint32_t rays) {
  switch (m) {
    case MaskMethod::kNone:
      return MaskShape{};
    case MaskMethod::kR:
      return MaskShape{0, rays};
    default:
      return MaskShape{maskRes, 0};
  }
}

namespace {
// Whether x (>= 0) lies within tol of an integer.
bool NearInteger(double x, double tol) {
  double f = x - static_cast<double>(static_cast<uint64_t>(x));
  return f <= tol || f >= 1.0 - tol;
}
}  // namespace

uint32_t MaskPixel(const glm::vec3& d, uint32_t res) {
  float z = d.z < 0.0f ? 0.0f : (d.z > 1.0f ? 1.0f : d.z);
  // The angles by FastAcos and FastAtan2, and by libm's acos and atan2 only
  // where the fast ones fall within their error of a row or column edge:
  // the same pixel as libm's everywhere (tests/mask_test.cpp), at a
  // fraction of the cost.
  const double tol = 4.0 * kTrigError * res;
  double rowAt = FastAcos(static_cast<double>(z)) / kHalfPi * res;
  if (NearInteger(rowAt, tol)) rowAt = std::acos(static_cast<double>(z)) / kHalfPi * res;
  double phi = FastAtan2(static_cast<double>(d.y), static_cast<double>(d.x));
  if (phi < 0.0) phi += kTwoPi;
  double colAt = phi / kTwoPi * (4 * res);
  if (NearInteger(colAt, tol)) {
    phi = std::atan2(static_cast<double>(d.y), static_cast<double>(d.x));
    if (phi < 0.0) phi += kTwoPi;
    colAt = phi / kTwoPi * (4 * res);
  }
  uint32_t row = static_cast<uint32_t>(rowAt);
  uint32_t col = static_cast<uint32_t>(colAt);
  if (row >= res) row = res - 1;
  if (col >= 4 * res) col = 4 * res - 1;
  return row * 4 * res + col;
}

glm::vec3 MaskPixelCentre(uint32_t pixel, uint32_t res) {
  uint32_t row = pixel / (4 * res), col = pixel % (4 * res);
  double theta = (row + 0.5) * kHalfPi / res;
  double phi = (col + 0.5) * kTwoPi / (4 * res);
  double s = std::sin(theta);
  return glm::vec3(static_cast<float>(s * std::cos(phi)), static_cast<float>(s * std::sin(phi)),
                   static_cast<float>(std::cos(theta)));
}

namespace {
// The smallest power of two >= n.
uint32_t PowerOfTwo(uint32_t n) {
  uint32_t p = 1;
  while (p < n) p *= 2;
  return p;
}
// How far (z, or p) a direction must be from an edge for the tables to
// decide its pixel: far above the double rounding in MaskPixel (~1e-15 rad)
// and in the edges (~1e-15). |dz/dtheta| and |dp/dphi| are <= 1, so a
// margin in z or p is at least as much in angle.
constexpr double kEdgeMargin = 1e-10;
// How far (radians) 2 pi u2 must be from a column edge for CosinePixel to
// take its column. CosineDirection forms phi = 6.2831855f * u2 (within
// 1.8e-7 u2 + 2.4e-7 of 2 pi u2: the float constant and one rounding), and
// x = r cosf(phi), y = r sinf(phi) (each within about two float ulps of r,
// so their angle within about 2e-7 of phi): under 7e-7 in all, and the
// margin is 14 times that, and sends few rays to Pixel.
constexpr double kSampleAngleMargin = 1e-5;
}  // namespace

void MaskDirections::Layout(Arena& arena, uint32_t res) {
  res_ = res;
  rowSin_ = arena.Alloc<double>(res);
  rowCos_ = arena.Alloc<double>(res);
  colCos_ = arena.Alloc<double>(size_t(4) * res);
  colSin_ = arena.Alloc<double>(size_t(4) * res);
  // Eight z bins a row and two p bins a column: at most one edge a bin,
  // but the rows within 0.06 rad of the normal (few cosine rays).
  rowBins_ = res > 0 ? PowerOfTwo(8 * res) : 0;
  colBins_ = res > 0 ? PowerOfTwo(2 * res) : 0;
  rowScale_ = rowBins_;
  colScale_ = colBins_;
  columns_ = 4.0 * res;
  columnMargin_ = kSampleAngleMargin * columns_ / kTwoPi;
  rowEdge_ = arena.Alloc<double>(res > 0 ? res + 1 : 0);
  rowBin_ = arena.Alloc<uint32_t>(res > 0 ? rowBins_ + 1 : 0);
  colEdge_ = arena.Alloc<double>(res > 0 ? res + 2 : 0);
  colBin_ = arena.Alloc<uint32_t>(res > 0 ? colBins_ + 1 : 0);
}

void MaskDirections::Fill() {
  // The angles exactly as MaskPixelCentre forms them.
  for (uint32_t row = 0; row < res_; ++row) {
    double theta = (row + 0.5) * kHalfPi / res_;
    rowSin_[row] = std::sin(theta);
    rowCos_[row] = std::cos(theta);
  }
  for (uint32_t col = 0; col < 4 * res_; ++col) {
    double phi = (col + 0.5) * kTwoPi / (4 * res_);
    colCos_[col] = std::cos(phi);
    colSin_[col] = std::sin(phi);
  }
  if (res_ == 0) return;
  // Pixel's edges, with stops at both ends.
  for (uint32_t k = 1; k < res_; ++k) {
    double a = k * kHalfPi / res_;
    rowEdge_[k] = std::cos(a);
    colEdge_[k] = std::sin(a) / (std::sin(a) + std::cos(a));
  }
  rowEdge_[0] = 2.0;
  rowEdge_[res_] = -1.0;
  colEdge_[0] = 0.0;
  colEdge_[res_] = 1.0;
  colEdge_[res_ + 1] = 2.0;
  // Bin b's first row: the edges at or above z = (b + 1) / rowBins_.
  uint32_t k = res_ - 1;
  for (uint32_t b = 0; b <= rowBins_; ++b) {
    double top = static_cast<double>(b + 1) / rowBins_;
    while (k > 0 && rowEdge_[k] < top) --k;
    rowBin_[b] = k;
  }
  // Bin b's first column: the edges at or below p = b / colBins_.
  uint32_t j = 0;
  for (uint32_t b = 0; b <= colBins_; ++b) {
    double bottom = static_cast<double>(b) / colBins_;
    while (j + 1 < res_ && colEdge_[j + 1] <= bottom) ++j;
    colBin_[b] = j;
  }
}

inline uint32_t MaskDirections::RowOf(float dz, bool* clear) const {
  const double z = dz < 0.0f ? 0.0 : (dz > 1.0f ? 1.0 : static_cast<double>(dz));
  // From its bin's first row, one edge on at most.
  uint32_t row = rowBin_[static_cast<uint32_t>(z * rowScale_)];
  row += rowEdge_[row + 1] > z;
  *clear = (rowEdge_[row] - z > kEdgeMargin) & (z - rowEdge_[row + 1] > kEdgeMargin);
  return row;
}

uint32_t MaskDirections::Pixel(const glm::vec3& d) const {
  const double x = d.x, y = d.y;
  // The quadrant, and (x, y) turned into the first: (a, b).
  double a, b;
  uint32_t quadrant;
  if (y > 0.0) {
    quadrant = x > 0.0 ? 0 : 1;
    a = x > 0.0 ? x : y;
    b = x > 0.0 ? y : -x;
  } else {
    quadrant = x < 0.0 ? 2 : 3;
    a = x < 0.0 ? -x : -y;
    b = x < 0.0 ? -y : x;
  }
  // On an axis (a or b is 0, exactly: floats' product; or NaN): a column edge.
  if (!(a * b > 0.0)) return MaskPixel(d, res_);
  const double p = b / (a + b);
  // Each from its bin's first, one edge on at most.
  bool rowClear;
  const uint32_t row = RowOf(d.z, &rowClear);
  uint32_t col = colBin_[static_cast<uint32_t>(p * colScale_)];
  col += colEdge_[col + 1] <= p;
  // Clear of all four edges by the margin: the pixel; else MaskPixel's.
  const bool clear =
      rowClear & (p - colEdge_[col] > kEdgeMargin) & (colEdge_[col + 1] - p > kEdgeMargin);
  if (!clear) return MaskPixel(d, res_);
  return (row * 4 + quadrant) * res_ + col;
}

uint32_t MaskDirections::CosinePixel(float u2, const glm::vec3& d) const {
  if (!(u2 >= 0.0f && u2 < 1.0f)) return Pixel(d);
  bool rowClear;
  const uint32_t row = RowOf(d.z, &rowClear);
  const double c = static_cast<double>(u2) * columns_;  // exact: u2 has 24 bits, 4R is small
  const uint32_t col = static_cast<uint32_t>(c);
  const double f = c - col;
  const bool clear = rowClear & (f > columnMargin_) & (f < 1.0 - columnMargin_) &
                     (std::fabs(d.x) + std::fabs(d.y) > 1e-6f);
  if (!clear) return Pixel(d);
  return row * 4 * res_ + col;
}

void MaskBits::SetAllOpen() {
  for (size_t w = 0; w < words_.size(); ++w) words_[w] = ~uint64_t(0);
  if (bits_ % 64) words_[words_.size() - 1] = (uint64_t(1) << (bits_ % 64)) - 1;
}

void MaskBits::SetAllClosed() {
  for (size_t w = 0; w < words_.size(); ++w) words_[w] = 0;
}

void MaskBits::ClosePrefix(uint32_t end) {
  const size_t words = std::min<size_t>(words_.size(), (size_t(end) + 63) / 64);
  for (size_t w = 0; w < words; ++w) words_[w] = 0;
}

void MaskBits::CloseFrom(uint32_t begin) {
  size_t w = begin >> 6;
  if (w >= words_.size()) return;
  if (begin & 63) words_[w++] &= (uint64_t(1) << (begin & 63)) - 1;
  for (; w < words_.size(); ++w) words_[w] = 0;
}

void MaskBits::And(const MaskBits& other) {
  DCHECK(other.words_.size() == words_.size());
  for (size_t w = 0; w < words_.size(); ++w) words_[w] &= other.words_[w];
}

void MaskBits::Or(const MaskBits& other) {
  DCHECK(other.words_.size() == words_.size());
  for (size_t w = 0; w < words_.size(); ++w) words_[w] |= other.words_[w];
}

void MaskBits::AndNot(const MaskBits& other) {
  DCHECK(other.words_.size() == words_.size());
  for (size_t w = 0; w < words_.size(); ++w) words_[w] &= ~other.words_[w];
}

void MaskBits::CopyFrom(const MaskBits& other) {
  DCHECK(other.words_.size() == words_.size());
  for (size_t w = 0; w < words_.size(); ++w) words_[w] = other.words_[w];
}

double MaskBits::OpenFraction() const {
  if (res_ == 0) return bits_ > 0 ? static_cast<double>(CountOpen()) / bits_ : 0.0;
  // Row i spans theta in [i, i+1) * (pi/2) / R; its cosine-weighted share of
  // the hemisphere is sin^2(theta1) - sin^2(theta0), split over 4R pixels.
  double total = 0.0;
  uint32_t cols = 4 * res_;
  for (uint32_t row = 0; row < res_; ++row) {
    double s0 = std::sin(row * kHalfPi / res_), s1 = std::sin((row + 1) * kHalfPi / res_);
    uint32_t open = CountOpen(row * cols, (row + 1) * cols);
    total += (s1 * s1 - s0 * s0) * open / cols;
  }
  return total;
}

uint32_t MaskBits::CountOpen(uint32_t begin, uint32_t end) const {
  uint32_t n = 0;
  while (begin < end) {
    uint32_t w = begin >> 6, lo = begin & 63;
    uint32_t hi = std::min<uint32_t>(64, lo + (end - begin));  // bits [lo, hi) of word w
    uint64_t word = words_[w] >> lo;
    if (hi - lo < 64) word &= (uint64_t(1) << (hi - lo)) - 1;
    n += PopCount(word);
    begin += hi - lo;
  }
  return n;
}

uint32_t MaskBits::CountOpen() const {
  uint32_t n = 0;
  for (uint64_t w : words_) n += PopCount(w);
  return n;
}

void MaskBits::Pack(uint8_t* out, uint32_t used) const {
  const uint32_t usedBytes = (std::min(used, bits_) + 7) / 8;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  // The words' bytes are the packet's bytes, lowest first.
  std::memcpy(out, words_.data(), usedBytes);
#else
  for (uint32_t b = 0; b < usedBytes; ++b)
    out[b] = static_cast<uint8_t>(words_[b >> 3] >> (8 * (b & 7)));
#endif
  // The bits past `used` in its last byte are 0; the bytes past it are left
  // as they were (no receiver reads them: Unpack with the same `used`).
  if (usedBytes > 0 && used < bits_ && used % 8) out[usedBytes - 1] &= (1u << (used % 8)) - 1;
}

void MaskBits::Unpack(const uint8_t* in, uint32_t used) {
  const uint32_t usedBytes = (std::min(used, bits_) + 7) / 8;
  // The words that hold the used bits start at 0 (the rest are left alone).
  const size_t usedWords =
      std::min<size_t>(words_.size(), (size_t(std::min(used, bits_)) + 63) / 64);
  for (size_t w = 0; w < usedWords; ++w) words_[w] = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::memcpy(words_.data(), in, usedBytes);
#else
  for (uint32_t b = 0; b < usedBytes; ++b) words_[b >> 3] |= uint64_t(in[b]) << (8 * (b & 7));
#endif
  if (used < bits_) {
    // Only the first `used` bits come from the packet; the rest of their
    // last word is closed.
    const uint32_t w = used >> 6;
    if (w < words_.size() && (used & 63)) words_[w] &= (uint64_t(1) << (used & 63)) - 1;
  }
}

void MaskBits::OrPrefix(const MaskBits& other, uint32_t used) {
  const size_t words = std::min<size_t>(words_.size(), (size_t(used) + 63) / 64);
  for (size_t w = 0; w < words; ++w) words_[w] |= other.words_[w];
}

}  // namespace vismask
