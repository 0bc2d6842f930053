// The ray-casting benchmark's parts (ray_bench.cpp): the scenes it builds
// for vismask's grid and for Embree, the ray sets, the hit comparison and
// the Markdown report.
#pragma once
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/environment.h"

namespace vismask::bench {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kTMin = 1e-3f;  // scene units (mm): far below any patch size
inline constexpr float kLift = 1e-2f;  // cosine rays start this far in front of the shooter (mm)

struct Args {
  std::string md;
  // The scenes, each with its patch sizes (--scene FILE[@L1,L2,...]; without
  // sizes, --sizes').
  std::vector<std::string> scenes;
  std::vector<std::vector<float>> sceneSizes;
  std::vector<float> sizes = {80.0f, 19.5f, 4.7f};
  Grid::Nest nest;       // the grid's sub-grids (--nest-min, --nest-density)
  bool uniform = false;  // also the uniform grid, for comparison (--uniform)
  int rays = 1 << 17;
  int shooters = 256;
  int reps = 5;
  float density = EnvOptions().gridDensity;  // as an environment plans its grid
};

// ---- Embree: a device with a memory monitor, and one scene per geometry ----

struct EmbreeDevice {
  RTCDevice device = nullptr;
  long long bytes = 0;  // held now, from the memory monitor
  long long peak = 0;
};

// Embree's memory monitor: keeps the device's bytes and their peak.
bool MemoryMonitor(void* user, ssize_t bytes, bool post);

struct EmbreeScene {
  RTCScene scene = nullptr;
  std::vector<float> vertices;  // shared with Embree (x, y, z per vertex, one float pad)
  std::vector<uint32_t> indices;
  std::vector<uint32_t> primPatch;  // primitive -> patch
  long long bvhBytes = 0;           // what the memory monitor saw the commit keep
  long long buildPeakBytes = 0;
  double buildSeconds = 0.0;
};

// CLOCK_MONOTONIC, in seconds.
double Now();

// The patches as Embree triangles (a quad patch is 2) or quads (one a patch).
void BuildEmbree(EmbreeDevice* dev, const std::vector<Patch>& patches, bool quads,
                 EmbreeScene* out);

inline void ToEmbree(const Ray& r, RTCRay* e) {
  e->org_x = r.o.x;
  e->org_y = r.o.y;
  e->org_z = r.o.z;
  e->dir_x = r.d.x;
  e->dir_y = r.d.y;
  e->dir_z = r.d.z;
  e->tnear = r.tMin;
  e->tfar = r.tMax;
  e->time = 0.0f;
  e->mask = 0xffffffffu;
  e->id = 0;
  e->flags = 0;
}

inline bool EmbreeIntersect(RTCScene s, RTCIntersectContext* ctx, const Ray& r, uint32_t* prim,
                            float* t) {
  RTCRayHit rh;
  ToEmbree(r, &rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(s, ctx, &rh);
  *prim = rh.hit.primID;
  *t = rh.ray.tfar;
  return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

inline bool EmbreeOccluded(RTCScene s, RTCIntersectContext* ctx, const Ray& r) {
  RTCRay ray;
  ToEmbree(r, &ray);
  rtcOccluded1(s, ctx, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

// ---- vismask: the patches, their ray-test data and the grid ----

struct VisScene {
  std::string scene;  // its file's name
  float patchSize = 0.0f;
  std::vector<Patch> patches;
  std::vector<PatchGeom> geom;
  Grid::Plan plan;
  std::unique_ptr<Arena> arena;
  Grid grid;
  double buildSeconds = 0.0;
  // The same patches in a uniform grid (no sub-grids), when asked for.
  Grid::Plan uniformPlan;
  std::unique_ptr<Arena> uniformArena;
  Grid uniform;
  size_t quads = 0, triangles = 0;
  Bounds bounds;
};

// `scene` meshed at `patchSize`, and the grid over its patches at `density`
// with sub-grids by `nest`; with `uniform`, also the grid without them.
void BuildVis(const Scene& scene, float patchSize, float density, const Grid::Nest& nest,
              bool uniform, VisScene* v);

// ---- ray sets ----

struct RaySet {
  std::string name;
  std::vector<Ray> rays;
  std::vector<uint32_t> skip;  // the shooter, or kNoPatch
};

// Origins uniform in the scene's box, directions uniform on the sphere.
void UniformRays(const VisScene& v, int n, RaySet* set);
// Rays as shots cast them, from `shooters` patches.
void CosineRays(const VisScene& v, int n, int shooters, RaySet* set);

// ---- the hit comparison ----

struct Agreement {
  size_t rays = 0;
  size_t same = 0;        // same patch (or both miss)
  size_t tie = 0;         // different patches at the same t: a shared edge or corner
  size_t onlyVis = 0;     // the grid hits, Embree misses
  size_t onlyEmbree = 0;  // Embree hits, the grid misses
  size_t other = 0;       // different patches at different t
  size_t occludedDiffer = 0;
  size_t uniformDiffer = 0;  // the uniform grid's closest or any hit is not the grid's
  size_t hits = 0;
};

// Every ray of `set`, closest and any hit, the grid against Embree.
Agreement Compare(const VisScene& v, const EmbreeScene& e, const RaySet& set);

// One patch size: its scenes, ray sets and agreements.
struct Case {
  VisScene vis;
  EmbreeScene tri, quad;
  RaySet sets[2];
  Agreement agree[2][2];  // [set][tri, quad]
};

// ---- results: Google Benchmark runs, kept per benchmark name ----

class Collector : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      auto it = r.counters.find("items_per_second");
      if (it != r.counters.end()) rates[r.run_name.function_name].push_back(it->second.value);
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, std::vector<double>> rates;
};

// The Markdown section of docs/BENCHMARKS.md from the cases and the rates.
void WriteMarkdown(FILE* md, const Args& args, const std::vector<std::unique_ptr<Case>>& cases,
                   Collector& collector);

}  // namespace vismask::bench
