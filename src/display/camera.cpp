#include "vismask/display/camera.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <limits>
#include <vector>

namespace vismask {

namespace {

struct SideSpec {
  const char* name;
  int axis;      // the view axis: 0 x, 1 y, 2 z
  bool eyeOnHi;  // the eye is beyond bounds.hi[axis] (else below bounds.lo[axis])
  glm::vec3 up;
};

// Indexed by ViewSide (see camera.h for the names and up vectors).
const SideSpec kSides[kNumViewSides] = {
    {"front", 2, false, {0.0f, 1.0f, 0.0f}}, {"back", 2, true, {0.0f, 1.0f, 0.0f}},
    {"left", 0, true, {0.0f, 1.0f, 0.0f}},   {"right", 0, false, {0.0f, 1.0f, 0.0f}},
    {"top", 1, true, {0.0f, 0.0f, 1.0f}},    {"bottom", 1, false, {0.0f, 0.0f, -1.0f}},
};

// Whether `q` lies inside the simple polygon `poly` (crossing number, edges
// half-open so a point on an edge shared by two polygons counts in one).
bool Inside(const std::vector<glm::dvec2>& poly, glm::dvec2 q) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::dvec2& a = poly[i];
    const glm::dvec2& b = poly[j];
    if ((a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

}  // namespace

const char* ViewSideName(ViewSide side) {
  return kSides[static_cast<int>(side)].name;
}

bool ParseViewSide(const char* name, ViewSide* side) {
  for (int s = 0; s < kNumViewSides; ++s) {
    if (std::strcmp(name, kSides[s].name) == 0) {
      *side = static_cast<ViewSide>(s);
      return true;
    }
  }
  return false;
}

Camera SideCamera(const Bounds& b, ViewSide side) {
  const SideSpec& s = kSides[static_cast<int>(side)];
  Camera c;
  glm::vec3 centre = 0.5f * (b.lo + b.hi);
  glm::vec3 half = 0.5f * (b.hi - b.lo);
  float tanHalf = std::tan(0.5f * c.fovyDeg * 3.14159265358979f / 180.0f);
  // The face across the view: its larger extent fills the field of view.
  // (front's arithmetic is exactly the camera's before --view: its images
  // stay byte for byte.)
  int u = s.axis == 0 ? 2 : 0, v = s.axis == 1 ? 2 : 1;
  float reach = std::fmax(half[u], half[v]);
  if (reach <= 0.0f) reach = std::fmax(half[s.axis], 1.0f);
  float distance = 1.04f * reach / tanHalf;
  float face = s.eyeOnHi ? b.hi[s.axis] : b.lo[s.axis];
  c.target = centre;
  c.target[s.axis] = face;
  c.eye = centre;
  c.eye[s.axis] = s.eyeOnHi ? face + distance : face - distance;
  c.up = s.up;
  return c;
}

Camera DefaultCamera(const Bounds& bounds) {
  return SideCamera(bounds, ViewSide::kFront);
}

Camera InsideCamera(const Bounds& b, int candidate) {
  static const float kAt[3] = {0.15f, 0.5f, 0.85f};
  const int k = candidate < 4 ? candidate : candidate + 1;  // the centre (4) left out
  const float fx = kAt[k % 3], fz = kAt[k / 3];
  const glm::vec3 e = b.hi - b.lo;
  Camera c;
  c.eye = b.lo + glm::vec3(fx * e.x, 0.6f * e.y, fz * e.z);
  c.target = b.lo + glm::vec3((1.0f - fx) * e.x, 0.35f * e.y, (1.0f - fz) * e.z);
  c.up = glm::vec3(0.0f, 1.0f, 0.0f);
  c.fovyDeg = 70.0f;
  return c;
}

void ViewProbe::Start(Probe& probe, const Camera& camera, int n) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  probe.n = n;
  probe.ok = MakeView(camera, n, n, &probe.view);
  if (!probe.ok) return;
  const View& view = probe.view;
  const glm::dvec3 right(view.right), up(view.up), forward(view.forward);
  const double focal = view.focal, halfN = 0.5 * n;
  probe.dir.resize(n * n);
  // One ray through each pixel centre of an n x n image, row 0 at the top.
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      probe.dir[y * n + x] = focal * forward + (x + 0.5 - halfN) * right + (halfN - (y + 0.5)) * up;
  probe.depth.assign(n * n, kInf);
  probe.nearest.assign(n * n, kInf);
  probe.index.assign(n * n, 0);
  probe.front.assign(n * n, 0);
  probe.plane.assign(n * n, 0);
  probe.normal.assign(n * n, glm::vec3(0.0f));
}

ViewProbe::ViewProbe(const Bounds& bounds) {
  reach_ = glm::length(bounds.hi - bounds.lo);
  centre_ = 0.5f * (bounds.lo + bounds.hi);
  for (int s = 0; s < kNumViewSides; ++s)
    Start(probes_[s], SideCamera(bounds, static_cast<ViewSide>(s)), kViewProbeRays);
  // Inside candidates only in a box with room to stand in.
  const glm::vec3 e = bounds.hi - bounds.lo;
  if (e.x > 0.0f && e.y > 0.0f && e.z > 0.0f)
    for (int k = 0; k < kInsideCandidates; ++k)
      Start(inside_[k], InsideCamera(bounds, k), kInsideProbeRays);
}

void ViewProbe::SetLights(const std::vector<ViewLight>& lights) {
  numLights_ = 0;
  for (const ViewLight& l : lights) {
    if (numLights_ == kViewLights || !(l.power > 0.0)) continue;
    const float len = glm::length(l.normal);
    if (!(len > 0.0f)) continue;
    ViewLight& mine = lights_[numLights_];
    mine = l;
    mine.normal = l.normal / len;
    // The shadow map: from just off the lamp along its normal, 120 degrees
    // across, up whichever axis is least along the normal.
    const glm::vec3 n = mine.normal;
    Camera c;
    c.eye = l.centre + 1e-4f * reach_ * n;
    c.target = c.eye + n;
    c.up = std::fabs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    c.fovyDeg = 120.0f;
    Start(lightProbes_[numLights_], c, kLightProbeRays);
    ++numLights_;
  }
}

bool ViewProbe::Probe::Project(const glm::dvec3& x, glm::dvec3* d, double* sx, double* sy) const {
  *d = x - glm::dvec3(view.eye);
  const double z = glm::dot(*d, glm::dvec3(view.forward));
  if (!(z > 0.0)) return false;
  const double halfN = 0.5 * n;
  *sx = halfN + view.focal * glm::dot(*d, glm::dvec3(view.right)) / z;
  *sy = halfN - view.focal * glm::dot(*d, glm::dvec3(view.up)) / z;
  return true;
}

double ViewProbe::LightAt(const glm::dvec3& x, const glm::dvec3& n) const {
  constexpr double kPi = 3.141592653589793;
  double sum = 0.0;
  const double reach = reach_;
  for (int k = 0; k < numLights_; ++k) {
    const ViewLight& l = lights_[k];
    const Probe& q = lightProbes_[k];
    if (!q.ok) continue;
    const glm::dvec3 toX = x - glm::dvec3(l.centre);
    const double r2 = std::max(glm::dot(toX, toX), 1e-6 * reach * reach), r = std::sqrt(r2);
    const double cosLamp = glm::dot(glm::dvec3(l.normal), toX) / r;
    const double cosHere = -glm::dot(n, toX) / r;
    if (!(cosLamp > 0.0 && cosHere > 0.0)) continue;
    // Seen from the lamp: x's pixel in its shadow map, x lit when no hit
    // there (or at a neighbour, the map's own resolution) is nearer than x
    // by more than 2% of the distance.
    glm::dvec3 d;
    double sx, sy;
    if (!q.Project(x, &d, &sx, &sy)) continue;
    if (!(sx >= 0.0 && sx < q.n && sy >= 0.0 && sy < q.n)) continue;  // outside the cone
    const int px = static_cast<int>(sx), py = static_cast<int>(sy);
    const double dist = glm::length(d);
    double farthest = 0.0;
    for (int y = std::max(0, py - 1); y <= std::min(q.n - 1, py + 1); ++y)
      for (int xx = std::max(0, px - 1); xx <= std::min(q.n - 1, px + 1); ++xx) {
        const int i = y * q.n + xx;
        farthest = std::max(farthest, q.depth[i] * glm::length(q.dir[i]));
      }
    if (dist > 1.02 * farthest + 1e-3 * reach) continue;  // in shadow
    sum += l.power * cosLamp * cosHere / (kPi * r2);
  }
  return sum;
}

void ViewProbe::Add(uint32_t index, const Polygon& p, bool twoSided) {
  for (Probe& probe : probes_) AddTo(probe, index, p, false, false);
  for (Probe& probe : inside_) AddTo(probe, index, p, true, twoSided);
  for (int k = 0; k < numLights_; ++k) AddTo(lightProbes_[k], index, p, true, true);
  if (sun_ > 0.0) AddTo(sunProbe_, index, p, true, true);
  if (hasSky_)
    for (Probe& probe : skyProbes_) AddTo(probe, index, p, true, true);
}

void ViewProbe::AddTo(Probe& probe, uint32_t index, const Polygon& p, bool clip, bool twoSided) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!probe.ok) return;
  const int n = probe.n;
  const View& view = probe.view;
  const glm::dvec3 eye(view.eye), right(view.right), up(view.up), forward(view.forward);
  const double focal = view.focal, halfN = 0.5 * n;
  // The polygon's nearest corner along the view, in units of t (a pixel's
  // ray has dot(dir, forward) = focal): of polygons a ray meets at the
  // same t, the one with the nearer corner, then the first in the file,
  // is seen (the order ChooseViewSide's near-to-far sweep gave).
  double tMin = kInf;
  for (const glm::vec3& corner : p.corners)
    tMin = std::min(tMin, glm::dot(glm::dvec3(corner) - eye, forward));
  tMin /= focal;
  // The pixels whose centres the polygon's projected corners bound. A side's
  // eye is outside the box, so every corner is in front of it; were one
  // not, the whole image is tested. An inside eye (`clip`) bounds the part
  // of the polygon in front of it: the corners there and where its edges
  // cross a plane just in front of the eye.
  double minX = kInf, maxX = -kInf, minY = kInf, maxY = -kInf;
  bool behind = false;
  auto extend = [&](const glm::dvec3& d, double z) {
    double sx = halfN + focal * glm::dot(d, right) / z, sy = halfN - focal * glm::dot(d, up) / z;
    minX = std::min(minX, sx), maxX = std::max(maxX, sx);
    minY = std::min(minY, sy), maxY = std::max(maxY, sy);
  };
  if (clip) {
    const double zNear = 1e-3 * static_cast<double>(view.nearZ);
    const size_t m = p.corners.size();
    for (size_t k = 0; k < m; ++k) {
      const glm::dvec3 a = glm::dvec3(p.corners[k]) - eye;
      const glm::dvec3 b = glm::dvec3(p.corners[(k + 1) % m]) - eye;
      const double za = glm::dot(a, forward), zb = glm::dot(b, forward);
      if (za > zNear) extend(a, za);
      if ((za > zNear) != (zb > zNear)) {
        const glm::dvec3 c = a + (b - a) * ((zNear - za) / (zb - za));
        extend(c, zNear);
      }
    }
    if (!(minX <= maxX)) return;  // wholly behind the eye
  } else {
    for (const glm::vec3& corner : p.corners) {
      glm::dvec3 d = glm::dvec3(corner) - eye;
      double z = glm::dot(d, forward);
      if (!(z > 0.0)) {
        behind = true;
        break;
      }
      extend(d, z);
    }
  }
  int x0 = 0, x1 = n - 1, y0 = 0, y1 = n - 1;
  if (!behind) {
    if (!(maxX >= -1.0 && minX <= n + 1.0 && maxY >= -1.0 && minY <= n + 1.0)) return;
    x0 = std::max(0, static_cast<int>(std::floor(std::max(minX, -1.0) - 0.5)));
    x1 = std::min(n - 1, static_cast<int>(std::ceil(std::min(maxX, n + 1.0) - 0.5)));
    y0 = std::max(0, static_cast<int>(std::floor(std::max(minY, -1.0) - 0.5)));
    y1 = std::min(n - 1, static_cast<int>(std::ceil(std::min(maxY, n + 1.0) - 0.5)));
    if (x0 > x1 || y0 > y1) return;
  }
  // The inside test in the plane's projection that distorts it least.
  const glm::dvec3 normal(p.normal);
  int drop = 0;
  for (int a = 1; a < 3; ++a)
    if (std::fabs(normal[a]) > std::fabs(normal[drop])) drop = a;
  const int pu = drop == 0 ? 1 : 0, pv = drop == 2 ? 1 : 2;
  const uint8_t plane = static_cast<uint8_t>(1 + 2 * drop + (normal[drop] < 0.0));
  poly_.clear();
  for (const glm::vec3& corner : p.corners) poly_.emplace_back(corner[pu], corner[pv]);
  const double reach = glm::dot(normal, glm::dvec3(p.corners[0]) - eye);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const int i = y * n + x;
      if (tMin * (1.0 - 1e-6) >= probe.depth[i])
        continue;  // (dot(dir, forward) is focal to rounding)
      double facing = glm::dot(normal, probe.dir[i]);
      if (facing == 0.0) continue;  // edge-on
      double t = reach / facing;
      if (!(t > 0.0)) continue;
      const bool nearer =
          t < probe.depth[i] ||
          (t == probe.depth[i] &&
           (tMin < probe.nearest[i] || (tMin == probe.nearest[i] && index < probe.index[i])));
      if (!nearer) continue;
      glm::dvec3 hit = eye + t * probe.dir[i];
      if (!Inside(poly_, glm::dvec2(hit[pu], hit[pv]))) continue;
      probe.depth[i] = t;
      probe.nearest[i] = tMin;
      probe.index[i] = index;
      probe.front[i] = facing < 0.0 || twoSided;
      probe.plane[i] = plane;
      probe.normal[i] = p.normal;
    }
  }
}

