#include "vismask/solve/outside.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <glm/geometric.hpp>
#include <vector>

#include "vismask/solve/centre_raster.h"

namespace vismask {

namespace {

// The largest radiance or irradiance read: far inside what the float image
// holds after a few bounces (scene.cpp's bound for Ke is 1e30).
constexpr double kMaxLight = 1e20;

// Comma-separated finite numbers, every one read whole.
bool ParseNumbers(const std::string& text, std::vector<double>* out) {
  out->clear();
  size_t start = 0;
  while (true) {
    size_t comma = text.find(',', start);
    std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (part.empty()) return false;
    char* end = nullptr;
    double v = std::strtod(part.c_str(), &end);
    if (end != part.c_str() + part.size() || !std::isfinite(v) || std::fabs(v) > kMaxLight)
      return false;
    out->push_back(v);
    if (comma == std::string::npos) return true;
    start = comma + 1;
  }
}

}  // namespace

bool ParseSky(const std::string& text, OutsideLight* light) {
  std::vector<double> v;
  if (!ParseNumbers(text, &v) || v.size() != 3) return false;
  for (double x : v)
    if (x < 0.0) return false;
  light->sky = glm::vec3(v[0], v[1], v[2]);
  return true;
}

bool ParseSun(const std::string& text, OutsideLight* light) {
  std::vector<double> v;
  if (!ParseNumbers(text, &v) || (v.size() != 6 && v.size() != 7)) return false;
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(len > 1e-30)) return false;
  for (int c = 3; c < 6; ++c)
    if (v[c] < 0.0) return false;
  if (v.size() == 7 && !(v[6] >= 0.0 && v[6] <= 90.0)) return false;
  light->sunToward = glm::vec3(v[0] / len, v[1] / len, v[2] / len);
  light->sun = glm::vec3(v[3], v[4], v[5]);
  if (v.size() == 7) light->sunDegrees = static_cast<float>(v[6]);
  return true;
}

void OutsideShooters(const EnvGrid& grid, int env, const OutsideLight& light, uint32_t tiles,
                     std::vector<OutsideShooter>* out) {
  out->clear();
  if (!light.Any()) return;
  tiles = std::max(1u, std::min(tiles, kMaxOutsideTiles));
  int cell[3];
  grid.Cell(env, cell);
  const Bounds box = grid.EnvBox(env);
  for (int kind = 0; kind < 2; ++kind) {
    if (kind == 0 ? !light.HasSky() : !light.HasSun()) continue;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        if (side == 0 ? cell[axis] != 0 : cell[axis] + 1 != grid.n[axis]) continue;
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        // The sun: E on a surface facing it, the cosine of it on the face
        // (between its light and the inward normal).
        const float inward = side == 0 ? 1.0f : -1.0f;
        const double cosine =
            kind == 0 ? 0.0 : -static_cast<double>(light.sunToward[axis]) * inward;
        if (kind == 1 && !(cosine > 0.0)) continue;
        for (uint32_t j = 0; j < tiles; ++j)
          for (uint32_t i = 0; i < tiles; ++i) {
            // Tile (i, j) of the face, as BoxFace makes a face (facing
            // out), turned to face in.
            Bounds t = box;
            const float w1 = box.hi[a1] - box.lo[a1], w2 = box.hi[a2] - box.lo[a2];
            t.lo[a1] = i == 0 ? box.lo[a1] : box.lo[a1] + w1 * i / tiles;
            t.hi[a1] = i + 1 == tiles ? box.hi[a1] : box.lo[a1] + w1 * (i + 1) / tiles;
            t.lo[a2] = j == 0 ? box.lo[a2] : box.lo[a2] + w2 * j / tiles;
            t.hi[a2] = j + 1 == tiles ? box.hi[a2] : box.lo[a2] + w2 * (j + 1) / tiles;
            const double area = (static_cast<double>(t.hi[a1]) - t.lo[a1]) *
                                (static_cast<double>(t.hi[a2]) - t.lo[a2]);
            if (!(area > 0.0)) continue;
            const Patch face = BoxFace(t, axis, side);
            OutsideShooter s;
            Patch& p = s.patch;
            p = Patch{};
            for (int k = 0; k < 4; ++k) p.corner[k] = face.corner[3 - k];
            p.normal = -face.normal;
            p.area = static_cast<float>(area);
            p.numCorners = 4;
            p.globalId = kOutsideIdBase + (static_cast<uint32_t>(env) << 10) +
                         (static_cast<uint32_t>(8 * kind + 2 * axis + side) << 6) + j * tiles + i;
            // The sky: a uniform radiance L through a plane carries pi L a
            // unit of area.
            for (int c = 0; c < 3; ++c) {
              s.power[c] = kind == 0 ? 3.141592653589793 * light.sky[c] * area
                                     : static_cast<double>(light.sun[c]) * cosine * area;
              p.ke[c] = static_cast<float>(s.power[c] / area);
            }
            out->push_back(s);
          }
      }
  }
}

double OutsidePower(const EnvGrid& grid, const OutsideLight& light, uint32_t tiles) {
  double total = 0.0;
  std::vector<OutsideShooter> s;
  for (int e = 0; e < grid.count(); ++e) {
    OutsideShooters(grid, e, light, tiles, &s);
    for (const OutsideShooter& o : s) total += o.power[0] + o.power[1] + o.power[2];
  }
  return total;
}

glm::vec3 SunRayDirection(const OutsideLight& light, float u1, float u2) {
  const glm::vec3 w = -light.sunToward;
  // A frame about w (Duff et al. 2017, branchless).
  const float sign = std::copysign(1.0f, w.z);
  const float a = -1.0f / (sign + w.z);
  const float b = w.x * w.y * a;
  const glm::vec3 t(1.0f + sign * w.x * w.x * a, sign * b, -sign * w.x);
  const glm::vec3 bt(b, sign + w.y * w.y * a, -w.y);
  const float half = 0.5f * light.sunDegrees * 0.017453292519943295f;
  const float cosMax = std::cos(half);
  const float cosT = 1.0f - u1 * (1.0f - cosMax);
  const float sinT = std::sqrt(std::fmax(0.0f, 1.0f - cosT * cosT));
  const float phi = 6.2831855f * u2;
  return glm::normalize(sinT * std::cos(phi) * t + sinT * std::sin(phi) * bt + cosT * w);
}

}  // namespace vismask
