#include "vismask/solve/patch.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace vismask {

PatchGeom MakePatchGeom(const Patch& p) {
  PatchGeom g{};
  const uint32_t nc = p.numCorners < 4 ? p.numCorners : 4;
  if (nc == 0) return g;
  // The plane, scaled so that its largest component (the first of equal
  // ones) is +1 or -1 exactly. A zero or non-finite normal is kept as it
  // is: no ray hits the patch (IntersectPatch's denom is 0 or NaN).
  int k = 0;
  for (int a = 1; a < 3; ++a)
    if (std::fabs(p.normal[a]) > std::fabs(p.normal[k])) k = a;
  const float s = std::fabs(p.normal[k]);
  g.n = s > 0.0f && std::isfinite(s) ? p.normal / s : p.normal;
  g.d = glm::dot(g.n, p.corner[0]);
  const int i = (k + 1) % 3, j = (k + 2) % 3;

  // The corners in (i, j), counter-clockwise there: the patch's own order
  // when its normal points along +k, reversed when along -k.
  double cu[4], cv[4];
  for (uint32_t m = 0; m < nc; ++m) {
    const uint32_t from = p.normal[k] < 0.0f ? nc - 1 - m : m;
    cu[m] = p.corner[from][i];
    cv[m] = p.corner[from][j];
  }
  // Tolerance: every edge pushed out by a relative widening (as the 3D edge
  // planes of before were: 1e-5 of the patch's size and 4 float steps of
  // the edge line's offset), so that shared edges leave no crack through
  // which a ray could pass between two adjacent patches. A corner moves to
  // where its two edges' moved lines meet; where they nearly run along
  // each other (a straight corner, a needle's tip) it moves along their
  // bisector as far as the larger push, at most 45 times it.
  float size = 0.0f;
  for (uint32_t m = 0; m < nc; ++m)
    size = std::fmax(size, glm::length(p.corner[(m + 1) % nc] - p.corner[m]));
  double out[4][2];  // each edge's outward unit normal, (0, 0) for a point
  double push[4];
  for (uint32_t m = 0; m < nc; ++m) {
    const uint32_t b = (m + 1) % nc;
    const double eu = cu[b] - cu[m], ev = cv[b] - cv[m], len = std::sqrt(eu * eu + ev * ev);
    out[m][0] = len > 0.0 ? ev / len : 0.0;
    out[m][1] = len > 0.0 ? -eu / len : 0.0;
    const double w = out[m][0] * cu[m] + out[m][1] * cv[m];
    push[m] = 1e-5 * size + 4.0 * std::numeric_limits<float>::epsilon() * std::fabs(w);
  }
  for (uint32_t m = 0; m < nc; ++m) {
    const uint32_t prev = (m + nc - 1) % nc;
    const double* a = out[prev];
    const double* b = out[m];
    const double det = a[0] * b[1] - a[1] * b[0];
    const double cosine = a[0] * b[0] + a[1] * b[1];
    double du, dv;
    if (std::fabs(det) > 1e-3 && 1.0 + cosine > 1e-3) {
      // The move with a . move = push[prev] and b . move = push[m].
      du = (push[prev] * b[1] - push[m] * a[1]) / det;
      dv = (a[0] * push[m] - b[0] * push[prev]) / det;
    } else {
      const double w = std::fmax(push[prev], push[m]) / std::fmax(1.0 + cosine, 1e-3);
      du = w * (a[0] + b[0]);
      dv = w * (a[1] + b[1]);
    }
    g.u[m] = static_cast<float>(cu[m] + du);
    g.v[m] = static_cast<float>(cv[m] + dv);
  }
  for (uint32_t m = nc; m < 4; ++m) {
    g.u[m] = g.u[nc - 1];
    g.v[m] = g.v[nc - 1];
  }
  return g;
}

glm::dvec3 GeomCorner(const PatchGeom& g, int m) {
  const int k = PlaneAxis(g.n), i = (k + 1) % 3, j = (k + 2) % 3;
  glm::dvec3 x;
  x[i] = g.u[m];
  x[j] = g.v[m];
  x[k] = (static_cast<double>(g.d) - static_cast<double>(g.n[i]) * x[i] -
          static_cast<double>(g.n[j]) * x[j]) /
         static_cast<double>(g.n[k]);
  return x;
}

}  // namespace vismask
