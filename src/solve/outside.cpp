#include "vismask/solve/outside.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
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
  auto endsWith = [&](const char* tail) {
    const size_t n = std::strlen(tail);
    if (text.size() < n) return false;
    for (size_t k = 0; k < n; ++k)
      if (std::tolower(static_cast<unsigned char>(text[text.size() - n + k])) != tail[k])
        return false;
    return true;
  };
  if (text.find('/') != std::string::npos || endsWith(".hdr") || endsWith(".pic")) {
    light->skyFile = text;
    light->sky = glm::vec3(0.0f);
    return true;
  }
  std::vector<double> v;
  if (!ParseNumbers(text, &v) || v.size() != 3) return false;
  for (double x : v)
    if (x < 0.0) return false;
  light->sky = glm::vec3(v[0], v[1], v[2]);
  light->skyFile.clear();
  light->skyMap.reset();
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
            // unit of area; a map, its integral over the sky this face
            // sees (SkyMap::crossing).
            const SkyMap* map = light.skyMap.get();
            for (int c = 0; c < 3; ++c) {
              s.power[c] = kind == 1 ? static_cast<double>(light.sun[c]) * cosine * area
                           : map     ? map->crossing[2 * axis + side][c] * area
                                     : 3.141592653589793 * light.sky[c] * area;
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

namespace {

constexpr double kPi = 3.141592653589793;

// The integral of max(0, f(phi)) over [a, b] within [-pi, pi], f = cos
// (axis 0) or sin (axis 2) times `sign`, piece by piece where f keeps its sign.
double AzimuthIntegral(double a, double b, int axis, double sign) {
  const double cuts[5] = {-kPi, -0.5 * kPi, 0.0, 0.5 * kPi, kPi};
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double lo = std::max(a, cuts[k]), hi = std::min(b, cuts[k + 1]);
    if (!(hi > lo)) continue;
    const double mid = 0.5 * (cuts[k] + cuts[k + 1]);
    const double f = sign * (axis == 0 ? std::cos(mid) : std::sin(mid));
    if (f <= 0.0) continue;
    // The antiderivative of sign * cos is sign * sin, of sign * sin is -sign * cos.
    sum += axis == 0 ? sign * (std::sin(hi) - std::sin(lo)) : -sign * (std::cos(hi) - std::cos(lo));
  }
  return sum;
}

}  // namespace

glm::vec3 SkyMap::Radiance(const glm::vec3& w) const {
  const double len = std::sqrt(double(w.x) * w.x + double(w.y) * w.y + double(w.z) * w.z);
  if (!(len > 0.0) || width == 0 || height == 0) return glm::vec3(0.0f);
  const double phi = std::atan2(double(w.z), double(w.x));  // -pi .. pi, 0 along +X
  const double el = std::asin(std::max(-1.0, std::min(1.0, w.y / len)));
  const double fx = (phi + kPi) / (2.0 * kPi) * width, fy = (0.5 * kPi - el) / kPi * height;
  const uint32_t i = static_cast<uint32_t>(std::min<double>(std::max(0.0, fx), width - 1));
  const uint32_t j = static_cast<uint32_t>(std::min<double>(std::max(0.0, fy), height - 1));
  const float* t = texels.data() + (size_t(j) * width + i) * 3;
  return glm::vec3(t[0], t[1], t[2]);
}

void SkyMap::Integrate() {
  // Each face's integral as pi (the cosine's over a hemisphere) times the
  // map's weighted mean over it, that mean taken about the first texel: a
  // uniform map's is then exactly its value, and --sky FILE.hdr of one
  // colour shoots exactly what --sky R,G,B of it does.
  double sum[6][3] = {}, weight[6] = {};
  const float* t = staged.data();
  const double ref[3] = {t[0], t[1], t[2]};
  for (uint32_t j = 0; j < height; ++j) {
    // Elevations of the row, top first; the solid angle is cos(el) del dphi.
    const double e1 = 0.5 * kPi - kPi * j / height, e0 = 0.5 * kPi - kPi * (j + 1.0) / height;
    // Over the row: the integral of sin(el) cos(el) where it is positive
    // (the upper sky, seen through the top face) and negative (the lower),
    // and of cos^2(el) (the sides, times their azimuth integral).
    auto sin2 = [](double e) { return std::sin(e) * std::sin(e); };
    const double up = 0.5 * (sin2(std::max(e1, 0.0)) - sin2(std::max(e0, 0.0)));
    const double down = 0.5 * (sin2(std::min(e0, 0.0)) - sin2(std::min(e1, 0.0)));
    auto g = [](double e) { return 0.5 * e + 0.25 * std::sin(2.0 * e); };
    const double side = g(e1) - g(e0);
    for (uint32_t i = 0; i < width; ++i, t += 3) {
      const double a = -kPi + 2.0 * kPi * i / width, b = -kPi + 2.0 * kPi * (i + 1.0) / width;
      // Outward normal of face 2 * axis + side: +/- the axis (side 1: +).
      const double w[6] = {side * AzimuthIntegral(a, b, 0, -1.0),
                           side * AzimuthIntegral(a, b, 0, 1.0),
                           (b - a) * down,
                           (b - a) * up,
                           side * AzimuthIntegral(a, b, 2, -1.0),
                           side * AzimuthIntegral(a, b, 2, 1.0)};
      for (int f = 0; f < 6; ++f) {
        weight[f] += w[f];
        for (int c = 0; c < 3; ++c) sum[f][c] += w[f] * (t[c] - ref[c]);
      }
    }
  }
  for (int f = 0; f < 6; ++f)
    for (int c = 0; c < 3; ++c)
      crossing[f][c] =
          weight[f] > 0.0 ? std::max(0.0, kPi * (ref[c] + sum[f][c] / weight[f])) : 0.0;
}

glm::vec3 SunRayDirection(const OutsideLight& light, float u1, float u2) {
  return SunConeDirection(light.sunToward, light.sunDegrees, u1, u2);
}

glm::vec3 SunConeDirection(const glm::vec3& toward, float degrees, float u1, float u2) {
  const glm::vec3 w = -toward;
  // A frame about w (Duff et al. 2017, branchless).
  const float sign = std::copysign(1.0f, w.z);
  const float a = -1.0f / (sign + w.z);
  const float b = w.x * w.y * a;
  const glm::vec3 t(1.0f + sign * w.x * w.x * a, sign * b, -sign * w.x);
  const glm::vec3 bt(b, sign + w.y * w.y * a, -w.y);
  const float half = 0.5f * degrees * 0.017453292519943295f;
  const float cosMax = std::cos(half);
  const float cosT = 1.0f - u1 * (1.0f - cosMax);
  const float sinT = std::sqrt(std::fmax(0.0f, 1.0f - cosT * cosT));
  const float phi = 6.2831855f * u2;
  return glm::normalize(sinT * std::cos(phi) * t + sinT * std::sin(phi) * bt + cosT * w);
}

}  // namespace vismask
