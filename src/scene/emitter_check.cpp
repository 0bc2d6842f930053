#include "vismask/scene/emitter_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"

namespace vismask {

namespace {

bool Emits(const Material& m) {
  return m.ke.x > 0.0f || m.ke.y > 0.0f || m.ke.z > 0.0f;
}

// Percent, rounded down so that "100%" means every ray.
int Percent(double share) {
  return static_cast<int>(std::floor(100.0 * share + 1e-9));
}

}  // namespace

uint32_t EmitterCheckRays(uint64_t emitters) {
  if (emitters == 0) return kEmitterCheckRays;
  const uint64_t share = kEmitterCheckRayBudget / emitters;
  return static_cast<uint32_t>(
      std::max<uint64_t>(kEmitterCheckMinRays, std::min<uint64_t>(kEmitterCheckRays, share)));
}

EmitterCheck::EmitterCheck(const Bounds& bounds, const std::vector<Material>& materials,
                           const std::vector<std::pair<uint32_t, Polygon>>& emitters, size_t chunk)
    : chunk_(std::max<size_t>(1, chunk)), raysPer_(EmitterCheckRays(emitters.size())) {
  const glm::vec3 extent = bounds.hi - bounds.lo;
  const float largest = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  const float diagonal = glm::length(extent);
  if (!(largest > 0.0f) || !std::isfinite(diagonal)) {
    failed_ = true;
    return;
  }
  // One patch per polygon (triangles for those that are not convex quads):
  // a patch size beyond every edge.
  patchSize_ = 4.0f * diagonal;
  // Ray origins lifted off the plane as the solver's are (render_init.cpp).
  const glm::vec3 mag = glm::max(glm::abs(bounds.lo), glm::abs(bounds.hi));
  const float eps = std::fmax(1e-6f * diagonal, 8.0f * std::numeric_limits<float>::epsilon() *
                                                    std::fmax(mag.x, std::fmax(mag.y, mag.z)));
  nearDistance_ = kEmitterNearShare * largest;
  Scene one;
  one.materials = materials;
  // Reserved whole: growing by doubling would touch the old and the new
  // block at once (1.9 times the rays at the last step).
  rays_.reserve(emitters.size() * 2 * raysPer_);
  for (const auto& [polygon, poly] : emitters) {
    if (!Emits(materials[poly.material])) continue;
    one.polygons.assign(1, poly);
    Mesh mesh;
    if (!MeshScene(one, {0}, patchSize_, 32, &mesh).ok()) {
      failed_ = true;
      return;
    }
    const size_t end = mesh.patches.size();
    double area = 0.0;
    for (const Patch& p : mesh.patches) area += p.area;
    if (!(area > 0.0)) continue;
    Source src;
    src.polygon = polygon;
    src.material = poly.material;
    src.line = poly.line;
    src.firstRay = static_cast<uint32_t>(rays_.size());
    sources_.push_back(src);
    Rng rng(Mix64(0x656d6974746572ull ^ polygon), polygon);
    size_t k = 0;
    double below = 0.0;  // area of the patches before k
    for (uint32_t r = 0; r < raysPer_; ++r) {
      // Stratified over the polygon's area: ray r's share of it picks the patch.
      double at = (r + 0.5) / raysPer_ * area;
      while (k + 1 < end && below + mesh.patches[k].area <= at) below += mesh.patches[k++].area;
      for (int side = 0; side < 2; ++side) {
        Patch p = mesh.patches[k];
        if (side == 1) p.normal = -p.normal;
        PatchSampler s = MakePatchSampler(p);
        float u[5];
        for (float& x : u) x = rng.NextFloat();
        RayState ray;
        ray.o = s.Point(u[0], u[1], u[2]) + eps * s.frame.n;
        ray.d = s.frame.ToWorld(CosineDirection(u[3], u[4]));
        ray.patch = static_cast<uint32_t>(k);
        rays_.push_back(ray);
      }
    }
  }
  chunkScene_.materials = materials;
}

uint64_t EmitterCheck::HeapBytes(size_t emitters, size_t chunk) {
  // The rays, and a chunk's one-patch mesh (at most 8 triangles a polygon
  // are typical; a polygon of c corners makes c - 2), its geometry and grid
  // (refs at density 4 and a few cells per patch), as a bound per polygon.
  const uint64_t rays = uint64_t{emitters} * EmitterCheckRays(emitters) * 2 * sizeof(RayState);
  const uint64_t perPatch = sizeof(Patch) + 12 * 4 + sizeof(PatchGeom) + 64;
  return rays + uint64_t{chunk} * (sizeof(Polygon) + 256 + 4 * perPatch);
}

void EmitterCheck::Add(uint32_t index, const Polygon& p) {
  if (failed_ || sources_.empty()) return;
  if (chunkScene_.polygons.empty()) chunkFirst_ = index;
  chunkScene_.polygons.push_back(p);
  if (chunkScene_.polygons.size() >= chunk_) Flush();
}

void EmitterCheck::Flush() {
  const size_t n = chunkScene_.polygons.size();
  if (n == 0 || failed_) return;
  Mesh mesh;
  std::vector<uint32_t> all(n);
  for (uint32_t i = 0; i < n; ++i) all[i] = i;
  if (!MeshScene(chunkScene_, all, patchSize_, 16ull * n + 16, &mesh).ok()) {
    failed_ = true;
    return;
  }
  chunkScene_.polygons.clear();
  const size_t np = mesh.patches.size();
  // The first patch of each polygon of the chunk (mesh order is polygon order).
  std::vector<uint32_t> firstPatch(n + 1, 0);
  for (size_t i = np; i-- > 0;) firstPatch[mesh.patches[i].surface] = static_cast<uint32_t>(i);
  std::vector<PatchGeom> geom(np);
  for (size_t i = 0; i < np; ++i) geom[i] = MakePatchGeom(mesh.patches[i]);
  Span<const Patch> patches(mesh.patches.data(), np);
  Grid::Plan plan = Grid::MakePlan(patches, Span<const PatchGeom>(geom.data(), np), 4.0f);
  Grid grid;
  Arena measure = Arena::Measure();
  grid.Layout(measure, plan);
  Arena arena(ArenaRoundUp(measure.used()));
  grid.Layout(arena, plan);
  grid.Build(patches, Span<const PatchGeom>(geom.data(), np));
  for (const Source& src : sources_) {
    // A ray skips the patch it leaves, when that patch is in this chunk.
    const bool here = src.polygon >= chunkFirst_ && src.polygon < chunkFirst_ + n;
    const uint32_t base = here ? firstPatch[src.polygon - chunkFirst_] : 0;
    for (uint32_t r = 0; r < 2 * raysPer_; ++r) {
      RayState& s = rays_[src.firstRay + r];
      float tMax = std::numeric_limits<float>::infinity();
      if (s.t != kNoHit) {
        // A ray that hit already: a back ray's answer is in (it hit), a
        // front ray's can change only by a hit nearer than both its hit
        // and the near distance (with a margin over rounding: the near
        // test itself is made in Finish, as on one grid).
        if (r % 2 == 1) continue;
        const float nearT = static_cast<float>(nearDistance_ / glm::length(s.d)) * (1.0f + 1e-5f);
        tMax = std::min(s.t, nearT);
      }
      Ray ray{s.o, s.d, 0.0f, tMax};
      Hit hit;
      if (grid.Intersect(ray, Skip(here ? base + s.patch : kNoPatch), &hit) && hit.t < s.t)
        s.t = hit.t;
    }
  }
}

std::vector<EmitterEstimate> EmitterCheck::Finish() {
  Flush();
  std::vector<EmitterEstimate> out;
  if (failed_) return out;
  for (const Source& src : sources_) {
    EmitterEstimate e;
    e.polygon = src.polygon;
    e.material = src.material;
    e.line = src.line;
    uint32_t nearHits = 0, escaped = 0, backEscaped = 0;
    double nearSum = 0.0;
    for (uint32_t r = 0; r < raysPer_; ++r) {
      for (int side = 0; side < 2; ++side) {
        const RayState& s = rays_[src.firstRay + 2 * r + side];
        const bool any = s.t != kNoHit;
        if (side == 1) {
          backEscaped += !any;
        } else if (!any) {
          ++escaped;
        } else if (s.t * glm::length(s.d) <= nearDistance_) {
          ++nearHits;
          nearSum += s.t * glm::length(s.d);
        }
      }
    }
    e.nearShare = static_cast<double>(nearHits) / raysPer_;
    e.nearDistance = nearHits > 0 ? nearSum / nearHits : 0.0;
    e.escapeShare = static_cast<double>(escaped) / raysPer_;
    e.backEscapeShare = static_cast<double>(backEscaped) / raysPer_;
    out.push_back(e);
  }
  return out;
}

std::vector<EmitterEstimate> EstimateEmitters(const Scene& scene, size_t chunk) {
  std::vector<std::pair<uint32_t, Polygon>> emitters;
  for (uint32_t i = 0; i < scene.polygons.size(); ++i)
    if (Emits(scene.materials[scene.polygons[i].material]))
      emitters.emplace_back(i, scene.polygons[i]);
  EmitterCheck check(scene.bounds, scene.materials, emitters,
                     chunk == 0 ? scene.polygons.size() : chunk);
  for (uint32_t i = 0; i < scene.polygons.size(); ++i) check.Add(i, scene.polygons[i]);
  return check.Finish();
}

std::vector<std::string> EmitterWarnings(const Scene& scene) {
  return EmitterWarnings(EstimateEmitters(scene), scene.objPath, scene.materials, scene.bounds);
}

std::vector<std::string> EmitterWarnings(const std::vector<EmitterEstimate>& all,
                                         const std::string& objPath,
                                         const std::vector<Material>& materials,
                                         const Bounds& bounds) {
  std::vector<std::string> lines;
  std::vector<bool> done(materials.size(), false);
  const glm::vec3 extent = bounds.hi - bounds.lo;
  const double largest = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  for (const EmitterEstimate& e : all) {
    // A two-sided material (glTF doubleSided) emits from both sides already.
    if (materials[e.material].twoSided) continue;
    if (done[e.material] || !(e.nearWarning() || e.escapeWarning())) continue;
    done[e.material] = true;
    // How many of this material's emitting faces warn, and of how many.
    size_t faces = 0, warn = 0;
    for (const EmitterEstimate& f : all) {
      if (f.material != e.material) continue;
      ++faces;
      warn += f.nearWarning() || f.escapeWarning();
    }
    char what[256];
    if (e.nearWarning()) {
      std::snprintf(what, sizeof what,
                    "sends %d%% of its power into a surface it faces %.3g away, %.2g%% of the "
                    "scene's size",
                    Percent(e.nearShare), e.nearDistance, 100.0 * e.nearDistance / largest);
    } else {
      std::snprintf(what, sizeof what,
                    "sends %d%% of its power straight out of the scene, while its back faces "
                    "the scene",
                    Percent(e.escapeShare));
    }
    char tail[160];
    std::snprintf(tail, sizeof tail,
                  " (%zu of its %zu face%s; wound the wrong way? --two-sided-emitters makes both "
                  "sides emit)",
                  warn, faces, faces == 1 ? "" : "s");
    std::string line = objPath + ":" + std::to_string(e.line) + ": warning: emitter '" +
                       materials[e.material].name + "' " + what + tail;
    lines.push_back(line);
  }
  return lines;
}

}  // namespace vismask