void ViewProbe::Rays(uint32_t rays[kNumViewSides]) const {
  for (int s = 0; s < kNumViewSides; ++s) {
    rays[s] = 0;
    for (uint8_t f : probes_[s].front) rays[s] += f;
  }
}

ViewSide ViewProbe::Side() const {
  uint32_t rays[kNumViewSides];
  Rays(rays);
  uint32_t best = *std::max_element(rays, rays + kNumViewSides);
  // Near ties (counts within 1% of the best, the probe's own resolution
  // noise for a symmetric scene) go to the earlier side: front first.
  for (int s = 0; s < kNumViewSides; ++s)
    if (rays[s] + best / 100 >= best) return static_cast<ViewSide>(s);
  return ViewSide::kFront;
}

ViewChoice ViewProbe::Choose() const {
  ViewChoice c;
  c.side = Side();
  c.lamps = numLights_;
  c.sun = sun_ > 0.0;
  c.sky = hasSky_;
  const Probe& s = probes_[static_cast<int>(c.side)];
  const double n2 = static_cast<double>(s.n) * s.n;
  uint32_t front = 0, back = 0, planes[7] = {0, 0, 0, 0, 0, 0, 0};
  for (size_t i = 0; i < s.front.size(); ++i) {
    if (s.depth[i] == std::numeric_limits<double>::infinity()) continue;
    if (s.front[i]) {
      ++front;
      ++planes[s.plane[i]];
    } else {
      ++back;
    }
  }
  c.sideFront = front / n2;
  c.sideBack = back / n2;
  const uint32_t most = *std::max_element(planes + 1, planes + 7);
  c.sideOneWall = front > 0 && 10 * uint64_t{most} >= 9 * uint64_t{front};
  const bool poor = back > front || c.sideOneWall;
  // A candidate's score: its front hits off the orientation most of them
  // share, so that a view of one wall or of a block up close scores little
  // and one across a room (floor, walls, ceiling) much; its lit score the
  // same with each hit counted by the lamps' light estimated there
  // (ViewLight), plus every hit's light from outside (SetOutside).
  double bestScore = -1.0, bestLit = 0.0;
  int litCandidate = -1;
  double share[kInsideCandidates] = {};  // front hits over the probe's rays
  for (int k = 0; k < kInsideCandidates; ++k) {
    c.geometric[k] = c.lit[k] = -1.0;
    const Probe& q = inside_[k];
    if (!q.ok) continue;
    uint32_t f = 0, by[7] = {0, 0, 0, 0, 0, 0, 0};
    double lit = 0.0, litBy[7] = {0, 0, 0, 0, 0, 0, 0}, outside = 0.0;
    const glm::dvec3 eye(q.view.eye);
    for (size_t i = 0; i < q.front.size(); ++i)
      if (q.front[i]) {
        ++f;
        ++by[q.plane[i]];
        if (numLights_ == 0 && sun_ == 0.0 && !hasSky_) continue;
        const glm::dvec3 x = eye + q.depth[i] * q.dir[i];
        glm::dvec3 n(q.normal[i]);
        if (glm::dot(n, q.dir[i]) > 0.0) n = -n;  // a two-sided polygon's back
        const double e = LightAt(x, n);
        lit += e;
        litBy[q.plane[i]] += e;
        outside += OutsideAt(x, n, q.index[i]);
      }
    const double m2 = static_cast<double>(q.n) * q.n;
    const double score = (f - *std::max_element(by + 1, by + 7)) / m2;
    share[k] = f / m2;
    c.geometric[k] = score;
    // Light from outside counts whole: it comes in as patches (the sun's
    // through a skylight, on the floor) that the lamps' rule would miss.
    c.lit[k] = (lit - *std::max_element(litBy + 1, litBy + 7) + outside) / m2;
    if (score > bestScore) {
      bestScore = score;
      c.candidate = k;
    }
    const bool goes = share[k] > c.sideFront && share[k] >= 0.5 && score >= 0.1 * share[k];
    if (goes && c.lit[k] > bestLit) {
      bestLit = c.lit[k];
      litCandidate = k;
    }
  }
  if (litCandidate >= 0) {
    c.candidate = litCandidate;
    c.byLight = true;
  }
  if (c.candidate >= 0) {
    c.candidateFront = share[c.candidate];
    c.candidateScore = c.geometric[c.candidate];
  }
  c.inside = poor && c.candidate >= 0 && c.candidateFront > c.sideFront &&
             c.candidateFront >= 0.5 && c.candidateScore >= 0.1 * c.candidateFront;
  return c;
}

