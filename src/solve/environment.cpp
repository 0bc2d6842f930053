// Environment, its memory and init: the arena layout (Layout), what one
// environment holds and needs (Prepare, Build) and a solve's start (Reset).
// The rest of Environment is in env_receive.cpp (receiving, elements,
// display values), trace.cpp (rays) and env_queue.cpp (shots and the queue).
#include "vismask/solve/environment.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>
#include <type_traits>
#include <unordered_map>

#include "shot_ray.h"
#include "vismask/core/os.h"
#include "vismask/solve/centre_raster.h"
#include "vismask/solve/rng.h"

namespace vismask {

// What Prepare copies from the mesh for Build (on the heap, init only).
struct Environment::Staged {
  std::vector<Patch> patches;
  std::vector<PatchGeom> geom;
  std::vector<uint32_t> twin;     // empty without twins
  std::vector<PatchTexture> tex;  // empty when no patch is textured
  std::vector<OutsideShooter> outside;
  DisplayLattice::Staged lattice;
  Grid::Work gridWork;  // what MakePlan worked out, for grid_.Build
};

Span<const Patch> Environment::preparedPatches() const {
  if (staged_) return Span<const Patch>(staged_->patches.data(), staged_->patches.size());
  return patches_;
}

Environment::Environment() = default;
Environment::~Environment() = default;

// How many rays a local shot of `power` traces and what share of the
// power it carries (1 unless the shot is partial).
uint32_t Environment::ShotRays(const double power[3], double emission, uint64_t shotKey,
                               double* fraction) const {
  *fraction = 1.0;
  if (options_.rayQuantum <= 0.0) return options_.rays;
  const double worth = power[0] + power[1] + power[2] - (1.0 - options_.emissionRays) * emission;
  double x = std::fmax(worth, 0.0) / options_.rayQuantum;
  if (x > options_.rays) {
    *fraction = options_.rays / x;
    return options_.rays;
  }
  // Stochastic rounding from the shot's own stream: the same on every rank.
  double whole = std::floor(x);
  Rng rng(Mix64(shotKey ^ 0x5851f42d4c957f2dull), shotKey);
  uint32_t n = static_cast<uint32_t>(whole) + (rng.NextFloat() < x - whole ? 1u : 0u);
  return n < options_.minRays ? options_.minRays : n;
}

// Whether the centre-mask cache keeps known pixels too: C, and B when a
// local shot may read only (mayRead_, FillReadCosts).
bool Environment::PartCentres() const {
  return options_.maskMethod == MaskMethod::kC ||
         (options_.maskMethod == MaskMethod::kB && mayRead_);
}

void Environment::Layout(Arena& arena, uint32_t numPatches, const Grid::Plan& plan) {
  size_t mark = arena.used();
  auto part = [&](uint64_t* bytes) {
    *bytes = arena.used() - mark;
    mark = arena.used();
  };
  patches_ = arena.Alloc<Patch>(numPatches);
  geom_ = arena.Alloc<PatchGeom>(numPatches);
  twin_ = arena.Alloc<uint32_t>(staged_->twin.size());
  energy_ = arena.Alloc<PatchEnergy>(numPatches);
  shotCount_ = arena.Alloc<uint32_t>(numPatches);
  raysShot_ = arena.Alloc<uint32_t>(numPatches);
  outside_.Layout(arena, static_cast<uint32_t>(staged_->outside.size()));
  tree_.Layout(arena, numPatches);
  part(&footprint_.patches);
  // Per-pixel direct light: the indirect radiosity per element, the unshot
  // emission per patch, and the emitter list (counted from the staged
  // patches, which Build copies in unchanged).
  const bool direct = options_.directSamples > 0;
  elements_.Layout(arena, numPatches, options_.elements, direct);
  direct_.Layout(arena, numPatches, direct, !staged_->lattice.smooth.empty(),
                 direct ? DirectLight::Count(
                              Span<const Patch>(staged_->patches.data(), staged_->patches.size()))
                        : DirectLight::Counts{});
  part(&footprint_.elements);
  lattice_.Layout(arena, staged_->lattice, direct);
  part(&footprint_.vertices);
  patchTex_ = arena.Alloc<PatchTexture>(staged_->tex.empty() ? 0 : numPatches);
  part(&footprint_.textures);
  grid_.Layout(arena, plan);
  part(&footprint_.grid);
  // Exchange buffers only where there is someone to exchange with (its
  // queue and the rest, footprint_.queue and .packets); PartCentres needs
  // the read costs.
  FillReadCosts(numPatches);
  exchange_.Layout(arena, options_, numPatches, numNeighbours_ > 0, shape_,
                   numNeighbours_ > 0 ? PacketBytes(shape_) : 0, PartCentres(), &footprint_);
  footprint_.total = ArenaRoundUp(arena.used());
  footprint_.numPatches = numPatches;
  footprint_.gridCells = uint64_t(plan.res[0]) * plan.res[1] * plan.res[2];
}

namespace {

// The staged lattice's vertices on a face environment cell `cell` (box
// `box`) shares with a neighbour, and their surface's normal.
void StageCuts(const EnvGrid& grid, const int cell[3], const Bounds& box,
               const std::vector<Patch>& patches, DisplayLattice::Staged* lattice) {
  // Lattice vertices on a face shared with a neighbour.
  lattice->cut.clear();
  lattice->cutNormal.clear();
  {
    glm::vec3 extent = grid.box.hi - grid.box.lo;
    float tol = 1e-5f * std::fmax(extent.x, std::fmax(extent.y, extent.z));
    std::vector<char> seen(lattice->vertices.size(), 0);
    for (const Patch& p : patches) {
      for (uint32_t k = 0; k < p.numCorners; ++k) {
        uint32_t v = p.vertex[k];
        if (seen[v]) continue;
        seen[v] = 1;
        const glm::vec3& x = lattice->vertices[v];
        bool cut = false;
        for (int a = 0; a < 3; ++a) {
          cut |= cell[a] > 0 && std::fabs(x[a] - box.lo[a]) <= tol;
          cut |= cell[a] + 1 < grid.n[a] && std::fabs(x[a] - box.hi[a]) <= tol;
        }
        if (!cut) continue;
        lattice->cut.push_back(v);
        lattice->cutNormal.push_back(p.normal);
      }
    }
  }
}

// The staged lattice's smooth vertices (local ids, by vertex: `vertexMap`
// from the mesh's), the patch edges between two on one outline edge of
// their polygon, and how many vertices the display shares.
void StageSmooth(const Mesh& mesh, const std::unordered_map<uint32_t, uint32_t>& vertexMap,
                 const std::vector<Patch>& patches, DisplayLattice::Staged* lattice) {
  // Smooth vertices (local ids, by vertex), and the patch edges between two
  // on one outline edge of their polygon.
  lattice->smooth.clear();
  lattice->smoothEdges.clear();
  if (!mesh.smooth.empty()) {
    std::vector<uint32_t> at(lattice->vertices.size(),
                             kNoPatch);  // local vertex -> lattice->smooth
    for (const SmoothVertex& s : mesh.smooth) {
      auto it = vertexMap.find(s.vertex);
      if (it == vertexMap.end()) continue;
      lattice->smooth.push_back(s);
      lattice->smooth.back().vertex = it->second;
    }
    std::sort(lattice->smooth.begin(), lattice->smooth.end(),
              [](const SmoothVertex& a, const SmoothVertex& b) { return a.vertex < b.vertex; });
    for (uint32_t k = 0; k < lattice->smooth.size(); ++k) at[lattice->smooth[k].vertex] = k;
    if (!lattice->smooth.empty()) {
      lattice->smoothEdges.assign(patches.size(), 0);
      for (size_t i = 0; i < patches.size(); ++i) {
        const Patch& p = patches[i];
        for (uint32_t k = 0; k < p.numCorners; ++k) {
          uint32_t a = at[p.vertex[k]], b = at[p.vertex[(k + 1) % p.numCorners]];
          if (a == kNoPatch || b == kNoPatch) continue;
          const SmoothVertex &sa = lattice->smooth[a], &sb = lattice->smooth[b];
          bool common = false;
          for (uint32_t ea : sa.edge)
            for (uint32_t eb : sb.edge) common |= ea == eb;
          if (common) lattice->smoothEdges[i] |= static_cast<uint8_t>(1u << k);
        }
      }
    }
  }
  lattice->numShared = static_cast<uint32_t>(lattice->cut.size());
  {
    std::vector<char> cut(lattice->vertices.size(), 0);
    for (uint32_t v : lattice->cut) cut[v] = 1;
    for (const SmoothVertex& s : lattice->smooth) lattice->numShared += cut[s.vertex] ? 0 : 1;
  }
}

}  // namespace

// Init, first half: environment `index` of `grid` from the patches `ids`
// of `mesh` (copied to the heap, vertices remapped to a local lattice; a
// twin gets TwinGeom of its original's, paired when both are here); plans
// the grid and measures the arena. Second half (Build): the arena of
// exactly that size, the patches copied in, the grid built, the heap
// copies dropped; false, with nothing built, if the memory is refused.
const EnvFootprint& Environment::Prepare(const EnvGrid& grid, uint32_t index, const Mesh& mesh,
                                         const std::vector<uint32_t>& ids,
                                         const EnvOptions& options) {
  index_ = index;
  options_ = options;
  envGrid_ = grid;
  grid.Cell(static_cast<int>(index), cell_);
  box_ = grid.EnvBox(static_cast<int>(index));
  numNeighbours_ = 0;
  for (int a = 0; a < 3; ++a) numNeighbours_ += (cell_[a] > 0) + (cell_[a] + 1 < grid.n[a]);
  exchange_.FindExits(grid, cell_, box_);
  shape_ = numNeighbours_ > 0 ? MaskShapeOf(options.maskMethod, options.maskRes, options.rays)
                              : MaskShape{};
  staged_ = std::make_unique<Staged>();
  OutsideShooters(grid, static_cast<int>(index), options.outside, options.outsideTiles,
                  &staged_->outside);

  // Local copies of the patches and a compact local vertex lattice.
  staged_->patches.clear();
  staged_->lattice.vertices.clear();
  staged_->tex.clear();
  staged_->patches.reserve(ids.size());
  bool textured = false;
  std::unordered_map<uint32_t, uint32_t> vertexMap;
  for (uint32_t id : ids) {
    Patch p = mesh.patches[id];
    for (int k = 0; k < 4; ++k) {
      auto it = vertexMap.find(p.vertex[k]);
      if (it == vertexMap.end()) {
        it = vertexMap.emplace(p.vertex[k], static_cast<uint32_t>(staged_->lattice.vertices.size()))
                 .first;
        staged_->lattice.vertices.push_back(mesh.vertices[p.vertex[k]]);
      }
      p.vertex[k] = it->second;
    }
    staged_->patches.push_back(p);
    if (!mesh.textures.empty()) {
      staged_->tex.push_back(mesh.textures[id]);
      textured |= mesh.textures[id].texture != kNoTexture;
    }
  }
  // Ray-test data; a twin's from its original's (TwinGeom), and the pairs.
  staged_->geom.clear();
  staged_->twin.clear();
  numTwins_ = 0;
  for (uint32_t id : ids) {
    bool copy = !mesh.twin.empty() && mesh.twin[id] != kNoPatch && mesh.twin[id] < id;
    staged_->geom.push_back(copy ? TwinGeom(MakePatchGeom(mesh.patches[mesh.twin[id]]))
                                 : MakePatchGeom(mesh.patches[id]));
    numTwins_ += copy;
  }
  if (!mesh.twin.empty()) {
    std::unordered_map<uint32_t, uint32_t> local;
    for (uint32_t i = 0; i < ids.size(); ++i) local.emplace(ids[i], i);
    for (uint32_t id : ids) {
      auto it = mesh.twin[id] == kNoPatch ? local.end() : local.find(mesh.twin[id]);
      staged_->twin.push_back(it == local.end() ? kNoPatch : it->second);
    }
  }
  if (!textured) staged_->tex.clear();
  StageCuts(grid, cell_, box_, staged_->patches, &staged_->lattice);
  StageSmooth(mesh, vertexMap, staged_->patches, &staged_->lattice);
  uint32_t n = static_cast<uint32_t>(staged_->patches.size());
  Grid::Nest nest;
  nest.minRefs = options.subGridRefs;
  plan_ = Grid::MakePlan(Span<const Patch>(staged_->patches.data(), n),
                         Span<const PatchGeom>(staged_->geom.data(), n), options.gridDensity, nest,
                         &staged_->gridWork);
  Arena measure = Arena::Measure();
  Layout(measure, n, plan_);
  // What --export will write of this environment (src/output/export.cpp).
  footprint_.numVertices = staged_->lattice.vertices.size();
  footprint_.numTriangles = 0;
  for (const Patch& p : staged_->patches) footprint_.numTriangles += p.numCorners == 4 ? 2 : 1;
  return footprint_;
}

void Environment::Init(const EnvGrid& grid, uint32_t index, const Mesh& mesh,
                       const std::vector<uint32_t>& ids, const EnvOptions& options) {
  Prepare(grid, index, mesh, ids, options);
  Build();
}

bool Environment::Build() {
  uint32_t n = static_cast<uint32_t>(staged_->patches.size());
  if (!Arena::Reserve(footprint_.total, &arena_)) return false;
  Layout(arena_, n, plan_);
  CHECK(ArenaRoundUp(arena_.used()) == arena_.capacity());
  totalArea_ = 0.0;
  kdArea_ = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    patches_[i] = staged_->patches[i];
    geom_[i] = staged_->geom[i];
    totalArea_ += staged_->patches[i].area;
    const glm::vec3& kd = staged_->patches[i].kd;
    kdArea_ += (static_cast<double>(kd[0]) + kd[1] + kd[2]) / 3.0 * staged_->patches[i].area;
  }
  for (size_t i = 0; i < staged_->twin.size(); ++i) twin_[i] = staged_->twin[i];
  outside_.Fill(staged_->outside);
  for (size_t i = 0; i < patchTex_.size(); ++i) patchTex_[i] = staged_->tex[i];
  lattice_.Build(staged_->lattice, patches_);
  grid_.Build(patches_, geom_, &staged_->gridWork);
  // The sun per pixel: its shadow rays must leave the scene, which one
  // environment's grid tells alone; with neighbours, only where the pixels
  // gather every environment's light (the other environments' part from
  // their sun maps, foreign_light.h); else the sun is the solve's.
  direct_.Build(patches_, lattice_, options_.outside,
                numNeighbours_ == 0 || options_.gatherForeign);
  direct_.SetGathersForeign(options_.gatherForeign && numNeighbours_ > 0);
  centreStepsPerRay_ = 1;
  while ((centreStepsPerRay_ + 1) * (centreStepsPerRay_ + 1) * (centreStepsPerRay_ + 1) <=
         grid_.cellCount())
    ++centreStepsPerRay_;
  exchange_.Build();
  staged_.reset();  // the heap copies, no longer needed
  Reset();
  return true;
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
      e.var[c] = 0.0;
      e.unshot[c] = static_cast<double>(p.ke[c]) * p.area;
      ledger_.emitted[c] += e.unshot[c];
      ledger_.unshot[c] += e.unshot[c];
      ledger_.radiosity[c] += e.unshot[c];
    }
    shotCount_[i] = 0;
    raysShot_[i] = 0;
    direct_.ResetPatch(i, e.unshot);
    tree_.Set(i, UnshotKey(e));
  }
  direct_.SumEmission();
  elements_.Reset(patches_);
  // The leaves' buried parts, before any shot: rays leave from the open
  // part of a patch that runs on under a solid (ElementTree::SampleByPower).
  const uint64_t steps0 = grid_.steps();
  MeasureExposure();
  resetSteps_ += grid_.steps() - steps0;
  // With neighbours (and --origins power) a patch's rays leave from its
  // open cells alone, wherever its shot is traced (Patch::openCells): a ray
  // from under a block would only meet the block's inside, its power lost
  // on a back face (0.28% of the Cornell box's light, darkening the blocks
  // by 2-3%). One environment draws them by power instead (Distribute).
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    Patch& p = patches_[i];
    const bool open = numNeighbours_ > 0 && options_.originsByPower && !Emits(p);
    p.openCells = open ? elements_.PartOpen(p.numCorners == 3, i) : 0;
  }
  // The outside shooters emit as patches do; their power counts in the
  // radiosity power R as an emitter's b * area does (the power shot so far
  // is R - unshot).
  outside_.Reset(&ledger_);
  exchange_.Clear();
}

