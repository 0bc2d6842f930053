// Environment: the unit that owns memory. One local environment holds its own
// patches (geometry, material, energy), its own uniform grid over them, its
// own shooter-selection tree and its exchange state (ExchangeState: foreign
// shooters queued, packet buffers), all carved from one arena sized exactly
// at init. A single-environment run is one of these with no neighbours; it
// reserves no queue, mask or packet bytes. No environment reads another's
// geometry: what it knows of a foreign shooter is what its packet carries.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/direct_book.h"
#include "vismask/solve/display_lattice.h"
#include "vismask/solve/element_tree.h"
#include "vismask/solve/env_options.h"
#include "vismask/solve/exchange_state.h"
#include "vismask/solve/ledger.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/max_tree.h"
#include "vismask/solve/outside_set.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"

namespace vismask {

struct PatchSampler;

class Environment {
 public:
  Environment();
  ~Environment();
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;

  // Init in two halves (environment.cpp): Prepare measures, Build makes the arena (Init: both).
  const EnvFootprint& Prepare(const EnvGrid& grid, uint32_t index, const Mesh& mesh,
                              const std::vector<uint32_t>& ids, const EnvOptions& options);
  bool Build();
  void Init(const EnvGrid& grid, uint32_t index, const Mesh& mesh, const std::vector<uint32_t>& ids,
            const EnvOptions& options);
  const EnvFootprint& footprint() const { return footprint_; }
  // Emission: B = Ke, unshot power = Ke * area; ledger and queue restart.
  void Reset();

  // One round of shots, and the work rounds are measured in (env_queue.cpp).
  void RunRound(uint32_t shotBudget, uint32_t newForwards, uint64_t roundWork = 0);
  uint64_t workSteps() const;
  // For the pacer's shot costs (pace.h): the work with every centre cast
  // (a local shooter's cached ones too), and its part the shots cost
  // whatever their rays: WorkCosts::shot for each, local and foreign, and
  // the casts.
  uint64_t paceWork() const;
  uint64_t shotWork() const;
  // A centre ray's work: the integer cube root of the grid's cells, at least 1.
  uint64_t centreStepsPerRay() const { return centreStepsPerRay_; }

  // Packets: the exchange state (its outbox), delivery (env_queue.cpp), share here.
  const ExchangeState& exchange() const { return exchange_; }
  void ClearOutbox() { exchange_.outbox().Clear(); }
  void Deliver(const uint8_t* packet);
  double FlightShareAt(const uint8_t* packet) const;
  // The power booked as shot but not yet delivered (env_flight.cpp).
  void FlightPower(double power[3]) const;

  // Display values (env_receive.cpp): vertices', a leaf's, a patch's leaf at `st`.
  // ComputeVertexRadiosity first measures the leaves' exposed shares
  // (MeasureExposure): a leaf shows what it received over its exposed
  // area, and weighs that much in its vertices' means.
  void ComputeVertexRadiosity(const double ambient[3]);
  // Measures ElementTree::exposed for every leaf not yet measured
  // (exposure.cpp): of the points spread over the leaf (one to each cell
  // of its open-cell mask, kFineExposure^2 near a buried part), the share
  // from which the normal probe ray, or two of the others, reach a front
  // face or leave the scene. A point from which every probe meets a back
  // face first lies inside a closed solid, where no light arrives and no
  // eye looks; one from which a single probe gets out lies in a slit (a
  // ceiling above a lamp hung just below it), lit next to nothing and seen
  // by no eye. Reset measures the roots, Receive a split's children:
  // SampleByPower's origins avoid their buried cells.
  void MeasureExposure();
  // Leaf e's exposed area (its area until measured).
  float ExposedArea(uint32_t e) const {
    const float share = elements_.exposed(e);
    return elements_[e].area * (share < 0.0f ? 1.0f : share);
  }
  uint32_t IndirectFilterSteps() const;  // the indirect part's smoothing for the next image
  uint32_t filterSteps() const { return filterSteps_; }  // ... and the last image's
  glm::vec3 LeafRadiosity(uint32_t patch, uint32_t e, const double ambient[3]) const;
  glm::vec3 LeafSolvedDirect(uint32_t patch, uint32_t e) const;
  uint32_t LeafAt(uint32_t patch, glm::vec2 st) const;
  Span<const Element> elements() const { return elements_.all(); }
  const ElementTree& elementTree() const { return elements_; }
  uint32_t elementsUsed() const { return elements_.used(); }
  const DisplayLattice& lattice() const { return lattice_; }
  DisplayLattice& lattice() { return lattice_; }
  // Per-pixel direct light (--direct-samples; DirectBook).
  bool directPerPixel() const { return options_.directSamples > 0; }
  void SetDisplayIndirect(bool on) { direct_.SetShowIndirect(on && directPerPixel()); }
  const DirectBook& direct() const { return direct_; }
  uint32_t directSamples() const { return options_.directSamples; }
  float rayEpsilon() const { return options_.rayEpsilon; }
  // Unshot emission whose first bounce the pixels gather (emitters', gathered suns').
  void EmissionUnshot(double out[3]) const;
  // The same from DirectBook's running sum (EmissionLeft): without walking
  // the patches, so that every round may report it (EnvSums::emission).
  void EmissionLeft(double out[3]) const;

