#include "grid_test_util.h"

#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <string>

#include "test_util.h"
#include "vismask/solve/sampling.h"

namespace vismask::gridtest {

Patch MakePatch(const glm::vec3* c, uint32_t n) {
  Patch p{};
  for (uint32_t k = 0; k < 4; ++k) p.corner[k] = c[k < n ? k : n - 1];
  glm::vec3 cr =
      n == 3 ? glm::cross(c[1] - c[0], c[2] - c[0]) : glm::cross(c[2] - c[0], c[3] - c[1]);
  p.normal = glm::normalize(cr);
  p.area = 0.5f * glm::length(cr);
  p.numCorners = n;
  p.kd = glm::vec3(0.5f);
  return p;
}

glm::vec3 UnitVector(std::mt19937& rng) {
  std::normal_distribution<float> g;
  for (;;) {
    glm::vec3 v(g(rng), g(rng), g(rng));
    float len = glm::length(v);
    if (len > 1e-3f) return v / len;
  }
}

void AddRandomPatches(std::mt19937& rng, int count, glm::vec3 lo, glm::vec3 hi, float sizeLo,
                      float sizeHi, TestScene* scene) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  std::uniform_real_distribution<float> logSize(std::log(sizeLo), std::log(sizeHi));
  for (int added = 0; added < count;) {
    glm::vec3 centre = lo + glm::vec3(u01(rng), u01(rng), u01(rng)) * (hi - lo);
    float size = std::exp(logSize(rng));
    glm::vec3 c[4];
    uint32_t n;
    if (u01(rng) < 0.5f) {
      n = 3;
      for (int k = 0; k < 3; ++k) c[k] = centre + size * u01(rng) * UnitVector(rng);
    } else {
      n = 4;
      glm::vec3 normal = UnitVector(rng);
      glm::vec3 e1 = glm::normalize(glm::cross(normal, UnitVector(rng)));
      glm::vec3 e2 = glm::cross(normal, e1);
      float a = size * (0.2f + 0.8f * u01(rng)), b = size * (0.2f + 0.8f * u01(rng));
      float gap[4], sum = 0.0f;
      for (float& g : gap) sum += (g = u01(rng) + 0.05f);
      float angle = 2.0f * kPi * u01(rng);
      for (int k = 0; k < 4; ++k) {
        c[k] = centre + a * std::cos(angle) * e1 + b * std::sin(angle) * e2;
        angle += gap[k] / sum * 2.0f * kPi;
      }
    }
    Patch p = MakePatch(c, n);
    if (!std::isfinite(p.normal.x + p.normal.y + p.normal.z) || p.area <= 0.0f) continue;
    scene->Add(p);
    ++added;
  }
}

void AddAxisQuad(int axis, float w, float u0, float u1, float v0, float v1, int sign,
                 TestScene* scene) {
  int ua = (axis + 1) % 3, va = (axis + 2) % 3;
  glm::vec3 c[4];
  const float uv[4][2] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  for (int k = 0; k < 4; ++k) {
    c[k][axis] = w;
    c[k][ua] = uv[k][0];
    c[k][va] = uv[k][1];
  }
  // (ua, va, axis) is right-handed, so this order faces +axis.
  if (sign < 0) std::swap(c[1], c[3]);
  scene->Add(MakePatch(c, 4));
}

void AddSubdividedQuad(int axis, float w, float u0, float u1, float v0, float v1, int sign, int m,
                       TestScene* scene) {
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) {
      float a0 = u0 + (u1 - u0) * i / m, a1 = u0 + (u1 - u0) * (i + 1) / m;
      float b0 = v0 + (v1 - v0) * j / m, b1 = v0 + (v1 - v0) * (j + 1) / m;
      AddAxisQuad(axis, w, a0, a1, b0, b1, sign, scene);
    }
  }
}

