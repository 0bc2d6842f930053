#include "vismask/scene/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/geometric.hpp>

// Texture lookups (texels, the pyramid's levels), uv maps and a patch's
// mean texture; src/scene/texture_decode.cpp reads the files and
// src/scene/texture_scene.cpp a scene's textures.
namespace vismask {

namespace {

// sRGB decoding (IEC 61966-2-1): the files hold encoded values, reflectance
// is linear. Computed in double once, rounded to float.
std::array<float, 256> MakeSrgbTable() {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) {
    double c = i / 255.0;
    t[i] = static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  }
  return t;
}
const std::array<float, 256> kSrgbTable = MakeSrgbTable();

// The points and weights PatchTextureMean integrates with, passed to `f`.
template <class F>
void ForSamples(const Patch& p, int n, F f) {
  const double inv = 1.0 / n;
  if (p.numCorners == 3) {
    // The centroids of the n x n similar sub-triangles: equal areas.
    for (int j = 0; j < n; ++j)
      for (int i = 0; i + j < n; ++i) {
        f(glm::vec2(static_cast<float>((i + 1.0 / 3.0) * inv),
                    static_cast<float>((j + 1.0 / 3.0) * inv)),
          1.0);
        if (i + j + 1 < n)
          f(glm::vec2(static_cast<float>((i + 2.0 / 3.0) * inv),
                      static_cast<float>((j + 2.0 / 3.0) * inv)),
            1.0);
      }
    return;
  }
  // Cell midpoints of an n x n grid in (s, t), weighted by the bilinear
  // map's area element there.
  const glm::dvec3 c0(p.corner[0]), c1(p.corner[1]), c2(p.corner[2]), c3(p.corner[3]),
      nrm(p.normal);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double s = (i + 0.5) * inv, t = (j + 0.5) * inv;
      glm::dvec3 ds = (1 - t) * (c1 - c0) + t * (c2 - c3), dt = (1 - s) * (c3 - c0) + s * (c2 - c1);
      double w = std::max(0.0, glm::dot(nrm, glm::cross(ds, dt)));
      f(glm::vec2(static_cast<float>(s), static_cast<float>(t)), w);
    }
}

}  // namespace

float SrgbToLinear(uint8_t code) {
  return kSrgbTable[code];
}

glm::vec3 Texture::Sample(glm::vec2 uv) const {
  float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
  if (!(u >= 0.0f && u <= 1.0f)) u = 0.0f;  // NaN or infinite
  if (!(v >= 0.0f && v <= 1.0f)) v = 0.0f;
  // Texel centres at (i + 1/2) / width; row 0 is the image's top, v = 1.
  float x = u * static_cast<float>(width) - 0.5f,
        y = (1.0f - v) * static_cast<float>(height) - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);  // -1 .. size - 1
  const int w = static_cast<int>(width), h = static_cast<int>(height);
  uint32_t i0 = static_cast<uint32_t>(x0 < 0 ? w - 1 : x0),
           i1 = static_cast<uint32_t>(x0 + 1 >= w ? 0 : x0 + 1);
  uint32_t j0 = static_cast<uint32_t>(y0 < 0 ? h - 1 : y0),
           j1 = static_cast<uint32_t>(y0 + 1 >= h ? 0 : y0 + 1);
  const uint8_t* r0 = texels + size_t(j0) * width * 3;
  const uint8_t* r1 = texels + size_t(j1) * width * 3;
  glm::vec3 out;
  for (int c = 0; c < 3; ++c) {
    float t00 = kSrgbTable[r0[i0 * 3 + c]], t10 = kSrgbTable[r0[i1 * 3 + c]];
    float t01 = kSrgbTable[r1[i0 * 3 + c]], t11 = kSrgbTable[r1[i1 * 3 + c]];
    out[c] = (1.0f - ay) * ((1.0f - ax) * t00 + ax * t10) + ay * ((1.0f - ax) * t01 + ax * t11);
  }
  return out;
}

