// ElementTree: its layout, reset, descent and splits.
#include "vismask/solve/element_tree.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace vismask {

void ElementTree::Layout(Arena& arena, uint32_t numPatches, const ElementOptions& options,
                         bool indirect) {
  options_ = options;
  elements_ = arena.Alloc<Element>(size_t(numPatches) * (1 + options.perPatch));
  indirect_ = arena.Alloc<double>(indirect ? 3 * size_t(numPatches) * (1 + options.perPatch) : 0);
  indirectQuarter_ =
      arena.Alloc<float>(indirect ? 12 * size_t(numPatches) * (1 + options.perPatch) : 0);
  indirectSquares_ =
      arena.Alloc<double>(indirect ? size_t(numPatches) * (1 + options.perPatch) : 0);
  exposed_ = arena.Alloc<float>(elements_.size());
  open_ = arena.Alloc<uint16_t>(elements_.size());
}

void ElementTree::Reset(Span<const Patch> patches) {
  for (uint32_t i = 0; i < patches.size(); ++i) {
    if (!indirect_.empty()) {
      for (int c = 0; c < 3; ++c) indirect_[3 * i + c] = 0.0;
      for (int k = 0; k < 12; ++k) indirectQuarter_[12 * size_t(i) + k] = 0.0f;
      indirectSquares_[i] = 0.0;
    }
    Element& root = elements_[i];
    root = Element{};
    root.area = patches[i].area;
    root.child = kNoElement;
    exposed_[i] = kUnmeasured;
    open_[i] = 0;
  }
  used_ = static_cast<uint32_t>(patches.size());
}

namespace {

// The quarters' spread beyond noise: chi-square of the power each received
// against an even spread (quarter q expects f_q = area_q / area of the
// total), with variance f_q * (sum of the hits' squared powers).
double QuarterChi2(const double area[4], double areaSum, const double power[4], double total,
                   double squares) {
  double chi2 = 0.0;
  for (uint32_t q = 0; q < 4; ++q) {
    const double f = area[q] / areaSum, expect = f * total;
    chi2 += (power[q] - expect) * (power[q] - expect) / (f * squares);
  }
  return chi2;
}

}  // namespace

ElementTree::Split ElementTree::MaybeSplit(const Patch& p, uint32_t e, const uint8_t* path,
                                           uint32_t depth) {
  Element& el = elements_[e];
  double quarterArea[4];
  QuarterAreas(p, path, depth, quarterArea);
  double areaSum = quarterArea[0] + quarterArea[1] + quarterArea[2] + quarterArea[3];
  double power[4], total = 0.0;
  for (uint32_t q = 0; q < 4; ++q) {
    power[q] = el.quarter[q][0] + el.quarter[q][1] + el.quarter[q][2];
    total += power[q];
  }
  if (!(total > 0.0) || !(el.squares > 0.0)) return Split::kNone;
  // Significant (QuarterChi2), and large: the relative RMS spread of the
  // quarters' densities.
  const double chi2 = QuarterChi2(quarterArea, areaSum, power, total, el.squares);
  double spread = 0.0;
  for (uint32_t q = 0; q < 4; ++q) {
    double f = quarterArea[q] / areaSum, rel = power[q] / (f * total) - 1.0;
    spread += f * rel * rel;
  }
  if (chi2 <= options_.chi2 || std::sqrt(spread) <= options_.threshold) return Split::kNone;
  if (used_ + 4 > elements_.size()) return Split::kRefused;
  uint32_t first = used_;
  used_ += 4;
  for (uint32_t q = 0; q < 4; ++q) {
    Element& ch = elements_[first + q];
    ch = Element{};
    ch.area = static_cast<float>(quarterArea[q] * (el.area / areaSum));
    ch.child = kNoElement;
    ch.depth = el.depth + 1;
    if (!indirect_.empty()) {
      for (int k = 0; k < 12; ++k) indirectQuarter_[12 * size_t(first + q) + k] = 0.0f;
      indirectSquares_[first + q] = 0.0;
    }
    exposed_[first + q] = kUnmeasured;
    open_[first + q] = 0;
    for (int c = 0; c < 3; ++c) {
      double older = el.received[c] -
                     (el.quarter[0][c] + el.quarter[1][c] + el.quarter[2][c] + el.quarter[3][c]);
      ch.received[c] = older * (quarterArea[q] / areaSum) + el.quarter[q][c];
      // The indirect part in the same proportion as the whole.
      if (!indirect_.empty())
        indirect_[3 * size_t(first + q) + c] =
            el.received[c] > 0.0 ? indirect_[3 * size_t(e) + c] * (ch.received[c] / el.received[c])
                                 : 0.0;
    }
  }
  el.child = first;
  return Split::kSplit;
}