void VisibleFrontRays(const Scene& scene, uint32_t rays[kNumViewSides]) {
  ViewProbe probe(scene.bounds);
  for (uint32_t k = 0; k < scene.polygons.size(); ++k) probe.Add(k, scene.polygons[k]);
  probe.Rays(rays);
}

ViewSide ChooseViewSide(const Scene& scene) {
  ViewProbe probe(scene.bounds);
  for (uint32_t k = 0; k < scene.polygons.size(); ++k) probe.Add(k, scene.polygons[k]);
  return probe.Side();
}
bool MakeView(const Camera& c, int width, int height, View* v) {
  if (!(c.fovyDeg > 0.0f && c.fovyDeg < 180.0f) || width <= 0 || height <= 0) return false;
  glm::vec3 f = c.target - c.eye;
  if (!(glm::length(f) > 0.0f)) return false;
  v->nearZ = 1e-3f * glm::length(f);
  f = glm::normalize(f);
  glm::vec3 r = glm::cross(f, c.up);
  if (!(glm::length(r) > 1e-6f * glm::length(c.up))) return false;
  r = glm::normalize(r);
  v->eye = c.eye;
  v->forward = f;
  v->right = r;
  v->up = glm::cross(r, f);
  v->width = width;
  v->height = height;
  v->focal =
      0.5f * static_cast<float>(height) / std::tan(0.5f * c.fovyDeg * 3.14159265358979f / 180.0f);
  return true;
}

}  // namespace vismask
