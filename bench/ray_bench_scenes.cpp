// The benchmark's scenes (Embree's and the grid's), ray sets and the hit
// comparison.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <glm/geometric.hpp>
#include <random>

#include "ray_bench.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"

namespace vismask::bench {

bool MemoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
  EmbreeDevice* d = static_cast<EmbreeDevice*>(user);
  d->bytes += bytes;
  d->peak = std::max(d->peak, d->bytes);
  return true;
}

double Now() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

void BuildEmbree(EmbreeDevice* dev, const std::vector<Patch>& patches, bool quads,
                 EmbreeScene* out) {
  for (const Patch& p : patches) {
    uint32_t base = static_cast<uint32_t>(out->vertices.size() / 3);
    for (uint32_t k = 0; k < p.numCorners; ++k)
      for (int a = 0; a < 3; ++a) out->vertices.push_back(p.corner[k][a]);
    uint32_t id = p.globalId;
    if (quads) {
      // A triangle is a quad whose last two corners are the same vertex.
      uint32_t last = p.numCorners == 4 ? base + 3 : base + 2;
      out->indices.insert(out->indices.end(), {base, base + 1, base + 2, last});
      out->primPatch.push_back(id);
    } else {
      out->indices.insert(out->indices.end(), {base, base + 1, base + 2});
      out->primPatch.push_back(id);
      if (p.numCorners == 4) {
        out->indices.insert(out->indices.end(), {base, base + 2, base + 3});
        out->primPatch.push_back(id);
      }
    }
  }
  out->vertices.push_back(0.0f);  // Embree reads 16 bytes at the last vertex
  size_t numVerts = (out->vertices.size() - 1) / 3;
  long long before = dev->bytes;
  dev->peak = dev->bytes;
  double t0 = Now();
  out->scene = rtcNewScene(dev->device);
  RTCGeometry g =
      rtcNewGeometry(dev->device, quads ? RTC_GEOMETRY_TYPE_QUAD : RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, out->vertices.data(),
                             0, 3 * sizeof(float), numVerts);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0,
                             quads ? RTC_FORMAT_UINT4 : RTC_FORMAT_UINT3, out->indices.data(), 0,
                             (quads ? 4 : 3) * sizeof(uint32_t), out->primPatch.size());
  rtcCommitGeometry(g);
  rtcAttachGeometry(out->scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(out->scene);
  out->buildSeconds = Now() - t0;
  out->bvhBytes = dev->bytes - before;
  out->buildPeakBytes = dev->peak - before;
  if (rtcGetDeviceError(dev->device) != RTC_ERROR_NONE) {
    std::fprintf(stderr, "vismask_bench: Embree scene build failed\n");
    std::exit(1);
  }
}

namespace {

// A grid laid out in its own arena (measured first, as an environment does).
// `work`: what MakePlan kept for Build, as an environment passes it.
void LayOut(const VisScene& v, const Grid::Plan& plan, Grid::Work* work,
            std::unique_ptr<Arena>* arena, Grid* grid) {
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, plan);
  *arena = std::make_unique<Arena>(ArenaRoundUp(measure.used()));
  grid->Layout(**arena, plan);
  grid->Build(Span<const Patch>(v.patches.data(), v.patches.size()),
              Span<const PatchGeom>(v.geom.data(), v.geom.size()), work);
}

}  // namespace

void BuildVis(const Scene& scene, float patchSize, float density, const Grid::Nest& nest,
              bool uniform, VisScene* v) {
  Mesh mesh;
  std::vector<uint32_t> all(scene.polygons.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  Status s = MeshScene(scene, all, patchSize, 50000000, &mesh);
  if (!s.ok()) {
    std::fprintf(stderr, "vismask_bench: %s\n", s.ToString().c_str());
    std::exit(2);
  }
  v->patchSize = patchSize;
  v->patches = std::move(mesh.patches);
  for (const Patch& p : v->patches) (p.numCorners == 4 ? v->quads : v->triangles)++;
  double t0 = Now();
  v->geom.resize(v->patches.size());
  for (size_t i = 0; i < v->patches.size(); ++i) v->geom[i] = MakePatchGeom(v->patches[i]);
  Span<const Patch> ps(v->patches.data(), v->patches.size());
  Grid::Work work;
  v->plan = Grid::MakePlan(ps, Span<const PatchGeom>(v->geom.data(), v->geom.size()), density, nest,
                           &work);
  LayOut(*v, v->plan, &work, &v->arena, &v->grid);
  v->buildSeconds = Now() - t0;
  if (uniform) {
    Grid::Nest none;
    none.minRefs = 0;
    v->uniformPlan = Grid::MakePlan(ps, Span<const PatchGeom>(v->geom.data(), v->geom.size()),
                                    density, none, &work);
    LayOut(*v, v->uniformPlan, &work, &v->uniformArena, &v->uniform);
  }
  v->bounds = scene.bounds;
}

void UniformRays(const VisScene& v, int n, RaySet* set) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  std::normal_distribution<float> g;
  set->name = "uniform";
  const Bounds& b = v.bounds;
  while (static_cast<int>(set->rays.size()) < n) {
    glm::vec3 o = b.lo + glm::vec3(u01(rng), u01(rng), u01(rng)) * (b.hi - b.lo);
    glm::vec3 d(g(rng), g(rng), g(rng));
    float len = glm::length(d);
    if (!(len > 1e-3f)) continue;
    set->rays.push_back(Ray{o, d / len, kTMin, kInf});
    set->skip.push_back(kNoPatch);
  }
}

