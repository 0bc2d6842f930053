// Environment: the unit that owns memory. One local environment holds its own
// patches (geometry, material, energy), its own uniform grid over them, its
// own shooter-selection tree, its queue of foreign shooters and its packet
// buffers, all carved from one arena sized exactly at init. A
// single-environment run is one of these with no neighbours; it reserves no
// queue, mask or packet bytes. No environment reads another's geometry: what
// it knows of a foreign shooter is what its packet carries.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/display/direct.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/centre_mask_cache.h"
#include "vismask/solve/display_lattice.h"
#include "vismask/solve/element.h"
#include "vismask/solve/env_options.h"
#include "vismask/solve/foreign_queue.h"
#include "vismask/solve/ledger.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/max_tree.h"
#include "vismask/solve/outbox.h"
#include "vismask/solve/outside.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/patch.h"
#include "vismask/solve/work.h"

namespace vismask {

struct PatchSampler;

class Environment {
 public:
  Environment() = default;
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;

  // Init, first half: takes environment `index` of `grid` from the patches
  // `ids` of `mesh` (copied to the heap, display vertices remapped to a local
  // lattice), plans the grid and measures the arena. No arena yet. A twin
  // in a two-sided mesh (mesh.h) gets TwinGeom of its original's ray-test
  // data; twins are paired locally when both are among `ids`.
  const EnvFootprint& Prepare(const EnvGrid& grid, uint32_t index, const Mesh& mesh,
                              const std::vector<uint32_t>& ids, const EnvOptions& options);
  // Init, second half: makes the arena of exactly the measured size, copies
  // the patches in, builds the grid, and drops the heap copies. False, with
  // nothing built, if the system refuses the arena's memory.
  bool Build();
  // Prepare and Build.
  void Init(const EnvGrid& grid, uint32_t index, const Mesh& mesh, const std::vector<uint32_t>& ids,
            const EnvOptions& options) {
    Prepare(grid, index, mesh, ids, options);
    Build();
  }
  const EnvFootprint& footprint() const { return footprint_; }

  // Emission: B = Ke, unshot power = Ke * area; ledger and queue restart.
  void Reset();

  // One round: up to `shotBudget` shots, each the larger of the local patch
  // with most unshot power (allowed while `newForwards` remains, when there
  // are neighbours) and the queued foreign shooter with most power, ending
  // early once the round's work has reached `roundWork` grid steps (0: no
  // limit; workSteps below). Packets for neighbours go to the outbox.
  void RunRound(uint32_t shotBudget, uint32_t newForwards, uint64_t roundWork = 0);
  // The work rounds are measured in, counted and never timed (work.h): the
  // grid steps of the form-factor rays, WorkCosts' ray a form-factor ray (and a ray
  // B regenerates, ReadPixels and ReadShare, which costs about as much
  // beside its walk), a hit's and a shot's (by mask method), plus the work of
  // the centre casts (B and C)
  // that every --mask-cache makes: a foreign shooter's, and a local
  // shooter's first. The cache saves a local shooter's later casts, so their
  // real steps (and those of the last-occluder hint) are left out.
  uint64_t workSteps() const {
    const WorkCosts& w = WorkCostsOf(options_.maskMethod);
    return grid_.steps() - centreSteps_ + centreWork_ + w.ray * (stats_.rays + stats_.readRays) +
           w.hit * stats_.hits + w.shot * (stats_.shots + stats_.foreignShots);
  }
  // A centre ray's work: the integer cube root of the grid's cells (the
  // cells a ray crosses, about), at least 1; a cast by patch counts four a patch.
  uint64_t centreStepsPerRay() const { return centreStepsPerRay_; }

