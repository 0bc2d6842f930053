// Environment: the unit that owns memory. One environment holds its own
// patches (geometry, material, energy), its own uniform grid over them, its
// own shooter-selection tree and its own energy ledger, all carved from one
// arena sized exactly at init. A single-environment run is one of these.
// No environment ever reads another's geometry.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "vismask/arena.h"
#include "vismask/grid.h"
#include "vismask/max_tree.h"
#include "vismask/mesh.h"
#include "vismask/patch.h"
#include "vismask/span.h"

namespace vismask {

// Per-channel energy bookkeeping, in W (double): at every moment
// emitted == absorbed + escaped + unshot (up to rounding).
struct EnergyLedger {
  double emitted[3] = {0, 0, 0};
  double absorbed[3] = {0, 0, 0};  // by receivers (1 - kd) and by back faces
  double escaped[3] = {0, 0, 0};   // rays that hit nothing
  double unshot[3] = {0, 0, 0};    // kept current shot by shot
};

// Counters of one environment's work.
struct EnvStats {
  uint64_t shots = 0;
  uint64_t rays = 0;
  uint64_t hits = 0;
};

struct EnvOptions {
  float gridDensity = 4.0f;  // grid cells per patch (Cleary's lambda)
  float rayEpsilon = 0.0f;   // ray tMin in scene units
};

class Environment {
 public:
  Environment() = default;
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;

  // Builds environment `index` from the patches `ids` of `mesh` (init only):
  // measures the layout, makes the arena, copies the patches in, remaps their
  // display vertices to a local lattice and builds the grid.
  void Init(uint32_t index, const Mesh& mesh, const std::vector<uint32_t>& ids,
            const EnvOptions& options);

  // Emission: B = Ke, unshot power = Ke * area; the ledger restarts.
  void Reset();

  // Shoots patch `i`'s unshot power with `rays` rays (cosine directions from
  // uniform points on the patch), seeded by `shotKey`. Every ray that strikes
  // a front side delivers 1/rays of the power, reflected by the receiver's kd.
  void Shoot(uint32_t i, uint32_t rays, uint64_t shotKey);

  // The local patch with most unshot power (kNoPatch if none), and its key.
  uint32_t TopShooter() const { return tree_.Top(); }
  double ShooterKey(uint32_t i) const { return tree_.Key(i); }
  uint32_t ShotCount(uint32_t i) const { return shotCount_[i]; }

  // Display radiosity at the lattice vertices: the area-weighted mean of the
  // touching patches' B + kd * ambient.
  void ComputeVertexRadiosity(const double ambient[3]);

  uint32_t index() const { return index_; }
  Span<const Patch> patches() const { return patches_; }
  Span<const PatchEnergy> energy() const { return energy_; }
  Span<const glm::vec3> vertices() const { return vertices_; }
  Span<const glm::vec3> vertexRadiosity() const { return vertexB_; }
  const Grid& grid() const { return grid_; }
  const EnergyLedger& ledger() const { return ledger_; }
  const EnvStats& stats() const { return stats_; }
  double totalArea() const { return totalArea_; }
  size_t arenaCapacity() const { return arena_.capacity(); }
  size_t arenaUsed() const { return arena_.used(); }

 private:
  void Layout(Arena& arena, uint32_t numPatches, uint32_t numVertices, const Grid::Plan& plan);
  void Receive(uint32_t j, const double share[3]);

  uint32_t index_ = 0;
  EnvOptions options_;
  Arena arena_ = Arena::Measure();
  Span<Patch> patches_;
  Span<PatchGeom> geom_;
  Span<PatchEnergy> energy_;
  Span<uint32_t> shotCount_;
  Span<glm::vec3> vertices_;
  Span<glm::vec3> vertexB_;
  Span<float> vertexWeight_;
  Grid grid_;
  MaxTree tree_;
  EnergyLedger ledger_;
  EnvStats stats_;
  double totalArea_ = 0.0;
};

}  // namespace vismask
