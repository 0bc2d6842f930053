// An environment's bookkeeping: its energy ledger, its work counters and
// what a checkpoint keeps of it beside its arena's bytes (checkpoint.h).
#pragma once
#include <cstdint>

namespace vismask {

// Per-channel energy bookkeeping, in W (double). For one environment with no
// neighbours, emitted == absorbed + escaped + unshot up to rounding; with
// several, the difference is the power still in flight between environments
// plus what the masks lost or let leak. Method R books its power in flight
// exactly (summed over all environments, emitted == absorbed + escaped +
// unshot + inFlight up to rounding); the hemisphere masks cannot, and leave
// inFlight at 0.
struct EnergyLedger {
  double emitted[3] = {0, 0, 0};
  double absorbed[3] = {0, 0, 0};  // by receivers (1 - kd) and by back faces
  double escaped[3] = {0, 0, 0};   // rays that left the scene
  double unshot[3] = {0, 0, 0};    // local patches' unshot power, kept current
  // Method R: + the rays that left this environment for a neighbour, - those
  // that entered it from one (a ray enters exactly the next environment on
  // its path, so the sum over environments is the power not yet traced).
  double inFlight[3] = {0, 0, 0};
  double radiosity[3] = {0, 0, 0};  // sum of b * area over local patches (emitted + reflected)
  // --sky, --sun: of absorbed and escaped, what outside shooters' rays lost
  // at once, on a back face or crossing the scene without a hit: light
  // that never lit the scene. The solve's stop rules leave it out of the
  // emitted and radiosity power (exchange.cpp), so that the sky on the
  // outside of a closed room's walls does not count as converged power.
  double outsideLost[3] = {0, 0, 0};
};

// Counters of one environment's work.
struct EnvStats {
  uint64_t shots = 0;            // local shots
  uint64_t foreignShots = 0;     // queued foreign shooters distributed here
  uint64_t rays = 0;             // form-factor rays traced
  uint64_t maskRays = 0;         // Method B's and C's centre rays (pixels decided)
  uint64_t maskRaysByPatch = 0;  // those decided patch by patch (RasterCentres)
  uint64_t maskNoExit = 0;       // pixels closed because they lead to no neighbour (KeepExits)
  uint64_t castWork = 0;         // the work of every centre cast, cached or not (CastCentres)
  uint64_t readShots = 0;        // B's local shots deciding only the pixels read (ReadsOnly)
  uint64_t readRays = 0;         // rays regenerated for it (ReadPixels, ReadShare)
  uint64_t gridSteps = 0;        // their walks' cells entered and patches tested (Grid::steps)
  uint64_t hits = 0;
  uint64_t packetsSent = 0;
  uint64_t forwardsCreated = 0;  // local shots that went on to neighbours
  uint64_t splits = 0;           // elements split into four
  uint64_t refusedSplits = 0;    // splits refused because the element pool was used up
};

// What a checkpoint keeps of an environment beside its arena's bytes (the
// patches' energy, elements, shot counts, queue, slots and selection trees
// all live there): the counters and the ledger held in the object. Trivially
// copyable, written as it is (checkpoint.h).
struct EnvState {
  uint64_t arenaUsed;  // the arena's bytes (checked on resume: the same layout)
  uint64_t numPatches;
  uint64_t gridSteps;
  uint64_t centreSteps;
  uint64_t centreWork;
  uint32_t nextElement;
  uint32_t queued;
  uint32_t outCount;  // 0 at a round's end (the outbox is delivered)
  uint32_t index;
  EnergyLedger ledger;
  EnvStats stats;
};

}  // namespace vismask