  // The packets this round produced, `packetBytes()` each, in send order.
  const Outbox& outbox() const { return outbox_; }
  void ClearOutbox() { outbox_.Clear(); }
  // Takes a packet addressed to this environment. Packets must be delivered
  // in a fixed order (sender, then send order) for results to be reproducible.
  void Deliver(const uint8_t* packet);
  // The share of a packet addressed here that FlightShare gives with this
  // environment's own box: what its sender must have put in the header
  // (tests/exchange_test.cpp).
  double FlightShareAt(const uint8_t* packet) const;

  // How many foreign shooters are held.
  uint32_t queuedCount() const { return queue_.count(); }
  // The power, per channel, this environment books as shot but not yet
  // delivered (docs/DESIGN.md, "Power in flight"), so that the sum over
  // environments counts each watt once: Method R's ledger().inFlight; for
  // the other methods, each queued shooter's power times the cosine-weighted
  // share of the directions, open in a packet received, whose centre ray
  // crosses from that packet's sender into this box, and the same for the
  // packets in the outbox, each with its receiver's share (so the sum is
  // the same before and after a delivery, up to rounding).
  void FlightPower(double power[3]) const;

  // Display radiosity at the lattice vertices: the area-weighted mean, over
  // the patches touching the vertex, of the leaf element at that corner's
  // B + kd * ambient.
  void ComputeVertexRadiosity(const double ambient[3]);
  // The display radiosity of leaf element `e` of patch `patch`: the
  // patch's emission + what the leaf received / its area + kd * ambient.
  // For a textured patch the part after the emission is scaled by
  // PatchTexture::scale (the material's mean kd over the patch's: texture.h).
  glm::vec3 LeafRadiosity(uint32_t patch, uint32_t e, const double ambient[3]) const;
  // The leaf element of patch `patch` at parameters `st`.
  uint32_t LeafAt(uint32_t patch, glm::vec2 st) const;
  Span<const Element> elements() const { return elements_; }
  // Per-pixel direct light (EnvOptions::directSamples > 0): the emitters,
  // and whether the display shows indirect radiosity only (LeafRadiosity
  // then gives the patch's emission + the leaf's indirect radiosity + kd *
  // ambient).
  bool directPerPixel() const { return options_.directSamples > 0; }
  // Whether LeafRadiosity gives the indirect part alone (directPerPixel()
  // and the image being drawn) or the whole (the export).
  void SetDisplayIndirect(bool on) { displayIndirect_ = on && directPerPixel(); }
  bool displayIndirect() const { return displayIndirect_; }
  // Whether patch i shows its indirect part alone (and the image gathers
  // its direct part): displayIndirect() and its polygon not smoothed (a
  // smoothed polygon, whose direct part the gather would shade with its
  // facets' normals, shows the solved whole, as without it).
  bool ShowsIndirect(uint32_t i) const {
    return displayIndirect_ && (smoothPatch_.empty() || !smoothPatch_[i]);
  }
  uint32_t directSamples() const { return options_.directSamples; }
  const DirectLight& directLight() const { return direct_; }
  float rayEpsilon() const { return options_.rayEpsilon; }
  // Leaf element e's indirect radiosity: what it received from shots other
  // than an emitter's own emission, reflected, over its area (0 without
  // directPerPixel()).
  glm::dvec3 Indirect(uint32_t e) const {
    if (indirect_.empty()) return glm::dvec3(0.0);
    return glm::dvec3(indirect_[3 * e], indirect_[3 * e + 1], indirect_[3 * e + 2]) /
           static_cast<double>(elements_[e].area);
  }
  // The emitted power not yet shot (per channel; 0 without directPerPixel()).
  void EmissionUnshot(double out[3]) const;
  // The display lattice (display.h shares its cut and smooth vertices).
  const DisplayLattice& lattice() const { return lattice_; }
  DisplayLattice& lattice() { return lattice_; }
  Span<const glm::vec3> vertices() const { return lattice_.vertices(); }
  Span<const glm::vec3> vertexRadiosity() const { return lattice_.radiosity(); }
  Span<const SmoothVertex> smoothVertices() const { return lattice_.smoothVertices(); }
  uint32_t numSharedVertices() const { return lattice_.numShared(); }
  uint32_t elementsUsed() const { return nextElement_; }

