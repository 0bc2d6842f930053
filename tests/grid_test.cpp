#include "vismask/grid.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/geometric.hpp>
#include <random>
#include <string>
#include <vector>

#include "vismask/arena.h"
#include "vismask/sampling.h"

namespace vismask {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kInf = std::numeric_limits<float>::infinity();

// A patch from 3 or 4 corners, counter-clockwise seen from the front.
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

// A scene: patches and their ray-test data, kept side by side.
struct TestScene {
  std::vector<Patch> patches;
  std::vector<PatchGeom> geom;
  void Add(const Patch& p) {
    patches.push_back(p);
    geom.push_back(MakePatchGeom(p));
  }
};

glm::vec3 UnitVector(std::mt19937& rng) {
  std::normal_distribution<float> g;
  for (;;) {
    glm::vec3 v(g(rng), g(rng), g(rng));
    float len = glm::length(v);
    if (len > 1e-3f) return v / len;
  }
}

// Random triangles and planar convex quads (corners on an ellipse, in angle
// order) of log-uniform sizes in [sizeLo, sizeHi], centred in [lo, hi].
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

// An axis-aligned quad [u0,u1] x [v0,v1] on the plane x[axis] == w, facing
// +axis (sign > 0) or -axis.
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

// Axis-aligned block [lo, hi], faces outward, each split m x m.
void AddBlock(glm::vec3 lo, glm::vec3 hi, int m, TestScene* scene) {
  for (int axis = 0; axis < 3; ++axis) {
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    AddSubdividedQuad(axis, lo[axis], lo[ua], hi[ua], lo[va], hi[va], -1, m, scene);
    AddSubdividedQuad(axis, hi[axis], lo[ua], hi[ua], lo[va], hi[va], +1, m, scene);
  }
}

// A Cornell-like box in [0,1]^3: five inward walls, a light, two blocks.
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

// A grid laid out in its own arena and built.
struct BuiltGrid {
  Grid::Plan plan;
  Arena arena{1};
  Grid grid;
};

void BuildGrid(const TestScene& s, float density, BuiltGrid* b) {
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  b->plan = Grid::MakePlan(patches, density);
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, b->plan);
  b->arena = Arena(measure.used());
  b->grid.Layout(b->arena, b->plan);
  b->grid.Build(patches, Span<const PatchGeom>(s.geom.data(), s.geom.size()));
}

// The reference: every patch, the same tie rule (a front side, then the
// lower index: grid.h).
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

uint32_t Bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

// Compares grid and brute force on one ray (with its skip); also the query
// skipping the brute-force hit itself. Returns the number of disagreements.
struct Checker {
  const TestScene& scene;
  const Grid& grid;
  int rays = 0;
  int hits = 0;
  int failures = 0;
  uint32_t hint = kNoPatch;

  void Check(const Ray& ray, uint32_t skip, const char* kind) {
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
    bool same =
        wantHit == gotHit && occluded == wantHit && hinted == wantHit && anyHinted == wantHit &&
        (!wantHit ||
         (want.patch == got.patch && Bits(want.t) == Bits(got.t) && want.front == got.front));
    if (!same && ++failures <= 5) {
      ADD_FAILURE() << kind << " ray o=(" << ray.o.x << "," << ray.o.y << "," << ray.o.z << ") d=("
                    << ray.d.x << "," << ray.d.y << "," << ray.d.z << ") t=(" << ray.tMin << ","
                    << ray.tMax << ") skip=" << skip << ": brute "
                    << (wantHit ? std::to_string(want.patch) + "@" + std::to_string(want.t)
                                : std::string("miss"))
                    << ", grid "
                    << (gotHit ? std::to_string(got.patch) + "@" + std::to_string(got.t)
                               : std::string("miss"))
                    << ", occluded " << occluded << " (hinted " << hinted << ", " << anyHinted
                    << ")";
    }
  }

  void CheckWithSkips(const Ray& ray, const char* kind) {
    Check(ray, kNoPatch, kind);
    Hit first;
    if (BruteIntersect(scene, ray, kNoPatch, &first)) Check(ray, first.patch, kind);
  }
};

glm::vec3 PointOnPatch(std::mt19937& rng, const Patch& p) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  float a = u01(rng), b = u01(rng);
  if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
  // A triangle of the patch: (0,1,2) or, for quads, (0,2,3).
  int tri = p.numCorners == 4 && u01(rng) < 0.5f;
  glm::vec3 c0 = p.corner[0], c1 = p.corner[tri ? 2 : 1], c2 = p.corner[tri ? 3 : 2];
  return c0 + a * (c1 - c0) + b * (c2 - c0);
}

// Rays as the solver casts them: a uniform point on a patch, a cosine-
// distributed direction about its normal, tMin = 1e-6 of the scene diagonal,
// skipping the patch itself.
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

// Sends `perKind` rays of each kind through `b` and checks them all.
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

