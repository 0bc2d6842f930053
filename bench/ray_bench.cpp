// Ray-casting benchmark: vismask's grid against Embree 3, single thread, on
// the Cornell box meshed by vismask's own mesher. The only binary that links
// Embree (and Google Benchmark); vismask and its tests never do.
//
// For each --patch-size: the same rays go to the grid (Intersect, Occluded)
// and to Embree (rtcIntersect1, rtcOccluded1) over two geometries built from
// the same patches: triangles (a quad patch is 2 triangles, a triangle patch
// is 1) and Embree's native quads (one per patch). Two ray sets:
//   uniform - origins uniform in the scene's bounding box, directions uniform
//             on the sphere;
//   cosine  - rays as a shot casts them (src/trace.cpp): shooters drawn
//             uniformly by patch index, each shot's stream from ShotKey, a
//             uniform point on the patch and a cosine-distributed direction.
// Cosine rays start kLift in front of their shooter (Embree cannot skip the
// shooter as the grid does; the grid is given the shooter to skip as well,
// as in the solver), every ray at tMin = kTMin. Before timing, every ray's
// hit is compared (patch id and t).
//
// Usage: vismask_bench [--md FILE] [--sizes L1,L2,...] [--rays N]
//                      [--shooters N] [--reps N] [--density D] [google-benchmark flags]
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "vismask/arena.h"
#include "vismask/environment.h"
#include "vismask/grid.h"
#include "vismask/mesh.h"
#include "vismask/rng.h"
#include "vismask/sampling.h"
#include "vismask/scene.h"

namespace vismask {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kTMin = 1e-3f;  // scene units (mm): far below any patch size
constexpr float kLift = 1e-2f;  // cosine rays start this far in front of the shooter (mm)

struct Args {
  std::string md;
  std::string scene = "scenes/cornell.obj";
  std::vector<float> sizes = {80.0f, 19.5f, 4.7f};
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

bool MemoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
  EmbreeDevice* d = static_cast<EmbreeDevice*>(user);
  d->bytes += bytes;
  d->peak = std::max(d->peak, d->bytes);
  return true;
}

struct EmbreeScene {
  RTCScene scene = nullptr;
  std::vector<float> vertices;  // shared with Embree (x, y, z per vertex, one float pad)
  std::vector<uint32_t> indices;
  std::vector<uint32_t> primPatch;  // primitive -> patch
  long long bvhBytes = 0;           // what the memory monitor saw the commit keep
  long long buildPeakBytes = 0;
  double buildSeconds = 0.0;
};

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

void ToEmbree(const Ray& r, RTCRay* e) {
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
  float patchSize = 0.0f;
  std::vector<Patch> patches;
  std::vector<PatchGeom> geom;
  Grid::Plan plan;
  std::unique_ptr<Arena> arena;
  Grid grid;
  double buildSeconds = 0.0;
  size_t quads = 0, triangles = 0;
  Bounds bounds;
};

void BuildVis(const Scene& scene, float patchSize, float density, VisScene* v) {
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
  v->plan = Grid::MakePlan(ps, density);
  Arena measure = Arena::Measure();
  Grid probe;
  probe.Layout(measure, v->plan);
  v->arena = std::make_unique<Arena>(ArenaRoundUp(measure.used()));
  v->grid.Layout(*v->arena, v->plan);
  v->grid.Build(ps, Span<const PatchGeom>(v->geom.data(), v->geom.size()));
  v->buildSeconds = Now() - t0;
  v->bounds = scene.bounds;
}

// ---- ray sets ----

struct RaySet {
  std::string name;
  std::vector<Ray> rays;
  std::vector<uint32_t> skip;  // the shooter, or kNoPatch
};

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

// ---- the hit comparison ----

struct Agreement {
  size_t rays = 0;
  size_t same = 0;        // same patch (or both miss)
  size_t tie = 0;         // different patches at the same t: a shared edge or corner
  size_t onlyVis = 0;     // the grid hits, Embree misses
  size_t onlyEmbree = 0;  // Embree hits, the grid misses
  size_t other = 0;       // different patches at different t
  size_t occludedDiffer = 0;
  size_t hits = 0;
};

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

struct Stat {
  double median = 0, min = 0, max = 0;
  int n = 0;
};

Stat StatOf(std::vector<double> v) {
  Stat s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  s.n = static_cast<int>(n);
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  s.min = v.front();
  s.max = v.back();
  return s;
}

std::string Mrays(const Stat& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.2f (%.2f–%.2f)", s.median / 1e6, s.min / 1e6, s.max / 1e6);
  return buf;
}

Args ParseArgs(int* argc, char** argv) {
  Args a;
  int out = 1;
  for (int i = 1; i < *argc; ++i) {
    std::string s = argv[i];
    auto value = [&](const char* name) -> const char* {
      if (i + 1 >= *argc) {
        std::fprintf(stderr, "vismask_bench: %s needs a value\n", name);
        std::exit(2);
      }
      return argv[++i];
    };
    if (s == "--md") {
      a.md = value("--md");
    } else if (s == "--scene") {
      a.scene = value("--scene");
    } else if (s == "--sizes") {
      a.sizes.clear();
      std::string list = value("--sizes");
      for (size_t p = 0; p < list.size();) {
        size_t q = list.find(',', p);
        if (q == std::string::npos) q = list.size();
        a.sizes.push_back(std::strtof(list.substr(p, q - p).c_str(), nullptr));
        p = q + 1;
      }
    } else if (s == "--rays") {
      a.rays = std::atoi(value("--rays"));
    } else if (s == "--shooters") {
      a.shooters = std::atoi(value("--shooters"));
    } else if (s == "--density") {
      a.density = std::strtof(value("--density"), nullptr);
    } else if (s == "--reps") {
      a.reps = std::atoi(value("--reps"));
    } else {
      argv[out++] = argv[i];  // Google Benchmark's
    }
  }
  *argc = out;
  return a;
}

}  // namespace
}  // namespace vismask