  uint32_t index() const { return index_; }
  uint32_t packetBytes() const { return packetBytes_; }
  bool hasNeighbours() const { return numNeighbours_ > 0; }
  const Bounds& box() const { return box_; }
  Span<const Patch> patches() const { return patches_; }
  // The local index of patch i's twin (two-sided meshes, mesh.h), or kNoPatch.
  uint32_t twinOf(uint32_t i) const { return twin_.empty() ? kNoPatch : twin_[i]; }
  uint32_t numTwins() const { return numTwins_; }  // patches that are a twin copy
  Span<const PatchEnergy> energy() const { return energy_; }
  // Patch i's texture data, or null when it is not textured.
  const PatchTexture* patchTexture(uint32_t i) const {
    return patchTex_.empty() || patchTex_[i].texture == kNoTexture ? nullptr : &patchTex_[i];
  }
  const Grid& grid() const { return grid_; }
  const EnergyLedger& ledger() const { return ledger_; }
  const EnvStats& stats() const { return stats_; }
  double totalArea() const { return totalArea_; }
  double kdArea() const { return kdArea_; }  // sum of kd * area, channels averaged
  size_t arenaCapacity() const { return arena_.capacity(); }
  size_t arenaUsed() const { return arena_.used(); }

  // Checkpoint and resume (checkpoint.h), between rounds only: the state
  // beside the arena, and the arena's bytes (restored over an arena laid
  // out by the same scene and options: spans hold no pointers into it).
  EnvState SaveState() const;
  // False if `s` is not of this environment's layout (index, patches,
  // arena bytes); then nothing is changed.
  bool RestoreState(const EnvState& s);
  // The whole block (capacity, footprint().total: what `footprint` counts).
  Span<const uint8_t> arenaBytes() const {
    return Span<const uint8_t>(arena_.data(), arena_.capacity());
  }
  Span<uint8_t> mutableArenaBytes() { return Span<uint8_t>(arena_.data(), arena_.capacity()); }

  // --max-seconds's plan (app.cpp): the seconds `rays` form-factor-like
  // rays take through this environment's grid (from patch centres, cosine
  // directions, a fixed stream), and the power a ray carries, changed.
  double TimeRays(uint32_t rays) const;
  double rayQuantum() const { return options_.rayQuantum; }
  void SetRayQuantum(double q) { options_.rayQuantum = q; }

  // Test hooks: the shooter a plain progressive-refinement step would take.
  uint32_t TopShooter() const { return tree_.Top(); }
  // Whether a local patch or an outside shooter (--sky, --sun) has unshot power.
  bool HasLocalUnshot() const;
  // The outside shooters this environment holds (outside.h).
  uint32_t numOutside() const { return numOutside_; }

