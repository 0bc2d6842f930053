#include "vismask/environment.h"

#include <unordered_map>

#include <glm/geometric.hpp>

#include "vismask/rng.h"
#include "vismask/sampling.h"

namespace vismask {

namespace {
double KeyOf(const PatchEnergy& e) { return e.unshot[0] + e.unshot[1] + e.unshot[2]; }
}  // namespace

void Environment::Layout(Arena& arena, uint32_t numPatches, uint32_t numVertices,
                         const Grid::Plan& plan) {
  patches_ = arena.Alloc<Patch>(numPatches);
  geom_ = arena.Alloc<PatchGeom>(numPatches);
  energy_ = arena.Alloc<PatchEnergy>(numPatches);
  shotCount_ = arena.Alloc<uint32_t>(numPatches);
  vertices_ = arena.Alloc<glm::vec3>(numVertices);
  vertexB_ = arena.Alloc<glm::vec3>(numVertices);
  vertexWeight_ = arena.Alloc<float>(numVertices);
  tree_.Layout(arena, numPatches);
  grid_.Layout(arena, plan);
}

void Environment::Init(uint32_t index, const Mesh& mesh, const std::vector<uint32_t>& ids,
                       const EnvOptions& options) {
  index_ = index;
  options_ = options;
  // Local copies of the patches and a compact local vertex lattice.
  std::vector<Patch> local;
  local.reserve(ids.size());
  std::unordered_map<uint32_t, uint32_t> vertexMap;
  std::vector<glm::vec3> verts;
  for (uint32_t id : ids) {
    Patch p = mesh.patches[id];
    for (int k = 0; k < 4; ++k) {
      auto it = vertexMap.find(p.vertex[k]);
      if (it == vertexMap.end()) {
        it = vertexMap.emplace(p.vertex[k], static_cast<uint32_t>(verts.size())).first;
        verts.push_back(mesh.vertices[p.vertex[k]]);
      }
      p.vertex[k] = it->second;
    }
    local.push_back(p);
  }
  uint32_t n = static_cast<uint32_t>(local.size());
  Grid::Plan plan = Grid::MakePlan(Span<const Patch>(local.data(), n), options.gridDensity);

  Arena measure = Arena::Measure();
  Layout(measure, n, static_cast<uint32_t>(verts.size()), plan);
  arena_ = Arena(measure.used());
  Layout(arena_, n, static_cast<uint32_t>(verts.size()), plan);

  totalArea_ = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    patches_[i] = local[i];
    geom_[i] = MakePatchGeom(local[i]);
    totalArea_ += local[i].area;
  }
  for (size_t v = 0; v < verts.size(); ++v) vertices_[v] = verts[v];
  grid_.Build(patches_, geom_);
  Reset();
}

void Environment::Reset() {
  ledger_ = EnergyLedger();
  stats_ = EnvStats();
  tree_.Clear();
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    const Patch& p = patches_[i];
    PatchEnergy& e = energy_[i];
    for (int c = 0; c < 3; ++c) {
      e.b[c] = p.ke[c];
      e.unshot[c] = static_cast<double>(p.ke[c]) * p.area;
      ledger_.emitted[c] += e.unshot[c];
      ledger_.unshot[c] += e.unshot[c];
    }
    shotCount_[i] = 0;
    tree_.Set(i, KeyOf(e));
  }
}

void Environment::Receive(uint32_t j, const double share[3]) {
  const Patch& p = patches_[j];
  PatchEnergy& e = energy_[j];
  double invArea = 1.0 / p.area;
  for (int c = 0; c < 3; ++c) {
    double reflected = share[c] * p.kd[c];
    e.b[c] += reflected * invArea;
    e.unshot[c] += reflected;
    ledger_.unshot[c] += reflected;
    ledger_.absorbed[c] += share[c] - reflected;
  }
  tree_.Set(j, KeyOf(e));
}

void Environment::Shoot(uint32_t i, uint32_t rays, uint64_t shotKey) {
  CHECK(i < patches_.size() && rays > 0);
  PatchEnergy& src = energy_[i];
  double share[3];
  for (int c = 0; c < 3; ++c) {
    share[c] = src.unshot[c] / rays;
    ledger_.unshot[c] -= src.unshot[c];
    src.unshot[c] = 0.0;
  }
  tree_.Set(i, 0.0);
  ++shotCount_[i];

  PatchSampler sampler = MakePatchSampler(patches_[i]);
  Rng rng = ShotRng(shotKey);
  uint64_t hits = 0;
  double lost[3] = {0, 0, 0};     // escaped
  double backHit[3] = {0, 0, 0};  // absorbed by back faces
  for (uint32_t r = 0; r < rays; ++r) {
    float u0 = rng.NextFloat(), u1 = rng.NextFloat(), u2 = rng.NextFloat();
    float v1 = rng.NextFloat(), v2 = rng.NextFloat();
    Ray ray;
    ray.o = sampler.Point(u0, u1, u2);
    ray.d = sampler.frame.ToWorld(CosineDirection(v1, v2));
    ray.tMin = options_.rayEpsilon;
    ray.tMax = std::numeric_limits<float>::infinity();
    Hit hit;
    if (!grid_.Intersect(ray, i, &hit)) {
      for (int c = 0; c < 3; ++c) lost[c] += share[c];
      continue;
    }
    ++hits;
    if (!hit.front) {
      for (int c = 0; c < 3; ++c) backHit[c] += share[c];
      continue;
    }
    Receive(hit.patch, share);
  }
  for (int c = 0; c < 3; ++c) {
    ledger_.escaped[c] += lost[c];
    ledger_.absorbed[c] += backHit[c];
  }
  stats_.shots += 1;
  stats_.rays += rays;
  stats_.hits += hits;
}

void Environment::ComputeVertexRadiosity(const double ambient[3]) {
  for (size_t v = 0; v < vertexB_.size(); ++v) {
    vertexB_[v] = glm::vec3(0.0f);
    vertexWeight_[v] = 0.0f;
  }
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    const Patch& p = patches_[i];
    glm::vec3 b;
    for (int c = 0; c < 3; ++c)
      b[c] = static_cast<float>(energy_[i].b[c] + p.kd[c] * ambient[c]);
    // Each distinct corner once (triangles repeat their last vertex).
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      vertexB_[p.vertex[k]] += p.area * b;
      vertexWeight_[p.vertex[k]] += p.area;
    }
  }
  for (size_t v = 0; v < vertexB_.size(); ++v)
    if (vertexWeight_[v] > 0.0f) vertexB_[v] /= vertexWeight_[v];
}

}  // namespace vismask