TEST(GridTest, RandomScenesMatchBruteForce) {
  struct Case {
    int count;
    glm::vec3 lo, hi;
    float sizeLo, sizeHi, density;
    int rays;
  };
  const Case cases[] = {
      {2000, glm::vec3(0.0f), glm::vec3(1.0f), 0.005f, 0.3f, 4.0f, 1800},
      {300, glm::vec3(-2.0f, 0.0f, 5.0f), glm::vec3(3.0f, 0.5f, 7.0f), 0.01f, 2.0f, 1.0f, 900},
      {1000, glm::vec3(100.0f, -50.0f, 20.0f), glm::vec3(101.0f, -49.0f, 21.0f), 0.002f, 0.1f, 8.0f,
       900},
      {50, glm::vec3(0.0f), glm::vec3(1.0f), 0.5f, 3.0f, 2.0f, 600},
  };
  uint32_t seed = 1;
  int total = 0;
  for (const Case& c : cases) {
    std::mt19937 rng(seed);
    TestScene s;
    AddRandomPatches(rng, c.count, c.lo, c.hi, c.sizeLo, c.sizeHi, &s);
    BuiltGrid b;
    BuildGrid(s, c.density, &b);
    Checker ck{s, b.grid};
    CheckRays(s, b, seed + 100, c.rays, &ck);
    EXPECT_EQ(ck.failures, 0) << "scene " << seed << " of " << c.count << " patches, " << ck.rays
                              << " rays";
    EXPECT_GT(ck.hits, ck.rays / 20);
    total += ck.rays;
    ++seed;
  }
  EXPECT_GE(total, 60000);
}

TEST(GridTest, CornellBoxMatchesBruteForce) {
  int total = 0;
  const float densities[] = {0.5f, 4.0f, 30.0f};
  for (float density : densities) {
    TestScene s = CornellScene(8);
    BuiltGrid b;
    BuildGrid(s, density, &b);
    Checker ck{s, b.grid};
    CheckRays(s, b, 7, 900, &ck);
    EXPECT_EQ(ck.failures, 0) << "density " << density;
    total += ck.rays;
  }
  EXPECT_GE(total, 45000);
}

TEST(GridTest, FlatScenes) {
  // One axis-aligned quad: the grid must still have thickness.
  TestScene quad;
  AddAxisQuad(2, 0.25f, 0.0f, 1.0f, 0.0f, 1.0f, +1, &quad);
  BuiltGrid b;
  BuildGrid(quad, 4.0f, &b);
  EXPECT_EQ(b.plan.res[2], 1);
  EXPECT_LT(b.plan.bounds.lo.z, 0.25f);
  EXPECT_GT(b.plan.bounds.hi.z, 0.25f);
  EXPECT_EQ(b.plan.refs, b.grid.cellCount());  // the quad spans every cell
  Hit hit;
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.3f, 0.6f, 1.0f), glm::vec3(0, 0, -1), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_EQ(hit.patch, 0u);
  EXPECT_EQ(hit.t, 0.75f);
  EXPECT_TRUE(hit.front);
  EXPECT_FALSE(b.grid.Intersect(Ray{glm::vec3(1.3f, 0.6f, 1.0f), glm::vec3(0, 0, -1), 0.0f, kInf},
                                kNoPatch, &hit));
  Checker ck{quad, b.grid};
  CheckRays(quad, b, 11, 300, &ck);
  EXPECT_EQ(ck.failures, 0);

  // Many triangles in one slanted plane.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene plane;
  glm::vec3 e1 = glm::normalize(glm::vec3(1.0f, 0.3f, 0.1f));
  glm::vec3 e2 = glm::normalize(glm::cross(glm::vec3(0.2f, 0.1f, 1.0f), e1));
  while (plane.patches.size() < 500) {
    glm::vec3 c[3];
    for (glm::vec3& x : c) x = (4.0f * u01(rng)) * e1 + (4.0f * u01(rng)) * e2;
    Patch p = MakePatch(c, 3);
    if (std::isfinite(p.normal.x) && p.area > 1e-4f) plane.Add(p);
  }
  BuiltGrid bp;
  BuildGrid(plane, 4.0f, &bp);
  Checker ckp{plane, bp.grid};
  CheckRays(plane, bp, 12, 400, &ckp);
  EXPECT_EQ(ckp.failures, 0);
}