void AddBlock(glm::vec3 lo, glm::vec3 hi, int m, TestScene* scene) {
  for (int axis = 0; axis < 3; ++axis) {
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    AddSubdividedQuad(axis, lo[axis], lo[ua], hi[ua], lo[va], hi[va], -1, m, scene);
    AddSubdividedQuad(axis, hi[axis], lo[ua], hi[ua], lo[va], hi[va], +1, m, scene);
  }
}

TestScene CornellScene(int m) {
  TestScene s;
  AddSubdividedQuad(1, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, m, &s);  // floor
  AddSubdividedQuad(1, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, m, &s);  // ceiling
  AddSubdividedQuad(2, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, m, &s);  // back
  AddSubdividedQuad(0, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, m, &s);  // left
  AddSubdividedQuad(0, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, m, &s);  // right
  AddAxisQuad(1, 0.999f, 0.4f, 0.6f, 0.4f, 0.6f, -1, &s);         // light
  AddBlock(glm::vec3(0.2f, 0.0f, 0.2f), glm::vec3(0.45f, 0.3f, 0.45f), 2, &s);
  AddBlock(glm::vec3(0.55f, 0.0f, 0.5f), glm::vec3(0.8f, 0.6f, 0.75f), 3, &s);
  return s;
}

void AddAnchors(TestScene* s) {
  AddAxisQuad(2, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, s);
  AddAxisQuad(2, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, s);
}

Grid::Plan AnchoredPlan(std::mt19937& rng, int count, float sizeLo, float sizeHi, float density) {
  TestScene first;
  AddAnchors(&first);
  AddRandomPatches(rng, count, glm::vec3(0.3f), glm::vec3(0.7f), sizeLo, sizeHi, &first);
  return Grid::MakePlan(Span<const Patch>(first.patches.data(), first.patches.size()), density);
}

::testing::AssertionResult SamePlan(const Grid::Plan& got, const Grid::Plan& want) {
  if (got.bounds.lo != want.bounds.lo || got.bounds.hi != want.bounds.hi)
    return ::testing::AssertionFailure() << "other bounds";
  for (int a = 0; a < 3; ++a)
    if (got.res[a] != want.res[a])
      return ::testing::AssertionFailure()
             << "res[" << a << "] " << got.res[a] << ", not " << want.res[a];
  return ::testing::AssertionSuccess();
}

void BuildGrid(const TestScene& s, float density, BuiltGrid* b, Grid::Nest nest) {
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  b->plan = Grid::MakePlan(patches, density, nest);
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, b->plan);
  b->arena = Arena(measure.used());
  b->grid.Layout(b->arena, b->plan);
  b->grid.Build(patches, Span<const PatchGeom>(s.geom.data(), s.geom.size()));
}

bool BruteIntersect(const TestScene& s, const Ray& ray, uint32_t skip, Hit* hit) {
  Hit best;
  for (uint32_t p = 0; p < s.geom.size(); ++p) {
    float t;
    bool front;
    if (p == skip || !IntersectPatch(s.geom[p], ray, &t, &front)) continue;
    if (best.patch == kNoPatch || t < best.t || (t == best.t && front && !best.front))
      best = Hit{p, t, front};
  }
  *hit = best;
  return best.patch != kNoPatch;
}

