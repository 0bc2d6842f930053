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
//   cosine  - rays as a shot casts them (src/solve/trace.cpp): shooters drawn
//             uniformly by patch index, each shot's stream from ShotKey, a
//             uniform point on the patch and a cosine-distributed direction.
// Cosine rays start kLift in front of their shooter (Embree cannot skip the
// shooter as the grid does; the grid is given the shooter to skip as well,
// as in the solver), every ray at tMin = kTMin. Before timing, every ray's
// hit is compared (patch id and t).
//
// Usage: vismask_bench [--md FILE] [--scene FILE[@L1,L2,...]]... [--sizes L1,L2,...]
//                      [--rays N] [--shooters N] [--reps N] [--density D]
//                      [--nest-min N] [--nest-density D] [--uniform] [google-benchmark flags]
// --scene may be given several times, each with its own patch sizes after
// '@' (else --sizes'); --nest-min 0 builds the uniform grid (no sub-grids);
// --uniform also times the uniform grid beside the nested one (issue 45's
// before and after, the same rays).
#include "ray_bench.h"

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace vismask::bench {
namespace {

std::vector<float> ParseSizes(const std::string& list) {
  std::vector<float> sizes;
  for (size_t p = 0; p < list.size();) {
    size_t q = list.find(',', p);
    if (q == std::string::npos) q = list.size();
    sizes.push_back(std::strtof(list.substr(p, q - p).c_str(), nullptr));
    p = q + 1;
  }
  return sizes;
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
      a.scenes.push_back(value("--scene"));
    } else if (s == "--nest-min") {
      a.nest.minRefs = static_cast<uint32_t>(std::atoi(value("--nest-min")));
    } else if (s == "--nest-density") {
      a.nest.density = std::strtof(value("--nest-density"), nullptr);
    } else if (s == "--uniform") {
      a.uniform = true;
    } else if (s == "--sizes") {
      a.sizes = ParseSizes(value("--sizes"));
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
  if (a.scenes.empty()) a.scenes.push_back("scenes/cornell.obj");
  for (std::string& scene : a.scenes) {
    size_t at = scene.rfind('@');
    a.sceneSizes.push_back(at == std::string::npos ? a.sizes : ParseSizes(scene.substr(at + 1)));
    if (at != std::string::npos) scene.resize(at);
  }
  return a;
}

// Registers the benchmark `name`: an iteration casts the `n` rays of a set,
// `cast(i)` the i-th (true on a hit).
template <typename Cast>
void RegisterCasts(const std::string& name, int reps, size_t n, Cast cast) {
  benchmark::RegisterBenchmark(
      name.c_str(),
      [n, cast](benchmark::State& state) mutable {
        for (auto _ : state) {
          uint32_t hits = 0;
          for (size_t i = 0; i < n; ++i) hits += cast(i);
          benchmark::DoNotOptimize(hits);
        }
        state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n));
      })
      ->Repetitions(reps)
      ->ReportAggregatesOnly(false)
      ->Unit(benchmark::kMillisecond);
}

}  // namespace
}  // namespace vismask::bench

int main(int argc, char** argv) {
  using namespace vismask;
  using namespace vismask::bench;
  Args args = ParseArgs(&argc, argv);
  benchmark::Initialize(&argc, argv);
  EmbreeDevice dev;
  dev.device = rtcNewDevice("threads=1");  // one build thread: the comparison is single-threaded
  if (!dev.device) {
    std::fprintf(stderr, "vismask_bench: rtcNewDevice failed\n");
    return 1;
  }
  rtcSetDeviceMemoryMonitorFunction(dev.device, MemoryMonitor, &dev);

  std::vector<std::unique_ptr<Case>> cases;
  for (size_t si = 0; si < args.scenes.size(); ++si) {
    Scene scene;
    Status st = LoadScene(args.scenes[si], &scene);
    if (!st.ok()) {
      std::fprintf(stderr, "%s\n", st.ToString().c_str());
      return 2;
    }
    const std::string& path = args.scenes[si];
    for (float size : args.sceneSizes[si]) {
      auto c = std::make_unique<Case>();
      c->vis.scene = path.substr(path.rfind('/') + 1);
      BuildVis(scene, size, args.density, args.nest, args.uniform, &c->vis);
      BuildEmbree(&dev, c->vis.patches, false, &c->tri);
      BuildEmbree(&dev, c->vis.patches, true, &c->quad);
      UniformRays(c->vis, args.rays, &c->sets[0]);
      CosineRays(c->vis, args.rays, args.shooters, &c->sets[1]);
      for (int s = 0; s < 2; ++s) {
        c->agree[s][0] = Compare(c->vis, c->tri, c->sets[s]);
        c->agree[s][1] = Compare(c->vis, c->quad, c->sets[s]);
      }
      std::fprintf(
          stderr,
          "vismask_bench: %s at patch size %g: %zu patches, grid %dx%dx%d, %llu sub-grids\n",
          c->vis.scene.c_str(), size, c->vis.patches.size(), c->vis.plan.res[0], c->vis.plan.res[1],
          c->vis.plan.res[2], static_cast<unsigned long long>(c->vis.plan.subGrids));
      cases.push_back(std::move(c));
    }
  }

  // One benchmark per (scene, ray set, engine, query); an iteration casts the
  // whole ray set once.
  for (size_t ci = 0; ci < cases.size(); ++ci) {
    Case* c = cases[ci].get();
    for (int s = 0; s < 2; ++s) {
      const RaySet* set = &c->sets[s];
      std::string tag = std::to_string(ci) + "/" + set->name + "/";
      auto reg = [&](const std::string& name, auto cast) {
        RegisterCasts(tag + name, args.reps, set->rays.size(), cast);
      };
      const Ray* rays = set->rays.data();
      const uint32_t* skip = set->skip.data();
      reg("vismask_intersect", [c, rays, skip](size_t i) {
        Hit hit;
        return c->vis.grid.Intersect(rays[i], skip[i], &hit);
      });
      reg("vismask_occluded",
          [c, rays, skip](size_t i) { return c->vis.grid.Occluded(rays[i], skip[i]); });
      if (args.uniform) {
        reg("uniform_intersect", [c, rays, skip](size_t i) {
          Hit hit;
          return c->vis.uniform.Intersect(rays[i], skip[i], &hit);
        });
        reg("uniform_occluded",
            [c, rays, skip](size_t i) { return c->vis.uniform.Occluded(rays[i], skip[i]); });
      }
      for (int q = 0; q < 2; ++q) {
        const EmbreeScene* e = q ? &c->quad : &c->tri;
        std::string kind = q ? "embree_quad" : "embree_tri";
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        reg(kind + "_intersect", [e, rays, ctx](size_t i) mutable {
          uint32_t prim;
          float t;
          return EmbreeIntersect(e->scene, &ctx, rays[i], &prim, &t);
        });
        reg(kind + "_occluded",
            [e, rays, ctx](size_t i) mutable { return EmbreeOccluded(e->scene, &ctx, rays[i]); });
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
  WriteMarkdown(md, args, cases, collector);
  if (md != stdout) std::fclose(md);
  for (auto& c : cases) {
    rtcReleaseScene(c->tri.scene);
    rtcReleaseScene(c->quad.scene);
  }
  rtcReleaseDevice(dev.device);
  return 0;
}