void CosineRays(const VisScene& v, int n, int shooters, RaySet* set) {
  std::mt19937 rng(54321);
  set->name = "cosine";
  int perShot = (n + shooters - 1) / shooters;
  uint32_t count = static_cast<uint32_t>(v.patches.size());
  for (int s = 0; s < shooters && static_cast<int>(set->rays.size()) < n; ++s) {
    uint32_t id = rng() % count;
    const Patch& p = v.patches[id];
    PatchSampler sampler = MakePatchSampler(p);
    Rng r = ShotRng(ShotKey(1, p.globalId, 0));
    for (int k = 0; k < perShot && static_cast<int>(set->rays.size()) < n; ++k) {
      float u0 = r.NextFloat(), u1 = r.NextFloat(), u2 = r.NextFloat();
      float v1 = r.NextFloat(), v2 = r.NextFloat();
      // Lifted off the patch by kLift along its normal: Embree cannot skip the
      // shooter, and a point rounded to float can sit a few ulps behind it.
      glm::vec3 o = sampler.Point(u0, u1, u2) + kLift * p.normal;
      Ray ray{o, sampler.frame.ToWorld(CosineDirection(v1, v2)), kTMin, kInf};
      set->rays.push_back(ray);
      set->skip.push_back(id);
    }
  }
}

Agreement Compare(const VisScene& v, const EmbreeScene& e, const RaySet& set) {
  Agreement a;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (size_t i = 0; i < set.rays.size(); ++i) {
    const Ray& r = set.rays[i];
    Hit hit;
    bool hv = v.grid.Intersect(r, set.skip[i], &hit);
    uint32_t prim;
    float te;
    bool he = EmbreeIntersect(e.scene, &ctx, r, &prim, &te);
    ++a.rays;
    a.hits += hv;
    if (hv != v.grid.Occluded(r, set.skip[i]) || he != EmbreeOccluded(e.scene, &ctx, r))
      ++a.occludedDiffer;  // any-hit disagrees with closest-hit: never expected
    if (v.uniformArena) {  // the same hit, bit for bit, without sub-grids
      Hit hu;
      bool u = v.uniform.Intersect(r, set.skip[i], &hu);
      if (u != hv || u != v.uniform.Occluded(r, set.skip[i]) ||
          (u && (hu.patch != hit.patch || std::memcmp(&hu.t, &hit.t, sizeof hu.t) != 0 ||
                 hu.front != hit.front)))
        ++a.uniformDiffer;
    }
    if (!hv && !he) {
      ++a.same;
    } else if (hv && !he) {
      ++a.onlyVis;
    } else if (!hv && he) {
      ++a.onlyEmbree;
    } else if (e.primPatch[prim] == hit.patch) {
      ++a.same;
    } else if (std::fabs(te - hit.t) <= 1e-4f * std::max(1.0f, hit.t)) {
      ++a.tie;
    } else {
      ++a.other;
    }
    if (std::getenv("VISMASK_BENCH_DEBUG") &&
        !(hv == he && (!hv || e.primPatch[prim] == hit.patch)))
      std::fprintf(
          stderr, "ray %zu skip %u: grid %d patch %u t %.9g front %d | embree %d patch %u t %.9g\n",
          i, set.skip[i], hv, hit.patch, hit.t, hit.front, he, he ? e.primPatch[prim] : 0u, te);
  }
  return a;
}

}  // namespace vismask::bench