TEST(GridTest, ResolutionFollowsPatchCount) {
  std::mt19937 rng(3);
  TestScene small, large;
  AddRandomPatches(rng, 100, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.05f, &small);
  AddRandomPatches(rng, 10000, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.05f, &large);
  for (float density : {1.0f, 4.0f, 16.0f}) {
    Grid::Plan ps = Grid::MakePlan(Span<const Patch>(small.patches.data(), 100), density);
    Grid::Plan pl = Grid::MakePlan(Span<const Patch>(large.patches.data(), 10000), density);
    uint64_t cs = uint64_t(ps.res[0]) * ps.res[1] * ps.res[2];
    uint64_t cl = uint64_t(pl.res[0]) * pl.res[1] * pl.res[2];
    EXPECT_LT(cs * 10, cl) << density;
    EXPECT_LE(cs, 8u * 100 + 64);
    EXPECT_LE(cl, 8u * 10000 + 64);
    // Near Cleary's target for a cube-like scene: density * N cells.
    EXPECT_GT(cl, 0.5 * std::min(density, 8.0f) * 10000);
    for (int a = 0; a < 3; ++a) EXPECT_LE(pl.res[a], 1024);
    EXPECT_GE(pl.refs, 10000u);
  }
  // Higher density, more cells.
  Grid::Plan lo = Grid::MakePlan(Span<const Patch>(large.patches.data(), 10000), 1.0f);
  Grid::Plan hi = Grid::MakePlan(Span<const Patch>(large.patches.data(), 10000), 4.0f);
  EXPECT_LT(uint64_t(lo.res[0]) * lo.res[1] * lo.res[2],
            uint64_t(hi.res[0]) * hi.res[1] * hi.res[2]);
  // A long thin scene gets its cells along the long axis, capped at 1024.
  TestScene rod;
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (int i = 0; i < 5000; ++i) {
    float x = 1000.0f * u01(rng), y = u01(rng), z = u01(rng);
    AddAxisQuad(i % 3, i % 3 == 0 ? x : i % 3 == 1 ? y : z, 0.0f, 0.3f, 0.0f, 0.3f, +1, &rod);
    Patch& p = rod.patches.back();
    for (glm::vec3& c : p.corner) c += glm::vec3(i % 3 == 0 ? 0.0f : x, 0.0f, 0.0f);
    rod.geom.back() = MakePatchGeom(p);
  }
  Grid::Plan pr = Grid::MakePlan(Span<const Patch>(rod.patches.data(), 5000), 4.0f);
  EXPECT_EQ(pr.res[0], 1024);
  EXPECT_LT(pr.res[1] * 100, pr.res[0]);
  EXPECT_LE(uint64_t(pr.res[0]) * pr.res[1] * pr.res[2], 8u * 5000 + 64);
}

TEST(GridTest, LayoutMeasuresWhatItUses) {
  std::mt19937 rng(9);
  TestScene s;
  AddRandomPatches(rng, 700, glm::vec3(0.0f), glm::vec3(2.0f, 1.0f, 1.0f), 0.01f, 0.4f, &s);
  Grid::Plan plan = Grid::MakePlan(Span<const Patch>(s.patches.data(), 700), 4.0f);

  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, plan);
  EXPECT_EQ(probe.cellStart().data(), nullptr);
  Arena arena(measure.used());
  Grid grid;
  grid.Layout(arena, plan);
  EXPECT_EQ(arena.used(), measure.used());
  EXPECT_EQ(grid.bytes(), probe.bytes());
  EXPECT_EQ(grid.bytes(), (grid.cellCount() + 1 + plan.refs) * sizeof(uint32_t) +
                              (grid.cellCount() + 63) / 64 * sizeof(uint64_t));
  grid.Build(Span<const Patch>(s.patches.data(), 700), Span<const PatchGeom>(s.geom.data(), 700));
  EXPECT_EQ(arena.used(), measure.used());

  // The built arrays hold exactly plan.refs references, sorted within cells,
  // and every patch is in the cell of its centroid.
  Span<const uint32_t> start = grid.cellStart();
  Span<const uint32_t> refs = grid.refs();
  // The occupancy bitmap marks exactly the cells that hold a reference.
  size_t occupiedCells = 0;
  for (size_t c = 0; c < grid.cellCount(); ++c) {
    bool bit = (grid.occupied()[c / 64] >> (c % 64)) & 1;
    ASSERT_EQ(bit, start[c + 1] > start[c]) << "cell " << c;
    occupiedCells += bit;
  }
  EXPECT_GT(occupiedCells, 0u);
  EXPECT_LT(occupiedCells, grid.cellCount());
  ASSERT_EQ(start.size(), grid.cellCount() + 1);
  EXPECT_EQ(start[0], 0u);
  EXPECT_EQ(start[grid.cellCount()], plan.refs);
  EXPECT_EQ(refs.size(), plan.refs);
  for (size_t c = 0; c < grid.cellCount(); ++c) {
    ASSERT_LE(start[c], start[c + 1]);
    for (uint32_t k = start[c] + 1; k < start[c + 1]; ++k) ASSERT_LT(refs[k - 1], refs[k]);
  }
  glm::vec3 cell =
      (plan.bounds.hi - plan.bounds.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  for (uint32_t i = 0; i < 700; ++i) {
    const Patch& p = s.patches[i];
    glm::vec3 centroid = (p.corner[0] + p.corner[1] + p.corner[2]) / 3.0f;
    glm::ivec3 c = glm::clamp(glm::ivec3((centroid - plan.bounds.lo) / cell), glm::ivec3(0),
                              glm::ivec3(plan.res[0], plan.res[1], plan.res[2]) - 1);
    size_t index = (size_t(c.z) * plan.res[1] + c.y) * plan.res[0] + c.x;
    bool found = false;
    for (uint32_t k = start[index]; k < start[index + 1]; ++k) found |= refs[k] == i;
    EXPECT_TRUE(found) << "patch " << i;
  }
}

TEST(GridTest, BuildRejectsAForeignPlan) {
  std::mt19937 rng(4);
  TestScene s, other;
  AddRandomPatches(rng, 200, glm::vec3(0.0f), glm::vec3(1.0f), 0.05f, 0.3f, &s);
  AddRandomPatches(rng, 200, glm::vec3(0.0f), glm::vec3(1.0f), 0.05f, 0.3f, &other);
  Grid::Plan plan = Grid::MakePlan(Span<const Patch>(other.patches.data(), 200), 4.0f);
  Arena arena(1 << 20);
  Grid grid;
  grid.Layout(arena, plan);
  EXPECT_DEATH(grid.Build(Span<const Patch>(s.patches.data(), 200),
                          Span<const PatchGeom>(s.geom.data(), 200)),
               "grid plan does not match");
}