void ElementTree::QuarterAreas(const Patch& p, const uint8_t* path, uint32_t depth,
                               double out[4]) const {
  const bool triangle = p.numCorners == 3;
  // The element's corners in the patch's parameters, down its path.
  glm::vec2 corners[4], next[4];
  int n = RootCorners(triangle, corners);
  for (uint32_t d = 0; d < depth; ++d) {
    ChildCorners(triangle, corners, path[d], next);
    for (int k = 0; k < n; ++k) corners[k] = next[k];
  }
  // Each quarter's area, from its corners on the patch.
  for (uint32_t q = 0; q < 4; ++q) {
    ChildCorners(triangle, corners, q, next);
    glm::vec3 w[4];
    for (int k = 0; k < n; ++k) w[k] = PatchPoint(p, next[k]);
    glm::vec3 cr =
        n == 3 ? glm::cross(w[1] - w[0], w[2] - w[0]) : glm::cross(w[2] - w[0], w[3] - w[1]);
    out[q] = 0.5 * glm::length(glm::dvec3(cr));
  }
}

glm::dvec3 ElementTree::CornerShift(const Patch& p, uint32_t e, const uint8_t* path, uint32_t depth,
                                    uint32_t q, double* alpha) const {
  *alpha = 0.0;
  if (indirect_.empty()) return glm::dvec3(0.0);
  const float* s = &indirectQuarter_[12 * size_t(e)];
  double area[4], power[4], total = 0.0;
  QuarterAreas(p, path, depth, area);
  const double areaSum = area[0] + area[1] + area[2] + area[3];
  for (int k = 0; k < 4; ++k) {
    power[k] = double(s[3 * k]) + double(s[3 * k + 1]) + double(s[3 * k + 2]);
    total += power[k];
  }
  const double squares = indirectSquares_[e];
  if (!(total > 0.0) || !(squares > 0.0) || !(areaSum > 0.0)) return glm::dvec3(0.0);
  const double chi2 = QuarterChi2(area, areaSum, power, total, squares);
  if (!(chi2 > kCornerDof)) return glm::dvec3(0.0);
  *alpha = 1.0 - kCornerDof / chi2;
  // Densities over the leaf's own area (its quarters' areas scaled to it).
  const double scale = areaSum / static_cast<double>(elements_[e].area);
  glm::dvec3 shift;
  for (int c = 0; c < 3; ++c) {
    double all = double(s[c]) + double(s[3 + c]) + double(s[6 + c]) + double(s[9 + c]);
    shift[c] = *alpha * (double(s[3 * q + c]) / area[q] - all / areaSum) * scale;
  }
  return shift;
}

uint32_t ElementTree::Descend(bool triangle, uint32_t patch, glm::vec2* st, uint8_t* path,
                              uint32_t* depth) const {
  uint32_t e = patch;
  while (elements_[e].child != kNoElement) {
    uint32_t k = ChildOf(triangle, st);
    if (path) path[(*depth)++] = static_cast<uint8_t>(k);
    e = elements_[e].child + k;
  }
  return e;
}

// The power received under element e, channels summed: its leaves' (an
// inner element keeps what it held when it split, which its children took).
double ElementTree::SubtreePower(uint32_t e) const {
  const Element& el = elements_[e];
  if (el.child == kNoElement) return el.received[0] + el.received[1] + el.received[2];
  double sum = 0.0;
  for (uint32_t k = 0; k < 4; ++k) sum += SubtreePower(el.child + k);
  return sum;
}

void ElementTree::OpenCellsPoint(uint16_t open, float* ua, float* ub) {
  const int count = __builtin_popcount(open);
  const float x = *ua * static_cast<float>(count);
  int pick = std::min(static_cast<int>(x), count - 1), cell = 0;
  for (int seen = -1; cell < kOpenSide * kOpenSide; ++cell)
    if (((open >> cell) & 1u) && ++seen == pick) break;
  const float within = std::min(std::max(x - static_cast<float>(pick), 0.0f), 1.0f);
  *ua = std::min(std::max((static_cast<float>(cell / kOpenSide) + within) / kOpenSide, kMargin),
                 1.0f - kMargin);
  *ub = std::min(std::max((static_cast<float>(cell % kOpenSide) + *ub) / kOpenSide, kMargin),
                 1.0f - kMargin);
}

static_assert(ElementTree::kOpenSide * ElementTree::kOpenSide == 16, "QuarterOrigins::cdf");

namespace {

// The point at (a, b) of the uniforms in the leaf with `corners` (a quad's
// bilinear parameters; a triangle's, square-root warped), a hair inside it
// (PatchSampler::Point's margin).
glm::vec2 PointInLeaf(bool triangle, const glm::vec2* corners, float a, float b) {
  a = std::min(std::max(a, ElementTree::kMargin), 1.0f - ElementTree::kMargin);
  b = std::min(std::max(b, ElementTree::kMargin), 1.0f - ElementTree::kMargin);
  if (triangle) {
    const float su = std::sqrt(a);
    return corners[0] + su * (1.0f - b) * (corners[1] - corners[0]) +
           su * b * (corners[2] - corners[0]);
  }
  return corners[0] + a * (corners[1] - corners[0]) + b * (corners[3] - corners[0]);
}

}  // namespace