 private:
  void Layout(Arena& arena, uint32_t numPatches, const Grid::Plan& plan);
  void ShootLocal(uint32_t i);
  // Outside shooter k (--sky, --sun) shoots, as a local patch does but with
  // no patch to skip and no centre-mask cache.
  void ShootOutside(uint32_t k);
  void ShootOwn(const Patch& p, Skip skip, const double power[3], uint64_t key, uint32_t shotIndex,
                uint32_t rays, uint32_t cached);
  // The outside shooter with the most unshot power (ties to the first), or
  // -1 when none has any.
  int BestOutside() const;
  // Ray r of a shot of shooter `id` from its five uniforms: ShotRay for a
  // patch; for an outside shooter (outside.h) its direction (cosine for the
  // sky, the sun's cone for the sun) from a point of its face, the origin
  // moved back along the ray to OutsideLift() outside the scene's box, so
  // that the ray crosses geometry lying on the box's face (a floor on its
  // bottom) rather than starting in its plane.
  Ray MakeShotRay(const PatchSampler& sampler, uint32_t id, const float u[5],
                  glm::vec3* local) const;
  // How far off its plane a shooter's centre rays start: rayEpsilon in front
  // of a patch, OutsideLift() behind an outside shooter (outside the box).
  float CentreLift(uint32_t id) const {
    return OutsideKindOf(id) == OutsideKind::kNone ? options_.rayEpsilon : -OutsideLift();
  }
  float OutsideLift() const { return 4.0f * options_.rayEpsilon; }
  void ShootForeign(uint32_t slot);
  // Traces `rays` rays of one shooter through this environment. Rays whose
  // pixel is closed in `in` are skipped; with a mask method, `out` loses the
  // pixels of rays that hit here (A), of centre rays that hit (B), or of
  // pixels the rays only hit and those whose centre ray hits (C).
  // `centre`, when given, is this shooter's slot of the centre-mask cache
  // (CachedCentre): B reads every pixel from it; C reads the pixels set in
  // *known, and casts the others it needs into it.
  // `read` (--centre-rays read, B): the pixels downstream will read; B
  // decides only those (ReadPixels).
  void Distribute(const Patch& shooter, Skip skip, const double power[3], uint64_t stream,
                  uint32_t rays, const MaskBits* in, MaskBits* out, MaskBits* centre = nullptr,
                  MaskBits* known = nullptr, MaskBits* read = nullptr);
  // Local patch i's slot of the centre-mask cache: false when the cache has
  // no slots. *centre: a pixel is open iff its centre ray from the shooter's
  // centre hits nothing here. B: every pixel, cast on a miss. C, and B with
  // --centre-rays read (PartCentres): the pixels set in *known (none after
  // a miss), which Distribute adds to.
  bool CachedCentre(uint32_t i, MaskBits* centre, MaskBits* known);
  // Whether the cache keeps a mask of known pixels beside each centre mask
  // (C, and B when some local shots may decide only the pixels read
  // downstream: mayRead_, FillReadCosts). A slot then takes twice the bytes.
  bool PartCentres() const {
    return options_.maskMethod == MaskMethod::kC ||
           (options_.maskMethod == MaskMethod::kB && mayRead_);
  }
  // Method B: whether local patch i's shot of `rays` rays decides only the
  // pixels its rays will read downstream (ReadPixels), its packets carrying
  // the share of the receiver's rays that pass (ReadShare) as their power in
  // flight and priority, rather than every open pixel that leads to a
  // neighbour. The source decides and says so in the packets' flags, which
  // every environment downstream follows. auto: whichever costs fewer
  // centre rays' worth by FillReadCosts' counts.
  bool ReadsOnly(uint32_t rays) const;
  // auto's counts for shots from here, in centre rays cast, from the grid
  // and the patch count (Layout): per ray of a shot, what reading costs
  // (every ray regenerated for each environment beyond a forwarding one
  // and for each packet's share, and the read pixels' casts); what casting
  // every open pixel costs, here and in each forwarding environment
  // downstream; and whether any shot from here, of the fewest rays a shot
  // may have, reads.
  void FillReadCosts(uint32_t numPatches);
  double readPerRay_ = 0.0;
  double allCost_ = 0.0;
  bool mayRead_ = false;
  // --centre-rays read: opens in *read (closed first) the pixel of every ray
  // that an environment downstream of this one will trace for the shot `h`
  // (Distribute's foreign rays: its stream, its box, the pixel of where the
  // ray enters it seen from the shooter's centre), every one it may reach.
  void ReadPixels(const PacketHeader& h, MaskBits* read);
  // --centre-rays read: the share of h's rays that environment `to` will
  // trace through pixels open in `mask` (its rays regenerated here).
  double ReadShare(const PacketHeader& h, const MaskBits& mask, int to);
  // Calls visit(pixel) with the entry pixel (Distribute's: where the ray
  // enters the box, seen from the shooter's centre) of every ray of h that
  // environment `env` traces for it: its stream (ForeignStream), its box.
  template <typename Visit>
  void ForEachEntryPixel(const PacketHeader& h, int env, const PatchSampler& sampler,
                         const glm::vec3& centre, Visit visit) const;
  // Casts the centre ray of every pixel open in *mask and closes those that
  // hit, after closing those that lead to no neighbour (KeepExits).
  void CastCentres(const Patch& shooter, Skip skip, MaskBits* mask);
  // Method R: regenerates the shot's rays from its key and traces those
  // whose bit is set in `alive` (a foreign shot: the rays that entered this
  // box). A ray that leaves the box for a neighbour is routed: its bit is
  // set in routes[ExitFace], the packet for the neighbour across that face
  // (the six route masks are cleared first); rays absorbed here or escaping
  // the scene end.
  void TraceAlive(const Patch& shooter, Skip skip, const double power[3], uint64_t shotKey,
                  uint32_t rays, bool foreign, const MaskBits& alive, MaskBits* routes);
  // Method R's route masks, one a face of the box (2 * axis + (step > 0)).
  MaskBits RouteMask(int face) const { return ScratchMask(2 + static_cast<uint32_t>(face)); }
  // How many rays a local shot of `power` traces and what share of the
  // power it carries (1 unless the shot is partial).
  uint32_t ShotRays(const double power[3], uint64_t shotKey, double* fraction) const;
  // Method C's two working masks: pixels some ray hit in, and pixels some ray
  // passed unoccluded.
  MaskBits ScratchMask(uint32_t k) const;
  // Patch j receives `share` (W per channel) at point `x`.
  void Receive(uint32_t j, const double share[3], const glm::vec3& x);
  // What a shot's rays did here, summed in ray order and booked once a shot
  // (Distribute and TraceAlive share it, trace.cpp).
  struct ShotTally {
    uint64_t traced = 0, hits = 0;
    double lost[3] = {0, 0, 0};     // left the scene
    double backHit[3] = {0, 0, 0};  // absorbed by back faces
    bool outside = false;           // an outside shooter's rays (EnergyLedger::outsideLost)
  };
  // A ray's first hit here: a front side receives `share`, a back side absorbs it.
  void Land(const Ray& ray, const Hit& hit, const double share[3], ShotTally* tally);
  // The tally into the ledger and the statistics.
  void Book(const ShotTally& tally);
  // The leaf of patch `patch` holding `st`, which is left in the leaf's own
  // parameters; with `path`, the children taken are appended there (*depth
  // of them, at most the element depth).
  uint32_t Descend(uint32_t patch, glm::vec2* st, uint8_t* path, uint32_t* depth) const;
  // Splits leaf `e` of patch `j` (reached from the root by the children
  // `path[0..depth)`) if its quarters differ beyond noise.
  void MaybeSplit(uint32_t j, uint32_t e, const uint8_t* path, uint32_t depth);
  // The face by which a ray from inside leaves this environment's box (the
  // nearest far plane: 2 * axis + (step > 0)), or -1 if beyond it lies no
  // environment: the ray leaves the scene.
  int ExitFace(const Ray& ray) const;
  bool LeavesScene(const Ray& ray) const { return ExitFace(ray) < 0; }
  // Sends the shooter's packet header and `mask` to the neighbours downstream from
  // the source environment; Method R sends each neighbour its face's route
  // mask (`routes`, TraceAlive) instead.
  void Forward(PacketHeader header, const MaskBits& mask, const MaskBits* routes = nullptr);
  // The grid cells downstream of this environment for a shooter from
  // `sourceEnv` (at most 6, into `next`), and how many there are.
  int Downstream(uint32_t sourceEnv, int (*next)[3]) const;
  // The cosine-weighted share of h's hemisphere whose centre rays are open
  // in the packet's mask `bits` (null: no mask, all open) and cross the face
  // from h.fromEnv into the receiver's `box` (at grid cell `to`). Worked out
  // by the sender (Forward), with the receiver's box as the receiver makes
  // it (EnvGrid::EnvBox); every environment has the same tables
  // (maskDirections_, flightCols_).
  double FlightShare(const PacketHeader& h, const uint8_t* bits, const Bounds& box,
                     const int to[3]) const;
  // FlightShare's hemisphere resolution (the mask's, or kNoMaskRes without
  // one) and its table of column directions, made once.
  uint32_t FlightRes() const;
  void FillFlightCols();
  Span<double> flightCols_;  // per column: cos(phi), sin(phi) of its centre

