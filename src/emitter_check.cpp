#include "vismask/emitter_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "vismask/arena.h"
#include "vismask/grid.h"
#include "vismask/mesh.h"
#include "vismask/rng.h"
#include "vismask/sampling.h"

namespace vismask {

namespace {

bool Emits(const Material& m) { return m.ke.x > 0.0f || m.ke.y > 0.0f || m.ke.z > 0.0f; }

// Percent, rounded down so that "100%" means every ray.
int Percent(double share) { return static_cast<int>(std::floor(100.0 * share + 1e-9)); }

}  // namespace

uint32_t EmitterCheckRays(uint64_t emitters) {
  if (emitters == 0) return kEmitterCheckRays;
  const uint64_t share = kEmitterCheckRayBudget / emitters;
  return static_cast<uint32_t>(std::max<uint64_t>(kEmitterCheckMinRays, std::min<uint64_t>(kEmitterCheckRays, share)));
}

std::vector<EmitterEstimate> EstimateEmitters(const Scene& scene) {
  std::vector<EmitterEstimate> out;
  const glm::vec3 extent = scene.bounds.hi - scene.bounds.lo;
  const float largest = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  const float diagonal = glm::length(extent);
  if (!(largest > 0.0f) || !std::isfinite(diagonal)) return out;

  // One patch per polygon (triangles for those that are not convex quads):
  // a patch size beyond every edge.
  Mesh mesh;
  std::vector<uint32_t> all(scene.polygons.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  if (!MeshScene(scene, all, 4.0f * diagonal, 16ull * all.size() + 16, &mesh).ok()) return out;
  const size_t n = mesh.patches.size();
  std::vector<PatchGeom> geom(n);
  for (size_t i = 0; i < n; ++i) geom[i] = MakePatchGeom(mesh.patches[i]);
  Span<const Patch> patches(mesh.patches.data(), n);
  Grid::Plan plan = Grid::MakePlan(patches, Span<const PatchGeom>(geom.data(), n), 4.0f);
  Grid grid;
  Arena measure = Arena::Measure();
  grid.Layout(measure, plan);
  Arena arena(ArenaRoundUp(measure.used()));
  grid.Layout(arena, plan);
  grid.Build(patches, Span<const PatchGeom>(geom.data(), n));

  // Ray origins lifted off the plane as the solver's are (app.cpp).
  const glm::vec3 mag = glm::max(glm::abs(scene.bounds.lo), glm::abs(scene.bounds.hi));
  const float eps = std::fmax(1e-6f * diagonal, 8.0f * std::numeric_limits<float>::epsilon() *
                                                     std::fmax(mag.x, std::fmax(mag.y, mag.z)));
  const double nearDistance = kEmitterNearShare * largest;

  uint64_t emitters = 0;
  for (const Polygon& poly : scene.polygons) emitters += Emits(scene.materials[poly.material]);
  const uint32_t rays = EmitterCheckRays(emitters);

  // Patches of a polygon are consecutive (mesh order is polygon order).
  size_t first = 0;
  while (first < n) {
    const uint32_t polygon = mesh.patches[first].surface;
    size_t end = first;
    double area = 0.0;
    while (end < n && mesh.patches[end].surface == polygon) area += mesh.patches[end++].area;
    const Polygon& poly = scene.polygons[polygon];
    if (!Emits(scene.materials[poly.material]) || !(area > 0.0)) {
      first = end;
      continue;
    }
    EmitterEstimate e;
    e.polygon = polygon;
    Rng rng(Mix64(0x656d6974746572ull ^ polygon), polygon);
    uint32_t nearHits = 0, escaped = 0, backEscaped = 0;
    double nearSum = 0.0;
    size_t k = first;
    double below = 0.0;  // area of the patches before k
    for (uint32_t r = 0; r < rays; ++r) {
      // Stratified over the polygon's area: ray r's share of it picks the patch.
      double at = (r + 0.5) / rays * area;
      while (k + 1 < end && below + mesh.patches[k].area <= at) below += mesh.patches[k++].area;
      for (int side = 0; side < 2; ++side) {
        Patch p = mesh.patches[k];
        if (side == 1) p.normal = -p.normal;
        PatchSampler s = MakePatchSampler(p);
        float u[5];
        for (float& x : u) x = rng.NextFloat();
        Ray ray{s.Point(u[0], u[1], u[2]) + eps * s.frame.n,
                s.frame.ToWorld(CosineDirection(u[3], u[4])), 0.0f,
                std::numeric_limits<float>::infinity()};
        Hit hit;
        bool any = grid.Intersect(ray, Skip(static_cast<uint32_t>(k)), &hit);
        if (side == 1) {
          backEscaped += !any;
        } else if (!any) {
          ++escaped;
        } else if (hit.t * glm::length(ray.d) <= nearDistance) {
          ++nearHits;
          nearSum += hit.t * glm::length(ray.d);
        }
      }
    }
    e.nearShare = static_cast<double>(nearHits) / rays;
    e.nearDistance = nearHits > 0 ? nearSum / nearHits : 0.0;
    e.escapeShare = static_cast<double>(escaped) / rays;
    e.backEscapeShare = static_cast<double>(backEscaped) / rays;
    out.push_back(e);
    first = end;
  }
  return out;
}

std::vector<std::string> EmitterWarnings(const Scene& scene) {
  std::vector<EmitterEstimate> all = EstimateEmitters(scene);
  std::vector<std::string> lines;
  std::vector<bool> done(scene.materials.size(), false);
  const glm::vec3 extent = scene.bounds.hi - scene.bounds.lo;
  const double largest = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  for (const EmitterEstimate& e : all) {
    const Polygon& poly = scene.polygons[e.polygon];
    if (done[poly.material] || !(e.nearWarning() || e.escapeWarning())) continue;
    done[poly.material] = true;
    // How many of this material's emitting faces warn, and of how many.
    size_t faces = 0, warn = 0;
    for (const EmitterEstimate& f : all) {
      if (scene.polygons[f.polygon].material != poly.material) continue;
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
    std::string line = scene.objPath + ":" + std::to_string(poly.line) + ": warning: emitter '" +
                       scene.materials[poly.material].name + "' " + what + tail;
    lines.push_back(line);
  }
  return lines;
}

}  // namespace vismask