void Checker::Check(const Ray& ray, uint32_t skip, const char* kind) {
  Hit want, got;
  bool wantHit = BruteIntersect(scene, ray, skip, &want);
  bool gotHit = grid.Intersect(ray, skip, &got);
  bool occluded = grid.Occluded(ray, skip);
  // With a hint: the last occluder found (kept from ray to ray, as Method
  // B's centre rays keep it), and any patch at all.
  bool hinted = grid.Occluded(ray, skip, &hint);
  uint32_t anyPatch = static_cast<uint32_t>((rays * 2654435761u) % scene.patches.size());
  bool anyHinted = grid.Occluded(ray, skip, &anyPatch);
  ++rays;
  hits += wantHit;
  bool same = wantHit == gotHit && occluded == wantHit && hinted == wantHit &&
              anyHinted == wantHit &&
              (!wantHit || (want.patch == got.patch && test::Bits(want.t) == test::Bits(got.t) &&
                            want.front == got.front));
  if (!same && ++failures <= 5) {
    ADD_FAILURE() << kind << " ray o=(" << ray.o.x << "," << ray.o.y << "," << ray.o.z << ") d=("
                  << ray.d.x << "," << ray.d.y << "," << ray.d.z << ") t=(" << ray.tMin << ","
                  << ray.tMax << ") skip=" << skip << ": brute "
                  << (wantHit ? std::to_string(want.patch) + "@" + std::to_string(want.t)
                              : std::string("miss"))
                  << ", grid "
                  << (gotHit ? std::to_string(got.patch) + "@" + std::to_string(got.t)
                             : std::string("miss"))
                  << ", occluded " << occluded << " (hinted " << hinted << ", " << anyHinted << ")";
  }
}

void Checker::CheckWithSkips(const Ray& ray, const char* kind) {
  Check(ray, kNoPatch, kind);
  Hit first;
  if (BruteIntersect(scene, ray, kNoPatch, &first)) Check(ray, first.patch, kind);
}

glm::vec3 PointOnPatch(std::mt19937& rng, const Patch& p) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  float a = u01(rng), b = u01(rng);
  if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
  // A triangle of the patch: (0,1,2) or, for quads, (0,2,3).
  int tri = p.numCorners == 4 && u01(rng) < 0.5f;
  glm::vec3 c0 = p.corner[0], c1 = p.corner[tri ? 2 : 1], c2 = p.corner[tri ? 3 : 2];
  return c0 + a * (c1 - c0) + b * (c2 - c0);
}

void SolverRays(const TestScene& s, uint32_t seed, int count, std::vector<Ray>* rays,
                std::vector<uint32_t>* from) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  glm::vec3 lo(kInf), hi(-kInf);
  for (const Patch& p : s.patches) {
    for (const glm::vec3& c : p.corner) {
      lo = glm::min(lo, c);
      hi = glm::max(hi, c);
    }
  }
  float eps = 1e-6f * glm::length(hi - lo);
  const uint32_t n = static_cast<uint32_t>(s.patches.size());
  for (int i = 0; i < count; ++i) {
    uint32_t p = static_cast<uint32_t>(u01(rng) * n) % n;
    PatchSampler sampler = MakePatchSampler(s.patches[p]);
    glm::vec3 o = sampler.Point(u01(rng), u01(rng), u01(rng));
    glm::vec3 d = sampler.frame.ToWorld(CosineDirection(u01(rng), u01(rng)));
    rays->push_back(Ray{o, d, eps, kInf});
    from->push_back(p);
  }
}