// EnvState's fields beside what holds each here, one list for both ways:
// with `env` const (SaveState) each is copied into `s`, else (RestoreState)
// out of it. A part's field goes through its getter and setter.
template <typename Env, typename State>
void Environment::StateFields(Env& env, State& s) {
  constexpr bool kSave = std::is_const<Env>::value;
  auto held = [](auto& saved, auto& member) {
    if constexpr (kSave)
      saved = member;
    else
      member = saved;
  };
  auto viaPart = [](auto& saved, auto& part, auto get, auto set) {
    if constexpr (kSave)
      saved = (part.*get)();
    else
      (part.*set)(saved);
  };
  viaPart(s.gridSteps, env.grid_, &Grid::steps, &Grid::SetSteps);
  held(s.centreSteps, env.centreSteps_);
  held(s.centreWork, env.centreWork_);
  viaPart(s.nextElement, env.elements_, &ElementTree::used, &ElementTree::SetUsed);
  viaPart(s.queued, env.exchange_.queue(), &ForeignQueue::count, &ForeignQueue::SetCount);
  held(s.ledger, env.ledger_);
  held(s.stats, env.stats_);
}

// Checkpoint and resume, between rounds: the state beside the arena;
// RestoreState is false, changing nothing, if `s` is not of this layout
// (the fields that say which are saved, and checked before anything
// changes). The arena's bytes are restored over one laid out alike.
EnvState Environment::SaveState() const {
  EnvState s;
  std::memset(static_cast<void*>(&s), 0, sizeof s);  // padding too: the same bytes every time
  s.arenaUsed = arena_.used();
  s.numPatches = patches_.size();
  s.outCount = exchange_.outbox().count();
  s.index = index_;
  StateFields(*this, s);
  return s;
}

