// The defaults that follow from the run's shape (options.h): how big a
// round is (ResolveRounds, AutoRoundWork), the foreign-shooter queue
// (AutoQueue), and --envs auto for a run of several ranks without --envs
// (AutoEnvsForRanks: ParseArgs for --ranks, SetWorldSize for the MPI world) and
// --emission-rays (ResolveEmissionRays). ParseArgs calls
// ResolveRounds once the environment count is known; init sets the automatic round work from the
// scene.
#include <algorithm>
#include <cmath>

#include "vismask/app/options.h"
#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/work.h"

namespace vismask {

void ResolveRounds(int numEnvs, Options* o) {
  o->roundWorkAuto = false;
  const uint64_t packet = PacketBytes(MaskShapeOf(o->maskMethod, o->maskRes, RayCap(*o)));
  // The outbox holds 6 packets a shot: fewer shots a round with big packets.
  const uint32_t fit = static_cast<uint32_t>(std::max<uint64_t>(
      1, std::min<uint64_t>(kAutoRoundShots, kAutoRoundOutboxBytes / (6 * packet))));
  if (o->hasRoundWork || o->hasRoundShots || numEnvs <= 1) {
    if (!o->hasRoundShots) o->roundShots = o->hasRoundWork ? fit : 1;
    if (!o->hasRoundWork) o->roundWork = 0;
  } else {
    o->roundShots = fit;
    o->roundWorkAuto = true;
  }
  if (!o->hasQueue) o->queue = AutoQueue(numEnvs, o->roundShots, packet);
}

uint32_t AutoQueue(int numEnvs, uint32_t roundShots, uint64_t packetBytes) {
  // Admission shares the free slots among the environments, so a round of
  // `roundShots` local shots in each needs numEnvs x roundShots of them.
  const uint64_t want = uint64_t(std::max(numEnvs, 1)) * std::min(roundShots, kAutoQueueShots);
  const uint64_t fit = kAutoQueueBytes / std::max<uint64_t>(packetBytes, 1);
  return static_cast<uint32_t>(std::max<uint64_t>(kMinAutoQueue, std::min(want, fit)));
}

bool AutoEnvsForRanks(int ranks, Options* o) {
  if (o->hasEnvs || ranks <= 1 || o->envsAuto) return false;
  o->envsAuto = true;
  o->envsAutoCount = std::min(ranks, kMaxAutoEnvs);
  return true;
}

void ResolveEmissionRays(int numEnvs, Options* o) {
  if (!o->hasEmissionRays)
    o->emissionRays =
        o->directSamples > 0 && (numEnvs == 1 || GathersForeign(*o)) ? kDefaultEmissionRays : 1.0;
}

bool SetWorldSize(int ranks, Options* o) {
  if (!AutoEnvsForRanks(ranks, o)) return false;
  if (!ChooseEnvShape(o->envsAutoCount, glm::vec3(1.0f), o->envs)) return false;
  ResolveRounds(o->envsAutoCount, o);
  ResolveEmissionRays(o->envsAutoCount, o);
  return true;
}

uint64_t AutoRoundWork(const Options& o, double patches, int numEnvs) {
  double cells = kStepCellsPerPatch * patches / std::max(1, numEnvs);
  double steps = std::max(1.0, std::cbrt(std::max(cells, 1.0)));
  const WorkCosts& w = WorkCostsOf(o.maskMethod);
  double shot = RayCap(o) * (steps + w.ray + w.hit) + w.shot;
  return static_cast<uint64_t>(kAutoRoundWorkShots * shot);
}

}  // namespace vismask