TexturePyramid BuildPyramid(const Texture& t) {
  TexturePyramid py;
  const uint32_t w = t.width, h = t.height;
  size_t total = 0;
  for (uint32_t lw = w, lh = h; lw > 1 || lh > 1;) {
    lw = (lw + 1) / 2;
    lh = (lh + 1) / 2;
    TexturePyramid::Level l;
    l.width = lw;
    l.height = lh;
    l.offset = total;
    total += size_t(lw) * lh * 3;
    py.levels.push_back(l);
  }
  py.texels.assign(total, 0.0f);
  // Level k's linear texel (x, y), level 0 being the 8-bit texture.
  auto at = [&](size_t k, uint32_t x, uint32_t y, int c) -> float {
    if (k == 0) return kSrgbTable[t.texels[(size_t(y) * w + x) * 3 + c]];
    const TexturePyramid::Level& l = py.levels[k - 1];
    return py.texels[l.offset + (size_t(y) * l.width + x) * 3 + c];
  };
  for (size_t k = 0; k < py.levels.size(); ++k) {
    const TexturePyramid::Level& l = py.levels[k];
    const uint32_t bw = k == 0 ? w : py.levels[k - 1].width;
    const uint32_t bh = k == 0 ? h : py.levels[k - 1].height;
    for (uint32_t y = 0; y < l.height; ++y)
      for (uint32_t x = 0; x < l.width; ++x) {
        const uint32_t x1 = std::min(2 * x + 1, bw - 1), y1 = std::min(2 * y + 1, bh - 1);
        const float n = static_cast<float>((x1 - 2 * x + 1) * (y1 - 2 * y + 1));
        for (int c = 0; c < 3; ++c) {
          float s = at(k, 2 * x, 2 * y, c);
          if (x1 != 2 * x) s += at(k, x1, 2 * y, c);
          if (y1 != 2 * y) s += at(k, 2 * x, y1, c);
          if (x1 != 2 * x && y1 != 2 * y) s += at(k, x1, y1, c);
          py.texels[l.offset + (size_t(y) * l.width + x) * 3 + c] = s / n;
        }
      }
  }
  return py;
}