bool Environment::RestoreState(const EnvState& s) {
  if (s.index != index_ || s.numPatches != patches_.size() || s.arenaUsed != arena_.used() ||
      s.outCount != 0 || s.nextElement > elements_.size())
    return false;
  StateFields(*this, s);
  exchange_.outbox().Clear();
  return true;
}

// --max-seconds's plan: the seconds `rays` form-factor-like rays take here.
double Environment::TimeRays(uint32_t rays) const {
  if (patches_.empty()) return 0.0;
  Rng rng(0x5eed, 41);
  const uint32_t n = static_cast<uint32_t>(patches_.size());
  uint64_t hits = 0;
  double start = os::Seconds();
  for (uint32_t k = 0; k < rays; ++k) {
    uint32_t i = static_cast<uint32_t>((uint64_t(k) * 2654435761u) % n);
    PatchSampler sampler = MakePatchSampler(patches_[i]);
    float u[5];
    for (float& x : u) x = rng.NextFloat();
    glm::vec3 local;
    Ray ray = ShotRay(sampler, u, options_.rayEpsilon, &local);
    Hit hit;
    hits += grid_.Intersect(ray, Skip(i, twinOf(i)), &hit) ? 1 : 0;
  }
  double seconds = os::Seconds() - start;
  return hits > rays ? 0.0 : seconds;  // (hits read, so the loop stays)
}

}  // namespace vismask
