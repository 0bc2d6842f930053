#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "../scene/geometry_util.h"
#include "vismask/core/check.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/partition.h"

// The grid of environments (partition.h): its boxes and planes, its shape
// (--envs), and balanced planes from the polygons' estimated patches
// (WorkSplitter); src/solve/partition.cpp cuts the scene along them.
namespace vismask {

Bounds EnvGrid::EnvBox(int index) const {
  CHECK(0 <= index && index < count());
  int c[3];
  Cell(index, c);
  Bounds b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = Plane(a, c[a]);
    b.hi[a] = Plane(a, c[a] + 1);
  }
  return b;
}

float EnvGrid::Plane(int axis, int k) const {
  CHECK(0 <= axis && axis < 3 && 0 <= k && k <= n[axis]);
  if (k == 0) return box.lo[axis];
  if (k == n[axis]) return box.hi[axis];
  if (balanced) return cut[axis][k];
  const float lo = box.lo[axis], hi = box.hi[axis];
  return lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n[axis]);
}

bool ParseEnvGrid(const char* text, int n[3]) {
  if (text == nullptr) return false;
  int parsed[3] = {1, 1, 1};
  int count = 0;
  const char* s = text;
  for (;;) {
    if (count == 3) return false;
    if (*s < '1' || *s > '9') return false;  // no sign, space, or leading zero
    int value = 0;
    for (; *s >= '0' && *s <= '9'; ++s) {
      value = value * 10 + (*s - '0');
      if (value > kMaxEnvsPerAxis) return false;
    }
    parsed[count++] = value;
    if (*s == '\0') break;
    if (*s++ != 'x') return false;
  }
  std::copy(parsed, parsed + 3, n);
  return true;
}

bool ChooseEnvShape(int count, const glm::vec3& extent, int n[3]) {
  bool found = false;
  double best = 0.0;
  for (int nx = 1; nx <= std::min(count, kMaxEnvsPerAxis); ++nx) {
    if (count % nx) continue;
    for (int ny = 1; ny <= std::min(count / nx, kMaxEnvsPerAxis); ++ny) {
      if ((count / nx) % ny) continue;
      int nz = count / nx / ny;
      if (nz > kMaxEnvsPerAxis) continue;
      const int m[3] = {nx, ny, nz};
      double area = 0.0;
      bool flat = false;
      for (int a = 0; a < 3; ++a) {
        if (m[a] > 1 && !(extent[a] > 0.0f)) flat = true;
        area += (m[a] - 1) * static_cast<double>(extent[(a + 1) % 3]) * extent[(a + 2) % 3];
      }
      if (flat || (found && !(area < best))) continue;
      found = true;
      best = area;
      std::copy(m, m + 3, n);
    }
  }
  return found;
}

double EstimatedPatches(const glm::vec3* c, int n, float patchSize) {
  CHECK(n >= 3 && patchSize > 0.0f);
  auto cells = [&](int i, int j) {
    double len = glm::length(glm::dvec3(c[j]) - glm::dvec3(c[i]));
    return EdgeDivisions(len, patchSize);
  };
  if (n == 4) {
    const glm::dvec3 q[4] = {glm::dvec3(c[0]), glm::dvec3(c[1]), glm::dvec3(c[2]),
                             glm::dvec3(c[3])};
    double m = 0.0, k = 0.0;
    QuadDivisions(q, patchSize, &m, &k);
    return m * k;
  }
  double longest = 1.0;
  for (int i = 0; i < n; ++i) longest = std::max(longest, cells(i, (i + 1) % n));
  if (n > 4) {
    // A convex polygon of many corners that MeshScene cuts in strips: their
    // count (the sliver estimate would be far too high).
    std::vector<glm::dvec3> d(c, c + n);
    const glm::dvec3 newell = NewellSum(d);
    Polygon poly;
    poly.corners.assign(c, c + n);
    poly.area = 0.5 * glm::length(newell);
    if (poly.area > 0.0) {
      poly.normal = glm::vec3(newell / glm::length(newell));
      double patches = 0.0, vertices = 0.0;
      bool strips = false;
      if (CountPolygonPatches("", poly, patchSize, &patches, &vertices, &strips).ok() && strips)
        return patches;
    }
  }
  return (n - 2) * longest * longest;
}

WorkSplitter::WorkSplitter() {
  for (Axis& a : axis_) a.bins.assign(kBins, 0.0);
}

