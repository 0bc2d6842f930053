// What an environment is built with (EnvOptions) and what its arena holds,
// part by part (EnvFootprint, from the measuring pass of its layout).
#pragma once
#include <cstdint>

#include "vismask/solve/element.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/outside.h"

namespace vismask {

// What an environment's arena holds, in bytes, by part (from the measuring
// pass of its layout; the parts sum to `total`).
struct EnvFootprint {
  uint64_t patches = 0;   // Patch, PatchGeom, PatchEnergy, shot counts, selection tree
  uint64_t vertices = 0;  // display lattice and its radiosity
  uint64_t textures = 0;  // textured patches' uv and display scale (0 with none textured)
  uint64_t elements = 0;  // the element pool (roots and children)
  uint64_t grid = 0;      // cell offsets and patch references
  uint64_t queue = 0;     // foreign-shooter slots and their masks
  uint64_t packets = 0;   // outbox, working masks and the centre-mask cache
  uint64_t total = 0;     // the arena's size (rounded up to Arena::kAlign)
  uint64_t numPatches = 0;
  uint64_t gridCells = 0;
  uint64_t numVertices = 0;   // display lattice vertices
  uint64_t numTriangles = 0;  // the patches as triangles (a quad is two): --export's
};

struct EnvOptions {
  // Grid cells per patch (Cleary's lambda). One: on the 130 000-patch box
  // 1.17-1.24x the rays per second of 4 (median of 6 alternated bench
  // pairs, docs/BENCHMARKS.md's cell-size table), the same within noise at
  // 8 000, and 16 B a patch less.
  float gridDensity = 1.0f;
  float rayEpsilon = 0.0f;  // ray origins lifted this far off the shooter's plane (scene units)
  // Rays per shot. With rayQuantum == 0 every shot traces `rays` rays.
  // With rayQuantum > 0 (power allocation) a shot of power P (channels
  // summed) traces P / rayQuantum rays, rounded stochastically from the
  // shot's own stream, at least minRays; a shot that would need more than
  // `rays` shoots only rays * rayQuantum of its power and keeps the rest
  // unshot (a partial shot), so `rays` is also the most any shot traces.
  uint32_t rays = 4096;
  double rayQuantum = 0.0;
  uint32_t minRays = 1;
  // Power allocation: the share of the rays its power is worth that a
  // shot's emission traces where the pixels gather that emission's first
  // bounce (an emitter patch's own Ke, the sun with --direct-samples):
  // there the solve's direct part only feeds the later shots, whose noise
  // the image shows (--emission-rays; docs/design/direct-light.md).
  double emissionRays = 1.0;
  bool sobol = true;  // scrambled Sobol' points; false: independent PCG32 draws
  // A local patch's rays leave from where its light landed (its leaves, in
  // proportion to their power), with one environment; false: uniform.
  bool originsByPower = true;
  // One environment, Sobol' points: a non-emitting patch's shots continue
  // one sequence (PatchStream); false: each shot its own (its key's).
  bool patchSequence = true;
  uint64_t seed = 1;  // run seed
  MaskMethod maskMethod = MaskMethod::kB;
  uint32_t maskRes = 50;
  uint32_t subGridRefs = 32;    // Grid::Nest's minRefs (--sub-grids; 0: a uniform grid)
  uint32_t roundShots = 1;      // shots per environment per round
  uint32_t queueCapacity = 64;  // foreign shooters held at once
  // Methods B and C: bytes for the centre masks of local shooters, one slot
  // per patch (direct-mapped) while they fit; kept for the patch's later
  // shots, since a local shooter's centre mask depends only on its geometry.
  uint64_t maskCacheBytes = uint64_t{8} << 20;
  // Method B: which open pixels take a centre ray (--centre-rays; ReadsOnly).
  CentreChoice centreRays = CentreChoice::kAuto;
  ElementOptions elements;
  // --direct-samples: shadow rays a shaded point sends to the emitters
  // (direct.h); 0: no per-pixel direct light (the display shows the solved
  // radiosity, direct part included). With N > 0 the environment keeps each
  // patch's indirect radiosity apart and its emitter list.
  uint32_t directSamples = 0;
  // Several environments whose pixels gather every environment's emitters
  // (--foreign-mask-res > 0): a foreign shot's emission is direct here too.
  bool gatherForeign = false;
  int indirectFilter = -1;  // display smoothing steps of the indirect part; -1: by hits a patch
  // (The automatic patch size over the patch size)^2: the automatic steps
  // scale with it (Environment::IndirectFilterSteps); set by PlanGrid.
  double filterPatchScale = 1.0;
  // --sky, --sun: the light from outside the scene's box (outside.h), in
  // outsideTiles x outsideTiles shooters a face of the box.
  OutsideLight outside;
  uint32_t outsideTiles = 1;
};

}  // namespace vismask