// Patches whose planes, edges and corners lie on the cell lattice, and rays
// along lattice lines: every hit is on a cell boundary.
TEST(GridTest, CellAlignedSceneMatchesBruteForce) {
  // Two big anchor quads fix the bounds; the plan depends only on them and on
  // the patch count, so a first scene of the same size tells us the lattice.
  auto anchored = [](TestScene* s) {
    AddAxisQuad(2, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, s);
    AddAxisQuad(2, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, s);
  };
  const int kCount = 600;
  std::mt19937 rng(17);
  TestScene first;
  anchored(&first);
  AddRandomPatches(rng, kCount, glm::vec3(0.3f), glm::vec3(0.7f), 0.01f, 0.1f, &first);
  Grid::Plan plan =
      Grid::MakePlan(Span<const Patch>(first.patches.data(), first.patches.size()), 4.0f);
  const Bounds& bb = plan.bounds;
  glm::vec3 cell = (bb.hi - bb.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  auto lattice = [&](int a, int k) { return bb.lo[a] + static_cast<float>(k) * cell[a]; };
  // Lattice indices well inside [0, 1] on every axis.
  int kLo[3], kHi[3];
  for (int a = 0; a < 3; ++a) {
    kLo[a] = static_cast<int>(std::ceil((0.1f - bb.lo[a]) / cell[a]));
    kHi[a] = static_cast<int>(std::floor((0.9f - bb.lo[a]) / cell[a]));
    ASSERT_LT(kLo[a] + 3, kHi[a]);
  }
  auto pick = [&](int a) { return kLo[a] + static_cast<int>(rng() % (kHi[a] - kLo[a] + 1)); };

  TestScene s;
  anchored(&s);
  while (static_cast<int>(s.patches.size()) < kCount + 2) {
    if (s.patches.size() % 2 == 0) {
      // Axis-aligned quad on a cell plane, edges on cell planes.
      int axis = static_cast<int>(rng() % 3), ua = (axis + 1) % 3, va = (axis + 2) % 3;
      int u0 = pick(ua), v0 = pick(va);
      int u1 = std::min(kHi[ua], u0 + 1 + static_cast<int>(rng() % 3));
      int v1 = std::min(kHi[va], v0 + 1 + static_cast<int>(rng() % 3));
      if (u1 == u0 || v1 == v0) continue;
      AddAxisQuad(axis, lattice(axis, pick(axis)), lattice(ua, u0), lattice(ua, u1),
                  lattice(va, v0), lattice(va, v1), rng() % 2 ? 1 : -1, &s);
    } else {
      // Triangle with corners on lattice points.
      glm::vec3 c[3];
      int k0[3];
      for (int a = 0; a < 3; ++a) k0[a] = pick(a);
      for (glm::vec3& x : c) {
        for (int a = 0; a < 3; ++a) {
          int k = std::clamp(k0[a] + static_cast<int>(rng() % 5) - 2, kLo[a], kHi[a]);
          x[a] = lattice(a, k);
        }
      }
      Patch p = MakePatch(c, 3);
      float minCell = std::min({cell.x, cell.y, cell.z});
      if (!(p.area > 0.1f * minCell * minCell)) continue;  // collinear corners
      s.Add(p);
    }
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  ASSERT_EQ(b.plan.bounds.lo, plan.bounds.lo);
  ASSERT_EQ(b.plan.bounds.hi, plan.bounds.hi);
  for (int a = 0; a < 3; ++a) ASSERT_EQ(b.plan.res[a], plan.res[a]);

  Checker ck{s, b.grid};
  CheckRays(s, b, 23, 400, &ck);
  // From lattice points along lattice axes, face and space diagonals.
  const glm::vec3 dirs[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1},  {1, 1, 0},  {1, 0, 1},
                            {0, 1, 1}, {1, 1, 1}, {1, -1, 0}, {1, 1, -1}, {-1, 1, 1}};
  for (int i = 0; i < 3000; ++i) {
    glm::vec3 o;
    for (int a = 0; a < 3; ++a) o[a] = lattice(a, static_cast<int>(rng() % (plan.res[a] + 1)));
    glm::vec3 d = dirs[rng() % 10] * (rng() % 2 ? 1.0f : -1.0f);
    for (int a = 0; a < 3; ++a) d[a] *= cell[a];  // through lattice points exactly
    ck.CheckWithSkips(Ray{o, d, 0.0f, kInf}, "lattice");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
}

// Slivers: the widened edge planes of a very sharp corner reach well past the
// tip, and IntersectPatch accepts hits there; the grid must too.
TEST(GridTest, SliverTipsMatchBruteForce) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene s;
  AddRandomPatches(rng, 300, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.2f, &s);
  struct Tip {
    glm::vec3 point, out, normal;
  };
  std::vector<Tip> tips;
  glm::vec3 shift(u01(rng) * 50.0f, 0.0f, 0.0f);
  for (int i = 0; i < 300; ++i) {
    glm::vec3 c0 = glm::vec3(u01(rng), u01(rng), u01(rng)) + (i % 2 ? shift : glm::vec3(0.0f));
    glm::vec3 axis = UnitVector(rng);
    glm::vec3 side = glm::normalize(glm::cross(axis, UnitVector(rng)));
    float length = 0.05f + 0.3f * u01(rng);
    float width = length * std::exp(std::log(1e-6f) + std::log(1e4f) * u01(rng));
    glm::vec3 c[3] = {c0, c0 + length * axis, c0 + 0.5f * length * axis + width * side};
    Patch p = MakePatch(c, 3);
    if (!std::isfinite(p.normal.x + p.normal.y + p.normal.z) || p.area <= 0.0f) continue;
    s.Add(p);
    tips.push_back({c[0], -axis, p.normal});
    tips.push_back({c[1], axis, p.normal});
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  Checker ck{s, b.grid};
  for (int i = 0; i < 20000; ++i) {
    const Tip& tip = tips[rng() % tips.size()];
    // A target on the patch plane, at or beyond the tip by 0 .. 0.1.
    float beyond = i % 4 == 0 ? 0.0f : std::exp(std::log(1e-9f) + std::log(1e8f) * u01(rng));
    glm::vec3 target = tip.point + beyond * tip.out;
    glm::vec3 from = target + (0.05f + u01(rng)) * UnitVector(rng);
    ck.CheckWithSkips(Ray{from, target - from, 0.0f, kInf}, "sliver-tip");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
}

// Registration by plane/box overlap: a big slanted quad is kept out of most
// of the cells its box covers.
TEST(GridTest, SlantedPatchSkipsCellsItMisses) {
  std::mt19937 rng(31);
  TestScene s;
  AddRandomPatches(rng, 2000, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.05f, &s);
  glm::vec3 c[4] = {{0, 0, 0.5f}, {1, 0, 0}, {1, 1, 0.5f}, {0, 1, 1}};
  s.Add(MakePatch(c, 4));
  uint32_t big = static_cast<uint32_t>(s.patches.size() - 1);
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  size_t count = 0;
  for (uint32_t r : b.grid.refs()) count += r == big;
  size_t boxCells = b.grid.cellCount();  // its box spans (nearly) the whole grid
  EXPECT_GT(count, 0u);
  EXPECT_LT(count * 4, boxCells) << count << " of " << boxCells;
  Checker ck{s, b.grid};
  CheckRays(s, b, 37, 200, &ck);
  EXPECT_EQ(ck.failures, 0);
}

// A face of the box that walls lie on is put just inside an outer layer of
// cells: its patches are registered in that layer only, and the next cell
// plane lies just beyond them. A face without walls keeps the plain margin.
TEST(GridTest, WallsLieInAnOuterLayer) {
  const int m = 8;
  TestScene s = CornellScene(m);  // floor, ceiling, back, left, right: m * m patches each
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  const Grid::Plan& plan = b.plan;
  glm::vec3 cell =
      (plan.bounds.hi - plan.bounds.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  struct Wall {
    int axis;
    bool high;  // on the box's upper face
  };
  const Wall walls[5] = {{1, false}, {1, true}, {2, false}, {0, false}, {0, true}};
  Span<const uint32_t> start = b.grid.cellStart();
  Span<const uint32_t> refs = b.grid.refs();
  for (int w = 0; w < 5; ++w) {
    int a = walls[w].axis;
    int layer = walls[w].high ? plan.res[a] - 1 : 0;
    float face = walls[w].high ? 1.0f : 0.0f;
    // The outer layer's inner plane is just past the wall, its outer plane far.
    float inner = walls[w].high ? plan.bounds.hi[a] - cell[a] : plan.bounds.lo[a] + cell[a];
    float outer = walls[w].high ? plan.bounds.hi[a] : plan.bounds.lo[a];
    EXPECT_GT(std::fabs(inner - face), 1e-5f) << "wall " << w;
    EXPECT_LT(std::fabs(inner - face), 0.01f) << "wall " << w;
    EXPECT_GT(std::fabs(outer - face), 0.5f * cell[a]) << "wall " << w;
    for (size_t c = 0; c < b.grid.cellCount(); ++c) {
      int coord[3] = {static_cast<int>(c % plan.res[0]),
                      static_cast<int>(c / plan.res[0] % plan.res[1]),
                      static_cast<int>(c / plan.res[0] / plan.res[1])};
      for (uint32_t k = start[c]; k < start[c + 1]; ++k) {
        uint32_t p = refs[k];
        if (p >= static_cast<uint32_t>(w * m * m) && p < static_cast<uint32_t>((w + 1) * m * m)) {
          ASSERT_EQ(coord[a], layer) << "wall " << w << " patch " << p;
        }
      }
    }
  }
  // The open front (z = 1) has no wall: the plain margin of 1e-3 of the box.
  EXPECT_LT(plan.bounds.hi.z - 1.0f, 0.01f);
  EXPECT_GT(plan.bounds.hi.z, 1.0f);

  // A wall that is not flat (leaning out by 1/100 over its height, as the
  // published Cornell box's red wall does by 6 mm): still in one layer.
  TestScene lean = CornellScene(m);
  for (uint32_t p = 4 * m * m; p < 5 * m * m; ++p) {
    for (glm::vec3& c : lean.patches[p].corner) c.x += 0.01f * c.y;
    lean.patches[p].normal = glm::normalize(glm::vec3(-1.0f, 0.01f, 0.0f));
    lean.geom[p] = MakePatchGeom(lean.patches[p]);
  }
  BuiltGrid bl;
  BuildGrid(lean, 4.0f, &bl);
  float inner = bl.plan.bounds.hi.x - (bl.plan.bounds.hi.x - bl.plan.bounds.lo.x) / bl.plan.res[0];
  EXPECT_LT(inner, 1.0f);
  EXPECT_GT(inner, 0.98f);
  Span<const uint32_t> ls = bl.grid.cellStart();
  Span<const uint32_t> lr = bl.grid.refs();
  for (size_t c = 0; c < bl.grid.cellCount(); ++c) {
    for (uint32_t k = ls[c]; k < ls[c + 1]; ++k) {
      if (lr[k] >= static_cast<uint32_t>(4 * m * m) && lr[k] < static_cast<uint32_t>(5 * m * m)) {
        ASSERT_EQ(static_cast<int>(c % bl.plan.res[0]), bl.plan.res[0] - 1) << "patch " << lr[k];
      }
    }
  }
  Checker ckl{lean, bl.grid};
  CheckRays(lean, bl, 61, 300, &ckl);
  EXPECT_EQ(ckl.failures, 0);
  // A random scene has no walls: margins only, on every face.
  std::mt19937 rng(41);
  TestScene r;
  AddRandomPatches(rng, 1000, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.1f, &r);
  Grid::Plan pr = Grid::MakePlan(Span<const Patch>(r.patches.data(), r.patches.size()), 4.0f);
  glm::vec3 lo(kInf), hi(-kInf);
  for (const Patch& p : r.patches) {
    for (const glm::vec3& c : p.corner) {
      lo = glm::min(lo, c);
      hi = glm::max(hi, c);
    }
  }
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(pr.bounds.lo[a], lo[a] - 0.01f) << a;
    EXPECT_LT(pr.bounds.hi[a], hi[a] + 0.01f) << a;
  }
}

// Rays as the solver casts them, from points on the walls of a Cornell box
// (walls in outer layers, rays leaving them through a sliver of a cell), at
// several densities; and again with the box far from the world origin, where
// the padding is a few hundred ulps of coordinates much larger than a cell.
TEST(GridTest, SolverRaysMatchBruteForce) {
  int total = 0;
  for (float offset : {0.0f, 3000.0f}) {
    TestScene s = CornellScene(12);
    if (offset != 0.0f) {
      for (size_t i = 0; i < s.patches.size(); ++i) {
        for (glm::vec3& c : s.patches[i].corner) c += glm::vec3(offset, -0.5f * offset, 0.0f);
        s.geom[i] = MakePatchGeom(s.patches[i]);
      }
    }
    for (float density : {1.0f, 4.0f, 8.0f}) {
      BuiltGrid b;
      BuildGrid(s, density, &b);
      Checker ck{s, b.grid};
      std::vector<Ray> rays;
      std::vector<uint32_t> from;
      SolverRays(s, 53, 4000, &rays, &from);
      for (size_t i = 0; i < rays.size(); ++i) ck.Check(rays[i], from[i], "solver");
      EXPECT_EQ(ck.failures, 0) << "offset " << offset << ", density " << density;
      EXPECT_GT(ck.hits, ck.rays / 2);
      total += ck.rays;
    }
  }
  EXPECT_GE(total, 24000);
}

// Tiny patches next to a cell edge (where two cell planes meet), a few pads
// from both planes, so that each is registered in one cell only: a ray that
// reaches one crosses the two planes within a few pads of each other, and
// must be walked across them in the right order (or it skips the patch's
// cell), after crossing many planes on its way there.
TEST(GridTest, EdgeHuggingPatchesMatchBruteForce) {
  // Two anchor quads fix the bounds, so a first scene of the same size gives
  // the lattice (as in CellAlignedSceneMatchesBruteForce).
  auto anchored = [](TestScene* s) {
    AddAxisQuad(2, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, +1, s);
    AddAxisQuad(2, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f, -1, s);
  };
  const int kCount = 1200;
  std::mt19937 rng(47);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene first;
  anchored(&first);
  AddRandomPatches(rng, kCount, glm::vec3(0.3f), glm::vec3(0.7f), 0.01f, 0.02f, &first);
  Grid::Plan plan =
      Grid::MakePlan(Span<const Patch>(first.patches.data(), first.patches.size()), 8.0f);
  const Bounds& bb = plan.bounds;
  glm::vec3 cell = (bb.hi - bb.lo) / glm::vec3(plan.res[0], plan.res[1], plan.res[2]);
  const float pad = 4e-5f;  // kPadRel times the scene magnitude, 1 here
  TestScene s;
  anchored(&s);
  std::vector<glm::vec3> targets;
  while (static_cast<int>(s.patches.size()) < kCount + 2) {
    // The edge along axis c where planes of axes a and b meet; the patch
    // faces along c, 4 pads off both planes, one pad across.
    int c = static_cast<int>(rng() % 3), a = (c + 1) % 3, b = (c + 2) % 3;
    glm::vec3 p;
    for (int q : {a, b}) {
      int k = 2 + static_cast<int>(rng() % (plan.res[q] - 3));
      p[q] = bb.lo[q] + static_cast<float>(k) * cell[q] + (rng() % 2 ? 4.0f : -4.0f) * pad;
    }
    int k = 1 + static_cast<int>(rng() % (plan.res[c] - 2));
    p[c] = bb.lo[c] + (static_cast<float>(k) + 0.2f + 0.6f * u01(rng)) * cell[c];
    targets.push_back(p);
    AddAxisQuad(c, p[c], p[a] - 0.5f * pad, p[a] + 0.5f * pad, p[b] - 0.5f * pad, p[b] + 0.5f * pad,
                rng() % 2 ? 1 : -1, &s);
  }
  BuiltGrid b;
  BuildGrid(s, 8.0f, &b);
  ASSERT_EQ(b.plan.bounds.lo, plan.bounds.lo);
  ASSERT_EQ(b.plan.bounds.hi, plan.bounds.hi);
  for (int a = 0; a < 3; ++a) ASSERT_EQ(b.plan.res[a], plan.res[a]);
  // Each target is registered in one cell.
  std::vector<int> cells(s.patches.size(), 0);
  for (uint32_t r : b.grid.refs()) ++cells[r];
  for (size_t i = 2; i < s.patches.size(); ++i) ASSERT_EQ(cells[i], 1) << "patch " << i;

  Checker ck{s, b.grid};
  for (int i = 0; i < 20000; ++i) {
    glm::vec3 target = targets[rng() % targets.size()];
    // From a random point on the grid's box, so many planes lie on the way.
    glm::vec3 o = bb.lo + glm::vec3(u01(rng), u01(rng), u01(rng)) * (bb.hi - bb.lo);
    int face = static_cast<int>(rng() % 3);
    o[face] = rng() % 2 ? bb.lo[face] : bb.hi[face];
    ck.Check(Ray{o, target - o, 0.0f, kInf}, kNoPatch, "edge-hugging");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_GT(ck.hits, ck.rays / 2);
}

// Long walks: a grid 1024 cells long, rays along it from end to end, so the
// per-axis plane formula is taken out to its last plane.
TEST(GridTest, LongWalksMatchBruteForce) {
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  TestScene s;
  for (int i = 0; i < 3000; ++i) {
    int axis = i % 3;
    float x = 1000.0f * u01(rng), w = axis == 0 ? x : u01(rng);
    AddAxisQuad(axis, w, 0.0f, 0.2f, 0.0f, 0.2f, i % 2 ? 1 : -1, &s);
    // Spread over the cross-section, off the quad's own plane.
    glm::vec3 shift(axis == 0 ? 0.0f : x, axis == 1 ? 0.0f : 0.8f * u01(rng),
                    axis == 2 ? 0.0f : 0.8f * u01(rng));
    Patch& p = s.patches.back();
    for (glm::vec3& c : p.corner) c += shift;
    s.geom.back() = MakePatchGeom(p);
  }
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  ASSERT_EQ(b.plan.res[0], 1024);
  Checker ck{s, b.grid};
  const Bounds& bb = b.plan.bounds;
  for (int i = 0; i < 3000; ++i) {
    // From beyond one end to beyond the other, slightly off the axis.
    float side = i % 2 ? 1.0f : -1.0f;
    glm::vec3 o(side > 0 ? bb.lo.x - 1.0f : bb.hi.x + 1.0f, u01(rng), u01(rng));
    glm::vec3 target(side > 0 ? bb.hi.x : bb.lo.x, u01(rng), u01(rng));
    ck.CheckWithSkips(Ray{o, target - o, 0.0f, kInf}, "along");
    // Exactly along the axis, from a cell plane.
    int k = static_cast<int>(rng() % (b.plan.res[0] + 1));
    float cell = (bb.hi.x - bb.lo.x) / b.plan.res[0];
    glm::vec3 o2(bb.lo.x + static_cast<float>(k) * cell, u01(rng), u01(rng));
    ck.CheckWithSkips(Ray{o2, glm::vec3(side, 0.0f, 0.0f), 0.0f, kInf}, "axis");
  }
  EXPECT_EQ(ck.failures, 0) << ck.rays << " rays";
  EXPECT_GT(ck.hits, ck.rays / 4);
}

TEST(GridTest, EdgeCases) {
  TestScene s = CornellScene(4);
  BuiltGrid b;
  BuildGrid(s, 4.0f, &b);
  Hit hit;
  // Zero direction, empty interval, reversed interval: no hit.
  EXPECT_FALSE(b.grid.Intersect(Ray{glm::vec3(0.5f), glm::vec3(0.0f), 0.0f, kInf}, kNoPatch, &hit));
  EXPECT_FALSE(b.grid.Occluded(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.3f, 0.3f}, kNoPatch));
  EXPECT_FALSE(b.grid.Occluded(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.4f, 0.1f}, kNoPatch));
  // Straight up from the floor's centre line through the light.
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.5f, 0.0f, 0.5f), glm::vec3(0, 1, 0), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_FLOAT_EQ(hit.t, 0.999f);
  EXPECT_TRUE(hit.front);
  // Along the floor plane: the floor is never hit edge-on, the right wall is.
  ASSERT_TRUE(b.grid.Intersect(Ray{glm::vec3(0.1f, 0.0f, 0.1f), glm::vec3(1, 0, 0), 0.0f, kInf},
                               kNoPatch, &hit));
  EXPECT_FLOAT_EQ(hit.t, 0.9f);
  EXPECT_TRUE(hit.front);  // the right wall faces -x, into the box
  // Shared edges between wall quads leave no crack.
  for (int i = 0; i <= 16; ++i) {
    float x = i / 16.0f;
    EXPECT_TRUE(
        b.grid.Occluded(Ray{glm::vec3(x, 0.5f, 0.9f), glm::vec3(0, 0, -1), 0.0f, kInf}, kNoPatch))
        << x;
  }
  // An empty grid answers every ray with a miss.
  TestScene none;
  BuiltGrid e;
  BuildGrid(none, 4.0f, &e);
  EXPECT_EQ(e.plan.refs, 0u);
  EXPECT_FALSE(
      e.grid.Intersect(Ray{glm::vec3(0.5f), glm::vec3(0, 1, 0), 0.0f, kInf}, kNoPatch, &hit));
  EXPECT_FALSE(e.grid.Occluded(Ray{glm::vec3(-3.0f), glm::vec3(1, 1, 1), 0.0f, kInf}, kNoPatch));
  // Out of the open front: nothing.
  EXPECT_FALSE(
      b.grid.Occluded(Ray{glm::vec3(0.1f, 0.9f, 0.9f), glm::vec3(0, 0, 1), 0.0f, kInf}, kNoPatch));
}

// Closest-hit throughput on 10k random patches (run with
// --gtest_also_run_disabled_tests; prints rays/s).
TEST(GridTest, DISABLED_Throughput) {
  std::mt19937 rng(21);
  TestScene s;
  AddRandomPatches(rng, 10000, glm::vec3(0.0f), glm::vec3(1.0f), 0.01f, 0.1f, &s);
  const int kRays = 1000000;
  std::vector<Ray> rays(kRays);
  std::vector<uint32_t> from(kRays);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (int i = 0; i < kRays; ++i) {
    uint32_t p = static_cast<uint32_t>(u01(rng) * 10000) % 10000;
    glm::vec3 d = UnitVector(rng);
    if (glm::dot(d, s.patches[p].normal) < 0.0f) d = -d;
    rays[i] = Ray{PointOnPatch(rng, s.patches[p]), d, 1e-5f, kInf};
    from[i] = p;
  }
  for (float density : {1.0f, 2.0f, 4.0f, 8.0f}) {
    BuiltGrid b;
    auto t0 = std::chrono::steady_clock::now();
    BuildGrid(s, density, &b);
    auto t1 = std::chrono::steady_clock::now();
    int hits = 0;
    Hit hit;
    for (int i = 0; i < kRays; ++i) hits += b.grid.Intersect(rays[i], from[i], &hit);
    auto t2 = std::chrono::steady_clock::now();
    int occluded = 0;
    for (int i = 0; i < kRays; ++i) occluded += b.grid.Occluded(rays[i], from[i]);
    auto t3 = std::chrono::steady_clock::now();
    double build = std::chrono::duration<double>(t1 - t0).count();
    double closest = std::chrono::duration<double>(t2 - t1).count();
    double any = std::chrono::duration<double>(t3 - t2).count();
    std::printf(
        "density %.0f: res %dx%dx%d, refs %llu (%.2f/patch), %zu KB, build %.3f s; "
        "closest %.2f Mrays/s (%d hits), occluded %.2f Mrays/s\n",
        density, b.plan.res[0], b.plan.res[1], b.plan.res[2],
        static_cast<unsigned long long>(b.plan.refs), b.plan.refs / 10000.0, b.grid.bytes() / 1024,
        build, kRays / closest / 1e6, hits, kRays / any / 1e6);
    EXPECT_EQ(hits, occluded);
  }
}

// Closest-hit and any-hit throughput on a Cornell box of about 5k patches
// with rays as the solver casts them (run with --gtest_also_run_disabled_tests;
// prints rays/s per density).
TEST(GridTest, DISABLED_CornellThroughput) {
  TestScene s = CornellScene(30);
  std::vector<Ray> rays;
  std::vector<uint32_t> from;
  const int kRays = 1000000;
  SolverRays(s, 59, kRays, &rays, &from);
  for (float density : {1.0f, 2.0f, 4.0f, 8.0f}) {
    BuiltGrid b;
    BuildGrid(s, density, &b);
    int hits = 0, occluded = 0;
    Hit hit;
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRays; ++i) hits += b.grid.Intersect(rays[i], from[i], &hit);
    auto t1 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRays; ++i) occluded += b.grid.Occluded(rays[i], from[i]);
    auto t2 = std::chrono::steady_clock::now();
    double closest = std::chrono::duration<double>(t1 - t0).count();
    double any = std::chrono::duration<double>(t2 - t1).count();
    std::printf(
        "density %.0f: %zu patches, res %dx%dx%d, refs %llu; closest %.2f Mrays/s (%d hits), "
        "occluded %.2f Mrays/s\n",
        density, s.patches.size(), b.plan.res[0], b.plan.res[1], b.plan.res[2],
        static_cast<unsigned long long>(b.plan.refs), kRays / closest / 1e6, hits,
        kRays / any / 1e6);
    EXPECT_EQ(hits, occluded);
  }
}

}  // namespace
}  // namespace vismask