// Widens axis `a` until [lo, hi] lies inside its bins: each doubling merges
// the bins pairwise into one half, growing towards the side that is short.
void WorkSplitter::Cover(Axis* a, double lo, double hi, double scale) {
  if (a->width == 0.0) {
    // The first polygon: its extent (or, flat on this axis, its size) spans
    // a quarter of the bins, so later polygons rarely force a doubling.
    double span = std::max(hi - lo, scale);
    a->width = 4.0 * span / kBins;
    a->lo = lo - 1.5 * span;
  }
  while (lo < a->lo || hi >= a->lo + a->width * kBins) {
    std::vector<double>& b = a->bins;
    const int half = kBins / 2;
    if (lo < a->lo) {  // grow down: the old bins become the upper half
      for (int j = kBins - 1; j >= half; --j) b[j] = b[2 * (j - half)] + b[2 * (j - half) + 1];
      for (int j = 0; j < half; ++j) b[j] = 0.0;
      a->lo -= a->width * kBins;
    } else {  // grow up: the lower half
      for (int j = 0; j < half; ++j) b[j] = b[2 * j] + b[2 * j + 1];
      for (int j = half; j < kBins; ++j) b[j] = 0.0;
    }
    a->width *= 2.0;
  }
}

void WorkSplitter::Add(const glm::vec3* corners, int n, double area, double weight) {
  CHECK(n >= 3);
  if (!(weight > 0.0) || !(area > 0.0)) return;
  glm::dvec3 lo(corners[0]), hi(corners[0]);
  for (int i = 1; i < n; ++i) {
    lo = glm::min(lo, glm::dvec3(corners[i]));
    hi = glm::max(hi, glm::dvec3(corners[i]));
  }
  const double scale = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, std::sqrt(area)});
  for (int k = 0; k < 3; ++k) {
    Axis& a = axis_[k];
    Cover(&a, lo[k], hi[k], scale);
    double x0 = (lo[k] - a.lo) / a.width, x1 = (hi[k] - a.lo) / a.width;
    int b0 = std::min(kBins - 1, static_cast<int>(x0)),
        b1 = std::min(kBins - 1, static_cast<int>(x1));
    if (b0 == b1) {
      a.bins[b0] += weight;
      continue;
    }
    // Evenly over [x0, x1]: each bin its share of the length.
    const double density = weight / (x1 - x0);
    for (int b = b0; b <= b1; ++b) {
      double from = std::max(x0, static_cast<double>(b)),
             to = std::min(x1, static_cast<double>(b + 1));
      if (to > from) a.bins[b] += density * (to - from);
    }
  }
  total_ += weight;
  ++count_;
}

std::vector<double> WorkSplitter::PlanesOf(int axis, int n, float boxLo, float boxHi) const {
  const Axis& a = axis_[axis];
  if (n <= 1 || a.width == 0.0 || !(boxHi > boxLo)) return {};
  // Edges e (0..kBins) strictly inside the box, and the weight below each.
  std::vector<double> below(kBins + 1, 0.0);
  for (int b = 0; b < kBins; ++b) below[b + 1] = below[b] + a.bins[b];
  const double total = below[kBins];
  if (!(total > 0.0)) return {};
  auto at = [&](int e) { return static_cast<float>(a.lo + a.width * e); };
  int eMin = 0, eMax = kBins;
  while (eMin <= kBins && !(at(eMin) > boxLo)) ++eMin;
  while (eMax >= 0 && !(at(eMax) < boxHi)) --eMax;
  std::vector<double> planes;
  int prev = eMin - 1;
  for (int k = 1; k < n; ++k) {
    const double target = total * k / n;
    // Leave room for the planes still to come.
    const int first = prev + 1, last = eMax - (n - 1 - k);
    if (first > last) return {};
    double bestDist = 0.0;
    int bestFrom = -1, bestTo = -1;
    for (int e = first; e <= last; ++e) {
      double d = std::fabs(below[e] - target);
      if (bestFrom < 0 || d < bestDist) {
        bestDist = d;
        bestFrom = bestTo = e;
      } else if (d == bestDist && bestTo == e - 1) {
        bestTo = e;  // a run of equally near edges (an empty stretch)
      }
    }
    int e = bestFrom + (bestTo - bestFrom) / 2;
    if (!planes.empty() && !(at(e) > static_cast<float>(planes.back()))) return {};
    planes.push_back(at(e));
    prev = e;
  }
  return planes;
}

void WorkSplitter::Planes(EnvGrid* grid) const {
  grid->balanced = true;
  for (int axis = 0; axis < 3; ++axis) {
    const int n = grid->n[axis];
    CHECK(1 <= n && n <= kMaxEnvsPerAxis);
    std::vector<double> planes = PlanesOf(axis, n, grid->box.lo[axis], grid->box.hi[axis]);
    for (int k = 0; k <= n; ++k) grid->cut[axis][k] = 0.0f;
    for (int k = 1; k < n; ++k) {
      const float lo = grid->box.lo[axis], hi = grid->box.hi[axis];
      grid->cut[axis][k] = planes.empty()
                               ? lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n)
                               : static_cast<float>(planes[k - 1]);
    }
    grid->cut[axis][0] = grid->box.lo[axis];
    grid->cut[axis][n] = grid->box.hi[axis];
  }
}

}  // namespace vismask