int main(int argc, char** argv) {
  using namespace vismask;
  Args args = ParseArgs(&argc, argv);
  benchmark::Initialize(&argc, argv);
  Scene scene;
  Status st = LoadScene(args.scene, &scene);
  if (!st.ok()) {
    std::fprintf(stderr, "%s\n", st.ToString().c_str());
    return 2;
  }
  EmbreeDevice dev;
  dev.device = rtcNewDevice("threads=1");  // one build thread: the comparison is single-threaded
  if (!dev.device) {
    std::fprintf(stderr, "vismask_bench: rtcNewDevice failed\n");
    return 1;
  }
  rtcSetDeviceMemoryMonitorFunction(dev.device, MemoryMonitor, &dev);

  struct Case {
    VisScene vis;
    EmbreeScene tri, quad;
    RaySet sets[2];
    Agreement agree[2][2];  // [set][tri, quad]
  };
  std::vector<std::unique_ptr<Case>> cases;
  for (float size : args.sizes) {
    auto c = std::make_unique<Case>();
    BuildVis(scene, size, args.density, &c->vis);
    BuildEmbree(&dev, c->vis.patches, false, &c->tri);
    BuildEmbree(&dev, c->vis.patches, true, &c->quad);
    UniformRays(c->vis, args.rays, &c->sets[0]);
    CosineRays(c->vis, args.rays, args.shooters, &c->sets[1]);
    for (int s = 0; s < 2; ++s) {
      c->agree[s][0] = Compare(c->vis, c->tri, c->sets[s]);
      c->agree[s][1] = Compare(c->vis, c->quad, c->sets[s]);
    }
    std::fprintf(stderr, "vismask_bench: patch size %g: %zu patches, grid %dx%dx%d\n", size,
                 c->vis.patches.size(), c->vis.plan.res[0], c->vis.plan.res[1], c->vis.plan.res[2]);
    cases.push_back(std::move(c));
  }

  // One benchmark per (scene, ray set, engine, query); an iteration casts the
  // whole ray set once.
  for (size_t ci = 0; ci < cases.size(); ++ci) {
    Case* c = cases[ci].get();
    for (int s = 0; s < 2; ++s) {
      const RaySet* set = &c->sets[s];
      std::string tag = std::to_string(ci) + "/" + set->name + "/";
      auto reg = [&](const std::string& name, auto fn) {
        benchmark::RegisterBenchmark((tag + name).c_str(), fn)
            ->Repetitions(args.reps)
            ->ReportAggregatesOnly(false)
            ->Unit(benchmark::kMillisecond);
      };
      reg("vismask_intersect", [c, set](benchmark::State& state) {
        const Ray* rays = set->rays.data();
        const uint32_t* skip = set->skip.data();
        size_t n = set->rays.size();
        for (auto _ : state) {
          uint32_t hits = 0;
          for (size_t i = 0; i < n; ++i) {
            Hit hit;
            hits += c->vis.grid.Intersect(rays[i], skip[i], &hit);
          }
          benchmark::DoNotOptimize(hits);
        }
        state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n));
      });
      reg("vismask_occluded", [c, set](benchmark::State& state) {
        const Ray* rays = set->rays.data();
        const uint32_t* skip = set->skip.data();
        size_t n = set->rays.size();
        for (auto _ : state) {
          uint32_t hits = 0;
          for (size_t i = 0; i < n; ++i) hits += c->vis.grid.Occluded(rays[i], skip[i]);
          benchmark::DoNotOptimize(hits);
        }
        state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n));
      });
      for (int q = 0; q < 2; ++q) {
        const EmbreeScene* e = q ? &c->quad : &c->tri;
        std::string kind = q ? "embree_quad" : "embree_tri";
        reg(kind + "_intersect", [e, set](benchmark::State& state) {
          RTCIntersectContext ctx;
          rtcInitIntersectContext(&ctx);
          const Ray* rays = set->rays.data();
          size_t n = set->rays.size();
          for (auto _ : state) {
            uint32_t hits = 0;
            for (size_t i = 0; i < n; ++i) {
              uint32_t prim;
              float t;
              hits += EmbreeIntersect(e->scene, &ctx, rays[i], &prim, &t);
            }
            benchmark::DoNotOptimize(hits);
          }
          state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n));
        });
        reg(kind + "_occluded", [e, set](benchmark::State& state) {
          RTCIntersectContext ctx;
          rtcInitIntersectContext(&ctx);
          const Ray* rays = set->rays.data();
          size_t n = set->rays.size();
          for (auto _ : state) {
            uint32_t hits = 0;
            for (size_t i = 0; i < n; ++i) hits += EmbreeOccluded(e->scene, &ctx, rays[i]);
            benchmark::DoNotOptimize(hits);
          }
          state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n));
        });
      }
    }
  }
  Collector collector;
  benchmark::RunSpecifiedBenchmarks(&collector);
  benchmark::Shutdown();

  // ---- the markdown section ----
  FILE* md = args.md.empty() ? stdout : std::fopen(args.md.c_str(), "w");
  if (!md) {
    std::fprintf(stderr, "vismask_bench: cannot write %s\n", args.md.c_str());
    return 1;
  }
  std::fprintf(
      md,
      "Embree %s (Debian's libembree-dev), device `threads=1`; build quality default. "
      "%d rays per set, %d repetitions; figures are Mrays/s of CPU time, median (min–max).\n\n",
      RTC_VERSION_STRING, args.rays, args.reps);
  std::fprintf(md, "### Scenes and memory\n\n");
  std::fprintf(
      md,
      "| --patch-size | patches (quads + triangles) | Embree triangles | grid cells | "
      "grid refs | grid bytes | + PatchGeom (80 B/patch) | **vismask B/patch** | "
      "Embree tri BVH bytes | **B/patch** (B/triangle) | Embree quad BVH bytes | **B/patch** | "
      "vismask ÷ Embree tri | build s (grid / tri / quad) |\n");
  std::fprintf(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& cp : cases) {
    const Case& c = *cp;
    size_t n = c.vis.patches.size();
    size_t tris = c.tri.primPatch.size();
    double gridBytes = static_cast<double>(c.vis.grid.bytes());
    double visBytes = gridBytes + 80.0 * n;
    std::fprintf(md,
                 "| %g | %zu (%zu + %zu) | %zu | %zu | %llu | %.0f | %.0f | **%.1f** | %lld | "
                 "**%.1f** (%.1f) | "
                 "%lld | **%.1f** | %.2f | %.3f / %.3f / %.3f |\n",
                 c.vis.patchSize, n, c.vis.quads, c.vis.triangles, tris, c.vis.grid.cellCount(),
                 static_cast<unsigned long long>(c.vis.plan.refs), gridBytes, visBytes,
                 visBytes / n, c.tri.bvhBytes, double(c.tri.bvhBytes) / n,
                 double(c.tri.bvhBytes) / tris, c.quad.bvhBytes, double(c.quad.bvhBytes) / n,
                 visBytes / c.tri.bvhBytes, c.vis.buildSeconds, c.tri.buildSeconds,
                 c.quad.buildSeconds);
  }
  std::fprintf(
      md,
      "\n### Same hits\n\nEvery ray of every set, closest hit, grid against Embree "
      "(\"tie\": another patch at the same t, within 1e-4 relative: a ray through a shared "
      "edge or corner, where the grid takes the lower patch index and Embree either one).\n\n");
  std::fprintf(md,
               "| patches | rays | Embree geometry | rays | same patch | tie at shared edge | "
               "only grid hits | only Embree hits | different | any-hit ≠ closest-hit |\n");
  std::fprintf(md, "|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& cp : cases) {
    for (int s = 0; s < 2; ++s) {
      for (int q = 0; q < 2; ++q) {
        const Agreement& a = cp->agree[s][q];
        std::fprintf(md, "| %zu | %s | %s | %zu | %zu | %zu | %zu | %zu | %zu | %zu |\n",
                     cp->vis.patches.size(), cp->sets[s].name.c_str(), q ? "quads" : "triangles",
                     a.rays, a.same, a.tie, a.onlyVis, a.onlyEmbree, a.other, a.occludedDiffer);
      }
    }
  }
  std::fprintf(md, "\n### Rays per second (single thread)\n\n");
  std::fprintf(md,
               "| patches | rays | query | vismask grid | Embree triangles | Embree quads | "
               "**grid ÷ Embree tri** | grid ÷ Embree quad |\n");
  std::fprintf(md, "|---|---|---|---|---|---|---|---|\n");
  for (size_t ci = 0; ci < cases.size(); ++ci) {
    for (int s = 0; s < 2; ++s) {
      for (const char* query : {"intersect", "occluded"}) {
        std::string tag = std::to_string(ci) + "/" + cases[ci]->sets[s].name + "/";
        Stat v = StatOf(collector.rates[tag + "vismask_" + query]);
        Stat t = StatOf(collector.rates[tag + "embree_tri_" + query]);
        Stat q = StatOf(collector.rates[tag + "embree_quad_" + query]);
        std::fprintf(md, "| %zu | %s | %s | %s | %s | %s | **%.2f×** | %.2f× |\n",
                     cases[ci]->vis.patches.size(), cases[ci]->sets[s].name.c_str(),
                     std::strcmp(query, "intersect") ? "any hit (Occluded / rtcOccluded1)"
                                                     : "closest (Intersect / rtcIntersect1)",
                     Mrays(v).c_str(), Mrays(t).c_str(), Mrays(q).c_str(),
                     t.median > 0 ? v.median / t.median : 0.0,
                     q.median > 0 ? v.median / q.median : 0.0);
      }
    }
  }
  // The targets, judged from the figures above.
  double lo = 1e30, hi = 0.0, memLo = 1e30, memHi = 0.0, gridLo = 1e30, gridHi = 0.0;
  for (size_t ci = 0; ci < cases.size(); ++ci) {
    const Case& c = *cases[ci];
    for (int s = 0; s < 2; ++s) {
      for (const char* query : {"intersect", "occluded"}) {
        std::string tag = std::to_string(ci) + "/" + c.sets[s].name + "/";
        Stat v = StatOf(collector.rates[tag + "vismask_" + query]);
        Stat t = StatOf(collector.rates[tag + "embree_tri_" + query]);
        if (t.median <= 0) continue;
        lo = std::min(lo, v.median / t.median);
        hi = std::max(hi, v.median / t.median);
      }
    }
    double n = static_cast<double>(c.vis.patches.size());
    double mem = (c.vis.grid.bytes() + 80.0 * n) / c.tri.bvhBytes;
    double grid = static_cast<double>(c.vis.grid.bytes()) / c.tri.bvhBytes;
    memLo = std::min(memLo, mem);
    memHi = std::max(memHi, mem);
    gridLo = std::min(gridLo, grid);
    gridHi = std::max(gridHi, grid);
  }
  std::fprintf(
      md,
      "\n**Targets.** Rays/s ≥ 1.0× Embree (triangles): %s, the grid runs at %.2f× to %.2f× "
      "of Embree's rate. Memory ≤ 1/4 of Embree's BVH: %s, grid + PatchGeom is %.2f× to %.2f× "
      "of it (the grid's own arrays alone %.2f× to %.2f×).\n",
      lo >= 1.0 ? "**met**" : "**not met**", lo, hi, memHi <= 0.25 ? "**met**" : "**not met**",
      memLo, memHi, gridLo, gridHi);
  if (md != stdout) std::fclose(md);
  for (auto& c : cases) {
    rtcReleaseScene(c->tri.scene);
    rtcReleaseScene(c->quad.scene);
  }
  rtcReleaseDevice(dev.device);
  return 0;
}