glm::vec3 TexturePyramid::Sample(size_t k, glm::vec2 uv) const {
  const Level& l = levels[k - 1];
  float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
  if (!(u >= 0.0f && u <= 1.0f)) u = 0.0f;
  if (!(v >= 0.0f && v <= 1.0f)) v = 0.0f;
  const float x = u * static_cast<float>(l.width) - 0.5f,
              y = (1.0f - v) * static_cast<float>(l.height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const int w = static_cast<int>(l.width), h = static_cast<int>(l.height);
  const size_t i0 = static_cast<size_t>(x0 < 0 ? w - 1 : x0),
               i1 = static_cast<size_t>(x0 + 1 >= w ? 0 : x0 + 1);
  const size_t j0 = static_cast<size_t>(y0 < 0 ? h - 1 : y0),
               j1 = static_cast<size_t>(y0 + 1 >= h ? 0 : y0 + 1);
  const float* r0 = texels.data() + l.offset + j0 * l.width * 3;
  const float* r1 = texels.data() + l.offset + j1 * l.width * 3;
  glm::vec3 out;
  for (int c = 0; c < 3; ++c)
    out[c] = (1.0f - ay) * ((1.0f - ax) * r0[i0 * 3 + c] + ax * r0[i1 * 3 + c]) +
             ay * ((1.0f - ax) * r1[i0 * 3 + c] + ax * r1[i1 * 3 + c]);
  return out;
}

Texture TextureImage::View() const {
  Texture t;
  t.width = width;
  t.height = height;
  t.texels = rgb.data();
  for (int c = 0; c < 3; ++c)
    t.invMean[c] = mean[c] > 0.0 ? static_cast<float>(1.0 / mean[c]) : 0.0f;
  return t;
}

glm::vec2 UvMap::At(const glm::vec3& x) const {
  glm::dvec3 p(x);
  return glm::vec2(static_cast<float>(u.x * p.x + u.y * p.y + u.z * p.z + u.w),
                   static_cast<float>(v.x * p.x + v.y * p.y + v.z * p.z + v.w));
}

UvMap FitUvMap(const Polygon& polygon) {
  UvMap m;
  const size_t n = polygon.corners.size();
  if (polygon.uv.size() != n || n < 3) return m;
  // Least squares in a frame of the plane, about the corners' centroid:
  // u = mean_u + c1 a + c2 b (the same for v).
  glm::dvec3 centroid(0.0);
  glm::dvec2 meanUv(0.0);
  for (size_t k = 0; k < n; ++k) {
    centroid += glm::dvec3(polygon.corners[k]);
    meanUv += glm::dvec2(polygon.uv[k]);
  }
  centroid /= static_cast<double>(n);
  meanUv /= static_cast<double>(n);
  const glm::dvec3 normal(polygon.normal);
  glm::dvec3 e1 = glm::dvec3(polygon.corners[1]) - glm::dvec3(polygon.corners[0]);
  e1 = glm::normalize(e1 - glm::dot(e1, normal) * normal);
  const glm::dvec3 e2 = glm::cross(normal, e1);
  double saa = 0, sab = 0, sbb = 0;
  glm::dvec2 sau(0.0), sbu(0.0);
  for (size_t k = 0; k < n; ++k) {
    glm::dvec3 d = glm::dvec3(polygon.corners[k]) - centroid;
    double a = glm::dot(d, e1), b = glm::dot(d, e2);
    glm::dvec2 w = glm::dvec2(polygon.uv[k]) - meanUv;
    saa += a * a;
    sab += a * b;
    sbb += b * b;
    sau += a * w;
    sbu += b * w;
  }
  double det = saa * sbb - sab * sab;
  if (!(det > 0.0)) return m;  // cannot happen for a loaded (non-degenerate) face
  glm::dvec2 c1 = (sbb * sau - sab * sbu) / det, c2 = (saa * sbu - sab * sau) / det;
  glm::dvec3 gu = c1.x * e1 + c2.x * e2, gv = c1.y * e1 + c2.y * e2;
  m.u = glm::dvec4(gu, meanUv.x - glm::dot(gu, centroid));
  m.v = glm::dvec4(gv, meanUv.y - glm::dot(gv, centroid));
  return m;
}

glm::vec2 PatchUv(const PatchTexture& t, bool triangle, glm::vec2 st) {
  if (triangle) return t.uv[0] + st.x * (t.uv[1] - t.uv[0]) + st.y * (t.uv[2] - t.uv[0]);
  return (1.0f - st.x) * (1.0f - st.y) * t.uv[0] + st.x * (1.0f - st.y) * t.uv[1] +
         st.x * st.y * t.uv[2] + (1.0f - st.x) * st.y * t.uv[3];
}

glm::dvec3 PatchTextureMean(const Texture& texture, const Patch& p, const glm::vec2 uv[4],
                            const TexturePyramid* pyramid, uint64_t* samples) {
  // Two samples a texel along the patch's longest extent in texel units.
  double extent = 0.0;
  for (uint32_t a = 0; a < p.numCorners; ++a)
    for (uint32_t b = a + 1; b < p.numCorners; ++b) {
      glm::vec2 d = uv[a] - uv[b];
      extent = std::max({extent, std::fabs(double(d.x)) * texture.width,
                         std::fabs(double(d.y)) * texture.height});
    }
  int n = 2;
  if (extent > 1.0) n = static_cast<int>(std::min(64.0, std::ceil(2.0 * extent)));
  // With the pyramid: the level where two samples a texel take at most
  // kDirectSamples a side (a patch of fewer keeps the texels themselves).
  size_t level = 0;
  if (pyramid && 2.0 * extent > kDirectSamples) {
    double e = extent;
    while (2.0 * e > kDirectSamples && level < pyramid->levels.size()) {
      e *= 0.5;
      ++level;
    }
    n = std::max(2, static_cast<int>(std::ceil(2.0 * e)));
  }
  PatchTexture t;
  for (int k = 0; k < 4; ++k) t.uv[k] = uv[k];
  const bool triangle = p.numCorners == 3;
  glm::dvec3 sum(0.0);
  double weight = 0.0;
  uint64_t taken = 0;
  ForSamples(p, n, [&](glm::vec2 st, double w) {
    const glm::vec2 at = PatchUv(t, triangle, st);
    sum += w * glm::dvec3(level > 0 ? pyramid->Sample(level, at) : texture.Sample(at));
    weight += w;
    ++taken;
  });
  if (samples) *samples += taken;
  return weight > 0.0 ? sum / weight : glm::dvec3(texture.Sample(uv[0]));
}

}  // namespace vismask