  uint32_t index_ = 0;
  EnvGrid envGrid_;  // the environment partition (grid_ is the ray-casting grid)
  int cell_[3] = {0, 0, 0};
  Bounds box_;
  // The faces of box_ that another environment lies beyond (KeepExits).
  Patch exits_[6] = {};
  uint32_t numExits_ = 0;
  uint32_t numNeighbours_ = 0;
  EnvOptions options_;
  MaskShape shape_;
  MaskDirections maskDirections_;  // B and C with a downstream neighbour: the pixels' centre rays
  uint32_t packetBytes_ = 0;
  Arena arena_ = Arena::Measure();
  Span<Patch> patches_;
  Span<PatchGeom> geom_;
  Span<uint32_t> twin_;  // two-sided meshes: each patch's twin or kNoPatch; else empty
  uint32_t numTwins_ = 0;
  Span<PatchEnergy> energy_;
  Span<uint32_t> shotCount_;
  Span<Element> elements_;  // roots first (element i is patch i's), then the pool
  // directPerPixel(), 3 channels: per element, the reflected power received
  // from shots other than emission (indirect_, history included like
  // Element::received); per patch, the emitted power not yet shot (emitLeft_); shotDirect_, the
  // share of the current shot's power, per channel, that is emission.
  Span<double> indirect_;
  Span<double> emitLeft_;
  double shotDirect_[3] = {0, 0, 0};
  bool displayIndirect_ = false;
  Span<uint8_t> smoothPatch_;  // directPerPixel(): 1 for a patch of a smoothed polygon
  DirectLight direct_;
  uint32_t nextElement_ = 0;
  DisplayLattice lattice_;
  Span<PatchTexture> patchTex_;  // one per patch when any is textured, else empty
  Grid grid_;
  MaxTree tree_;
  // Exchange state: empty for an environment without neighbours.
  ForeignQueue queue_;
  Span<uint64_t> scratchWords_;  // working masks: out, incoming (and C's hit, passed)
  CentreMaskCache cache_;        // B, C: centre masks of local shooters
  Outbox outbox_;
  uint32_t newForwards_ = 0;
  // --sky, --sun: this environment's outside shooters, staged at Prepare
  // and kept in the arena (so a checkpoint's arena bytes hold their unshot
  // power); none laid out when there are none.
  struct Outside {
    OutsideShooter shooter;
    double unshot[3];
    uint32_t shots;
  };
  std::vector<Outside> stagedOutside_;
  Span<Outside> outside_;
  uint32_t numOutside_ = 0;
  EnergyLedger ledger_;
  EnvStats stats_;
  uint64_t centreSteps_ = 0;  // grid steps of the centre rays really cast
  uint64_t centreWork_ = 0;   // the work of the casts every cache size makes (workSteps)
  uint64_t centreStepsPerRay_ = 1;
  double totalArea_ = 0.0;
  double kdArea_ = 0.0;
  EnvFootprint footprint_;
  // Between Prepare and Build only.
  std::vector<Patch> staged_;
  std::vector<PatchGeom> stagedGeom_;
  std::vector<uint32_t> stagedTwin_;     // empty without twins
  std::vector<PatchTexture> stagedTex_;  // empty when no patch is textured
  DisplayLattice::Staged stagedLattice_;
  Grid::Plan plan_;
};

}  // namespace vismask
