// Work: what a round is measured in (Environment::workSteps, rounds by
// work in options.h). Counted, never timed, so a round ends at the same shot
// whatever the machine, the ranks or the transport. The unit is a grid
// step (a cell entered or a patch tested, Grid::steps); beside the walks'
// steps a round charges, in steps:
#pragma once
#include <cstdint>

#include "vismask/solve/mask.h"

namespace vismask {

// A form-factor ray, a hit (the ray's landing here: the element tree's
// descent and the receiver's update) and a shot (local or foreign: its
// sampler, mask and packets).
struct WorkCosts {
  uint64_t ray, hit, shot;
};
// The hemisphere methods (none, A, B, C): from each environment's CPU
// seconds a round regressed on its counts (docs/design/queues-rounds.md):
// what a ray, a landing and a shot cost beside their walks, in steps. The
// hit term keeps the CPU per unit of work of two environments that land
// different shares of their rays alike.
constexpr WorkCosts kMaskWork{32, 40, 12288};
// Method R, whose shots carry no hemisphere: the instructions of a ray's
// sample, regeneration and exit face, of a landing, and of a shot's sampler,
// slot, packets and delivery, over a grid step's. A hemisphere method's shot
// charge would end the rounds of an environment that makes many small
// foreign shots long before its CPU share.
constexpr WorkCosts kRayBitsWork{10, 9, 41};
inline const WorkCosts& WorkCostsOf(MaskMethod m) {
  return m == MaskMethod::kR ? kRayBitsWork : kMaskWork;
}
// The grid steps a ray takes, estimated before any grid exists (the
// automatic round size, options.h): the cube root of this many cells for
// each of an environment's patches. The steps themselves hardly depend on
// the grid's own density (Grid::MakePlan): on the default two-environment
// Cornell run, 603 M steps with 4 cells a patch and 607 M with 1, fewer
// cells holding more patches each.
constexpr double kStepCellsPerPatch = 4.0;

}  // namespace vismask
