#include "vismask/solve/element.h"

#include <cmath>
#include <glm/geometric.hpp>

#include "vismask/core/fminmax.h"
#include "vismask/solve/element_tree.h"

namespace vismask {

namespace {

float Cross2(glm::vec2 a, glm::vec2 b) {
  return a.x * b.y - a.y * b.x;
}
float Clamp01(float v) {
  return FMin(FMax(v, 0.0f), 1.0f);
}

}  // namespace

glm::vec2 PatchParam(const Patch& p, const glm::vec3& x) {
  // The patch's plane in 2D: x axis along corner 0 -> 1.
  glm::vec3 e1 = p.corner[1] - p.corner[0];
  glm::vec3 ax = glm::normalize(e1 - glm::dot(e1, p.normal) * p.normal);
  glm::vec3 ay = glm::cross(p.normal, ax);
  auto to2 = [&](const glm::vec3& v) {
    glm::vec3 d = v - p.corner[0];
    return glm::vec2(glm::dot(d, ax), glm::dot(d, ay));
  };
  glm::vec2 h = to2(x), e = to2(p.corner[1]);
  if (p.numCorners == 3) {
    glm::vec2 f = to2(p.corner[2]);
    float det = Cross2(e, f);
    float s = Cross2(h, f) / det, t = Cross2(e, h) / det;
    s = Clamp01(s);
    t = Clamp01(t);
    if (s + t > 1.0f) {
      float k = 1.0f / (s + t);
      s *= k;
      t *= k;
    }
    return glm::vec2(s, t);
  }
  // Inverse bilinear: h = s e + t f + s t g.
  glm::vec2 f = to2(p.corner[3]), g = -e + to2(p.corner[2]) - f;
  float k2 = Cross2(g, f), k1 = Cross2(e, f) + Cross2(h, g), k0 = Cross2(h, e);
  float t;
  if (std::fabs(k2) < 1e-6f * std::fabs(k1)) {
    t = -k0 / k1;
  } else {
    float w = std::sqrt(FMax(k1 * k1 - 4.0f * k0 * k2, 0.0f));
    t = (-k1 - w) / (2.0f * k2);
    if (t < -1e-3f || t > 1.001f) t = (-k1 + w) / (2.0f * k2);
  }
  t = Clamp01(t);
  float den = e.x + g.x * t;
  float s = den != 0.0f ? (h.x - f.x * t) / den : 0.0f;
  return glm::vec2(Clamp01(s), t);
}

glm::vec3 PatchPoint(const Patch& p, glm::vec2 st) {
  if (p.numCorners == 3)
    return p.corner[0] + st.x * (p.corner[1] - p.corner[0]) + st.y * (p.corner[2] - p.corner[0]);
  return (1.0f - st.x) * (1.0f - st.y) * p.corner[0] + st.x * (1.0f - st.y) * p.corner[1] +
         st.x * st.y * p.corner[2] + (1.0f - st.x) * st.y * p.corner[3];
}

glm::vec3 MaskCentre(const Patch& p) {
  if (p.openCells == 0) return CentreOf(p);
  constexpr int kSide = ElementTree::kOpenSide;
  auto centre = [](int cell) {
    return glm::vec2((cell / kSide + 0.5f) / kSide, (cell % kSide + 0.5f) / kSide);
  };
  glm::vec2 mean(0.0f);
  int count = 0;
  for (int cell = 0; cell < kSide * kSide; ++cell)
    if ((p.openCells >> cell) & 1u) mean += centre(cell), ++count;
  mean /= static_cast<float>(count);
  int best = -1;
  float bestD = 0.0f;
  for (int cell = 0; cell < kSide * kSide; ++cell) {
    if (!((p.openCells >> cell) & 1u)) continue;
    const glm::vec2 d = centre(cell) - mean;
    const float d2 = d.x * d.x + d.y * d.y;
    if (best < 0 || d2 < bestD) best = cell, bestD = d2;
  }
  return PatchPoint(p, centre(best));
}

uint32_t ChildOf(bool triangle, glm::vec2* st) {
  float s = st->x, t = st->y;
  if (!triangle) {
    uint32_t ks = s >= 0.5f, kt = t >= 0.5f;
    *st = glm::vec2(2.0f * s - ks, 2.0f * t - kt);
    return ks + 2 * kt;
  }
  if (s >= 0.5f) {
    *st = glm::vec2(2.0f * s - 1.0f, 2.0f * t);
    return 1;
  }
  if (t >= 0.5f) {
    *st = glm::vec2(2.0f * s, 2.0f * t - 1.0f);
    return 2;
  }
  if (s + t < 0.5f) {
    *st = glm::vec2(2.0f * s, 2.0f * t);
    return 0;
  }
  *st = glm::vec2(1.0f - 2.0f * s, 1.0f - 2.0f * t);
  return 3;
}

void ChildCorners(bool triangle, const glm::vec2* in, uint32_t child, glm::vec2* out) {
  if (triangle) {
    glm::vec2 m01 = 0.5f * (in[0] + in[1]), m12 = 0.5f * (in[1] + in[2]),
              m20 = 0.5f * (in[2] + in[0]);
    const glm::vec2 tri[4][3] = {
        {in[0], m01, m20}, {m01, in[1], m12}, {m20, m12, in[2]}, {m12, m20, m01}};
    for (int k = 0; k < 3; ++k) out[k] = tri[child][k];
    return;
  }
  // The bilinear map of the quad's own parameters.
  auto at = [&](float s, float t) {
    return (1.0f - s) * (1.0f - t) * in[0] + s * (1.0f - t) * in[1] + s * t * in[2] +
           (1.0f - s) * t * in[3];
  };
  float s0 = 0.5f * static_cast<float>(child & 1u), t0 = 0.5f * static_cast<float>(child >> 1);
  out[0] = at(s0, t0);
  out[1] = at(s0 + 0.5f, t0);
  out[2] = at(s0 + 0.5f, t0 + 0.5f);
  out[3] = at(s0, t0 + 0.5f);
}

int RootCorners(bool triangle, glm::vec2* out) {
  out[0] = glm::vec2(0.0f, 0.0f);
  out[1] = glm::vec2(1.0f, 0.0f);
  if (triangle) {
    out[2] = glm::vec2(0.0f, 1.0f);
    return 3;
  }
  out[2] = glm::vec2(1.0f, 1.0f);
  out[3] = glm::vec2(0.0f, 1.0f);
  return 4;
}

}  // namespace vismask