void CheckRays(const TestScene& s, const BuiltGrid& b, uint32_t seed, int perKind, Checker* ck) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const Bounds& bb = b.plan.bounds;
  glm::vec3 ext = bb.hi - bb.lo;
  glm::vec3 cell = ext / glm::vec3(b.plan.res[0], b.plan.res[1], b.plan.res[2]);
  glm::vec3 mid = 0.5f * (bb.lo + bb.hi);
  float diag = glm::length(ext);
  auto inside = [&]() { return bb.lo + glm::vec3(u01(rng), u01(rng), u01(rng)) * ext; };
  auto onPlanes = [&](glm::vec3 o) {  // snaps 1..3 coordinates to cell planes
    int mask = 1 + static_cast<int>(u01(rng) * 7.0f) % 7;
    for (int a = 0; a < 3; ++a) {
      if (!(mask & (1 << a))) continue;
      int k = static_cast<int>(u01(rng) * (b.plan.res[a] + 1)) % (b.plan.res[a] + 1);
      o[a] = bb.lo[a] + static_cast<float>(k) * cell[a];
    }
    return o;
  };
  auto zeroSome = [&](glm::vec3 d) {  // one or two zero components
    int a = static_cast<int>(u01(rng) * 3.0f) % 3;
    d[a] = 0.0f;
    if (u01(rng) < 0.5f) d[(a + 1) % 3] = 0.0f;
    if (d == glm::vec3(0.0f)) d[a] = 1.0f;
    return d;
  };
  auto axisRay = [&](glm::vec3 o) {
    Ray r{o, zeroSome(UnitVector(rng)), 0.0f, kInf};
    return r;
  };
  const uint32_t n = static_cast<uint32_t>(s.patches.size());
  for (int i = 0; i < perKind; ++i) {
    ck->CheckWithSkips(Ray{inside(), UnitVector(rng), 0.0f, kInf}, "inside");
    ck->CheckWithSkips(axisRay(inside()), "parallel");
    glm::vec3 planeOrigin = onPlanes(inside());
    ck->CheckWithSkips(Ray{planeOrigin, UnitVector(rng), 0.0f, kInf}, "on-plane");
    ck->CheckWithSkips(axisRay(planeOrigin), "on-plane-parallel");
    // Outside the grid, pointing at it or anywhere.
    glm::vec3 far = mid + (0.6f + 1.5f * u01(rng)) * diag * UnitVector(rng);
    ck->CheckWithSkips(Ray{far, inside() - far, 0.0f, kInf}, "outside-in");
    ck->CheckWithSkips(Ray{far, UnitVector(rng), 0.0f, kInf}, "outside-any");
    ck->CheckWithSkips(axisRay(onPlanes(far)), "outside-parallel");
    // Finite segment ending inside the grid; direction not unit length.
    glm::vec3 d = UnitVector(rng) * std::exp(8.0f * u01(rng) - 4.0f);
    float tMax = u01(rng) * diag / glm::length(d);
    ck->CheckWithSkips(Ray{inside(), d, 0.0f, tMax}, "segment");
    // Patch to patch, as the solver and a visibility test would cast them.
    uint32_t from = static_cast<uint32_t>(u01(rng) * n) % n;
    uint32_t to = static_cast<uint32_t>(u01(rng) * n) % n;
    glm::vec3 o = PointOnPatch(rng, s.patches[from]);
    glm::vec3 dir = UnitVector(rng);
    if (glm::dot(dir, s.patches[from].normal) < 0.0f) dir = -dir;
    ck->Check(Ray{o, dir, 1e-5f, kInf}, from, "from-patch");
    ck->Check(Ray{o, PointOnPatch(rng, s.patches[to]) - o, 1e-4f, 1.0f - 1e-4f}, from,
              "patch-to-patch");
    ck->Check(Ray{o, zeroSome(dir), 0.0f, kInf}, from, "from-patch-parallel");
    // Random skip.
    ck->Check(Ray{inside(), UnitVector(rng), 0.0f, kInf}, to, "random-skip");
    // Interval ends exactly at a hit: tMax at it (excluded), just past it,
    // and tMin at it (the next hit beyond).
    Ray probe{inside(), UnitVector(rng), 0.0f, kInf};
    Hit first;
    if (BruteIntersect(s, probe, kNoPatch, &first)) {
      ck->Check(Ray{probe.o, probe.d, 0.0f, first.t}, kNoPatch, "tmax-at-hit");
      ck->Check(Ray{probe.o, probe.d, 0.0f, std::nextafter(first.t, kInf)}, kNoPatch,
                "tmax-past-hit");
      ck->Check(Ray{probe.o, probe.d, first.t, kInf}, kNoPatch, "tmin-at-hit");
    }
    // Origin too far for the grid: every patch is tested.
    if (i % 8 == 0) {
      float distance = std::exp(std::log(10.0f) + std::log(1e4f) * u01(rng));
      glm::vec3 veryFar = mid + distance * (diag + glm::length(mid)) * UnitVector(rng);
      ck->CheckWithSkips(Ray{veryFar, inside() - veryFar, 0.0f, kInf}, "very-far");
    }
  }
}

}  // namespace vismask::gridtest