bool ElementTree::MakeQuarterOrigins(bool triangle, uint32_t patch, QuarterOrigins* out) const {
  const Element& el = elements_[patch];
  if (el.child != kNoElement || el.hits < kQuarterHits) return false;
  double q[4], total = 0.0;
  for (int k = 0; k < 4; ++k)
    total += q[k] = el.quarter[k][0] + el.quarter[k][1] + el.quarter[k][2];
  if (!(total > 0.0)) return false;
  for (double& v : q) v += kQuarterPrior * total / (4.0 * el.hits);
  double w[16], sum = 0.0;
  out->triangle = triangle;
  if (triangle) {
    out->count = 4;
    for (int k = 0; k < 4; ++k) sum += w[k] = q[k];
  } else {
    // A cell's share: its quarter's power over the quarter's open cells
    // (all, unless the leaf is part buried).
    const uint16_t open = PartBuried(false, patch) ? open_[patch] : uint16_t{0xffff};
    auto quarterOf = [](int cell) {
      return (cell / kOpenSide >= kOpenSide / 2) + 2 * (cell % kOpenSide >= kOpenSide / 2);
    };
    int inQuarter[4] = {0, 0, 0, 0};
    for (int cell = 0; cell < 16; ++cell) inQuarter[quarterOf(cell)] += (open >> cell) & 1u;
    out->count = 16;
    for (int cell = 0; cell < 16; ++cell)
      sum += w[cell] =
          ((open >> cell) & 1u) ? q[quarterOf(cell)] / inQuarter[quarterOf(cell)] : 0.0;
  }
  double below = 0.0;
  for (int k = 0; k < out->count; ++k) out->cdf[k] = static_cast<float>((below += w[k]) / sum);
  out->cdf[out->count - 1] = 1.0f;
  return true;
}

glm::vec2 ElementTree::QuarterOrigins::Point(const float u[3]) const {
  int k = 0;
  while (k < count - 1 && u[0] >= cdf[k]) ++k;
  while (k > 0 && !(cdf[k] > cdf[k - 1])) --k;  // never a cell that sends nothing
  // Entry k's corners: a triangle's child k; a quad's cell k (a = k /
  // kOpenSide along the first edge, b = k % kOpenSide along the last).
  glm::vec2 c[4];
  if (triangle) {
    glm::vec2 root[4];
    RootCorners(true, root);
    ChildCorners(true, root, static_cast<uint32_t>(k), c);
  } else {
    const float side = 1.0f / kOpenSide;
    const glm::vec2 lo(static_cast<float>(k / kOpenSide) * side,
                       static_cast<float>(k % kOpenSide) * side);
    c[0] = lo, c[1] = lo + glm::vec2(side, 0.0f), c[2] = lo + glm::vec2(side),
    c[3] = lo + glm::vec2(0.0f, side);
  }
  return PointInLeaf(triangle, c, u[1], u[2]);
}

bool ElementTree::SampleByPower(bool triangle, uint32_t patch, const float u[3],
                                glm::vec2* st) const {
  uint32_t e = patch;
  if (elements_[e].child == kNoElement && !PartBuried(triangle, e)) return false;
  glm::vec2 corners[4];
  int n = RootCorners(triangle, corners);
  // Down the tree: a child in proportion to the power under it, u[0]
  // stretched back to [0, 1) within the child's share.
  double x = u[0];
  while (elements_[e].child != kNoElement) {
    double power[4], total = 0.0;
    for (uint32_t k = 0; k < 4; ++k) total += power[k] = SubtreePower(elements_[e].child + k);
    if (!(total > 0.0)) return false;
    uint32_t k = 0;
    double below = 0.0;
    while (k < 3 && x * total >= below + power[k]) below += power[k++];
    while (!(power[k] > 0.0)) --k;  // rounding past the last child with power
    x = std::min(std::max((x * total - below) / power[k], 0.0), 1.0);
    glm::vec2 child[4];
    ChildCorners(triangle, corners, k, child);
    for (int c = 0; c < n; ++c) corners[c] = child[c];
    e = elements_[e].child + k;
  }
  // Uniform in the leaf (PointInLeaf); part buried, in its open cells (u[1]
  // picks one and is stretched back).
  float ua = u[1], ub = u[2];
  if (PartBuried(triangle, e)) OpenCellsPoint(open_[e], &ua, &ub);
  *st = PointInLeaf(triangle, corners, ua, ub);
  return true;
}

}  // namespace vismask