  uint32_t index() const { return index_; }
  uint32_t packetBytes() const { return exchange_.outbox().packetBytes(); }
  bool hasNeighbours() const { return numNeighbours_ > 0; }
  const Bounds& box() const { return box_; }
  Span<const Patch> patches() const { return patches_; }
  // Its patches between Prepare and Build (the staged copies), or after.
  Span<const Patch> preparedPatches() const;
  // Patch i's twin (two-sided meshes) or kNoPatch; how many patches are twin copies.
  uint32_t twinOf(uint32_t i) const { return twin_.empty() ? kNoPatch : twin_[i]; }
  uint32_t numTwins() const { return numTwins_; }
  Span<const PatchEnergy> energy() const { return energy_; }
  // Patch i's texture data, or null when it is not textured.
  const PatchTexture* patchTexture(uint32_t i) const {
    return patchTex_.empty() || patchTex_[i].texture == kNoTexture ? nullptr : &patchTex_[i];
  }
  const Grid& grid() const { return grid_; }
  // Runs f(grid()) and leaves the grid's step count as it was: rays cast
  // outside the solve (foreign_light.h's masks at init) are not its work.
  template <class F>
  void UncountedOnGrid(F f) {
    const uint64_t steps = grid_.steps();
    f(static_cast<const Grid&>(grid_));
    grid_.SetSteps(steps);
  }
  const EnergyLedger& ledger() const { return ledger_; }
  const EnvStats& stats() const { return stats_; }
  double totalArea() const { return totalArea_; }
  double kdArea() const { return kdArea_; }  // sum of kd * area, channels averaged
  size_t arenaCapacity() const { return arena_.capacity(); }
  size_t arenaUsed() const { return arena_.used(); }

  // Checkpoint and resume between rounds (checkpoint.h; environment.cpp).
  EnvState SaveState() const;
  bool RestoreState(const EnvState& s);
  Span<const uint8_t> arenaBytes() const { return {arena_.data(), arena_.capacity()}; }
  Span<uint8_t> mutableArenaBytes() { return Span<uint8_t>(arena_.data(), arena_.capacity()); }
  // --max-seconds's plan (trace.cpp), and the power a ray carries.
  double TimeRays(uint32_t rays) const;
  double rayQuantum() const { return options_.rayQuantum; }
  void SetRayQuantum(double q) { options_.rayQuantum = q; }
  double emissionRays() const { return options_.emissionRays; }
  // Test hooks: the top local shooter, any unshot power, the outside shooters.
  uint32_t TopShooter() const { return tree_.Top(); }
  bool HasLocalUnshot() const;
  uint32_t numOutside() const { return outside_.size(); }

 private:
  // MeasureExposure's parts (exposure.cpp): patch i's leaves not yet
  // measured, `fine` points to a side of each open-cell mask's cell
  // (whether it measured any); whether a leaf of patch i is buried in part
  // or whole.
  static constexpr int kFineExposure = 2;  // the points to a cell's side near a buried part
  bool MeasurePatchExposure(uint32_t i, int fine);
  bool PartlyBuried(uint32_t i) const;

  struct Staged;     // the heap copies between Prepare and Build (environment.cpp)
  struct ShotTally;  // what a shot's rays did here, booked once a shot (trace.cpp)

  void Layout(Arena& arena, uint32_t numPatches, const Grid::Plan& plan);
  template <typename Env, typename State>
  static void StateFields(Env& env, State& s);  // SaveState and RestoreState's one list
  // Shots (env_queue.cpp) and their rays (trace.cpp).
  void ShootLocal(uint32_t i);
  void ShootOutside(uint32_t k);
  void ShootOwn(const Patch& p, Skip skip, const double power[3], uint64_t key, uint32_t shotIndex,
                uint32_t rays, uint32_t cached);
  void ShootForeign(uint32_t slot);
  // `emission`: the part of `power` (channels summed) that is emission the
  // pixels gather, which counts options_.emissionRays of its worth in rays.
  uint32_t ShotRays(const double power[3], double emission, uint64_t shotKey,
                    double* fraction) const;
  Ray MakeShotRay(const Patch& shooter, const PatchSampler& sampler, const float u[5],
                  glm::vec3* local) const;
  bool OriginsByPower(const Patch& shooter, bool foreign) const;
  void Distribute(const Patch& shooter, Skip skip, const double power[3], uint64_t stream,
                  uint32_t rays, const MaskBits* in, MaskBits* out, MaskBits* centre = nullptr,
                  MaskBits* known = nullptr, MaskBits* read = nullptr, uint32_t first = 0);
  void TraceAlive(const Patch& shooter, Skip skip, const double power[3], uint64_t shotKey,
                  uint32_t rays, bool foreign, const MaskBits& alive, MaskBits* routes);
  void Land(const Ray& ray, const Hit& hit, const double share[3], ShotTally* tally);
  void Book(const ShotTally& tally);
  int ExitFace(const Ray& ray) const;
  // Centre rays (B, C; trace.cpp) and B's reading shots (env_read.cpp).
  void CastCentres(const Patch& shooter, Skip skip, MaskBits* mask);
  bool CachedCentre(uint32_t i, MaskBits* centre, MaskBits* known);
  bool ReadsOnly(uint32_t rays) const;
  void FillReadCosts(uint32_t numPatches);
  void ReadPixels(const PacketHeader& h, MaskBits* read);
  double ReadShare(const PacketHeader& h, const MaskBits& mask, int to);
  template <typename Visit>
  void ForEachEntryPixel(const PacketHeader& h, int env, const Patch& shooter,
                         const PatchSampler& sampler, const glm::vec3& centre, Visit visit) const;
  void AddOutsideEmission(double out[3]) const;  // the gathered outside shooters' unshot
  float CentreLift(uint32_t id) const;
  float OutsideLift() const;
  bool PartCentres() const;
  // Packets (env_queue.cpp, env_flight.cpp).
  void Forward(PacketHeader header, const MaskBits& mask, const MaskBits* routes = nullptr);
  int Downstream(uint32_t sourceEnv, int (*next)[3]) const;
  double FlightShare(const PacketHeader& h, const uint8_t* bits, const Bounds& box,
                     const int to[3]) const;
  // Receiving (env_receive.cpp).
  void Receive(uint32_t j, const double share[3], const glm::vec3& x);
  uint32_t index_ = 0;
  EnvGrid envGrid_;  // the partition (grid_ is the ray-casting grid)
  int cell_[3] = {0, 0, 0};
  Bounds box_;
  uint32_t numNeighbours_ = 0, filterSteps_ = 0;
  EnvOptions options_;
  MaskShape shape_;
  Arena arena_ = Arena::Measure();
  Span<Patch> patches_;
  Span<PatchGeom> geom_;
  Span<uint32_t> twin_;  // two-sided meshes: each patch's twin or kNoPatch; else empty
  uint32_t numTwins_ = 0;
  Span<PatchEnergy> energy_;
  Span<uint32_t> shotCount_;
  Span<uint32_t> raysShot_;  // one environment: the rays of a patch's shots so far (PatchStream)
  Span<PatchTexture> patchTex_;  // one per patch when any is textured, else empty
  ElementTree elements_;
  DirectBook direct_;
  DisplayLattice lattice_;
  Grid grid_;
  MaxTree tree_;
  OutsideSet outside_;
  ExchangeState exchange_;  // empty for an environment without neighbours
  uint32_t newForwards_ = 0;
  double readPerRay_ = 0.0, allCost_ = 0.0;  // FillReadCosts
  bool mayRead_ = false;
  EnergyLedger ledger_;
  EnvStats stats_;
  uint64_t centreSteps_ = 0;  // grid steps of the centre rays really cast
  // Grid steps of Reset's exposure probes, which are init's, not the
  // solve's: left out of its work and steps.
  uint64_t resetSteps_ = 0;
  uint64_t centreWork_ = 0;  // the work of the casts every cache size makes (workSteps)
  uint64_t centreStepsPerRay_ = 1;
  double totalArea_ = 0.0, kdArea_ = 0.0;
  EnvFootprint footprint_;
  std::unique_ptr<Staged> staged_;
  Grid::Plan plan_;
};

}  // namespace vismask
