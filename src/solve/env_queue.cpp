// Environment, its shots and its queue: local shots, the foreign shooters
// queued from other environments (slots, admission, delivery), forwarding
// shooters downstream with their masks, and a round's shots. The slots
// themselves are a ForeignQueue (foreign_queue.h); the power still in
// flight is in env_flight.cpp, the rest of Environment in environment.cpp,
// env_receive.cpp, env_read.cpp and trace.cpp.
#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/solve/centre_raster.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"
#include "vismask/solve/work.h"

namespace vismask {

// The grid cells downstream of this environment for a shooter from
// `sourceEnv` (at most 6, into `next`), and how many there are.
int Environment::Downstream(uint32_t sourceEnv, int (*next)[3]) const {
  int source[3];
  envGrid_.Cell(static_cast<int>(sourceEnv), source);
  int count = 0;
  for (int a = 0; a < 3; ++a) {
    // Downstream: away from the source; both ways on an axis the source shares.
    for (int step : {-1, 1}) {
      if (cell_[a] != source[a] && step != (cell_[a] > source[a] ? 1 : -1)) continue;
      int c[3] = {cell_[0], cell_[1], cell_[2]};
      c[a] += step;
      if (c[a] < 0 || c[a] >= envGrid_.n[a]) continue;
      for (int k = 0; k < 3; ++k) next[count][k] = c[k];
      ++count;
    }
  }
  return count;
}

// Sends the shooter's packet header and `mask` to the neighbours downstream from
// the source environment; Method R sends each neighbour its face's route
// mask (`routes`, TraceAlive) instead.
void Environment::Forward(PacketHeader h, const MaskBits& mask, const MaskBits* routes) {
  int next[6][3];
  int count = Downstream(h.sourceEnv, next);
  h.fromEnv = index_;
  for (int k = 0; k < count; ++k) {
    const int* c = next[k];
    // Method R: the rays routed across the face to this neighbour, none if
    // no ray goes there (it never hears of the shot); only the shot's rays
    // travel (the bits past them are closed).
    int face = 0;
    for (int a = 0; a < 3; ++a)
      if (c[a] != cell_[a]) face = 2 * a + (c[a] > cell_[a]);
    if (routes && routes[face].CountOpen(0, h.rays) == 0) continue;
    uint8_t* packet = exchange_.outbox().Add();
    h.toEnv = static_cast<uint32_t>(envGrid_.Index(c[0], c[1], c[2]));
    if (routes) {
      routes[face].Pack(MaskBytes(packet), h.rays);
    } else if (!shape_.empty()) {
      mask.Pack(MaskBytes(packet));
    }
    // The receiver's share of the power in flight, worked out here from the
    // bytes it will get, so that this round's report can count it (exchange.h).
    // Its box and cell as it makes its own (Prepare).
    h.flightShare =
        options_.maskMethod == MaskMethod::kR ? 0.0f
        : (h.flags & kReadsOnly)
            ? static_cast<float>(ReadShare(h, mask, static_cast<int>(h.toEnv)))
            : static_cast<float>(FlightShare(h, shape_.empty() ? nullptr : MaskBytes(packet),
                                             envGrid_.EnvBox(static_cast<int>(h.toEnv)), c));
    WriteHeader(packet, h);
    ++stats_.packetsSent;
  }
}

void Environment::ShootLocal(uint32_t i) {
  PatchEnergy& src = energy_[i];
  const Patch& p = patches_[i];
  uint32_t shotIndex = shotCount_[i]++;
  uint64_t key = ShotKey(options_.seed, p.globalId, shotIndex);
  double fraction = 1.0;
  uint32_t rays = ShotRays(src.unshot, direct_.EmissionIn(i, src.unshot), key, &fraction);
  // A partial shot keeps the rest of the power unshot, at the top of the tree.
  double power[3];
  for (int c = 0; c < 3; ++c) {
    power[c] = fraction < 1.0 ? src.unshot[c] * fraction : src.unshot[c];
    // Per-pixel direct light: the share of this shot that is the patch's
    // own emission, in proportion to the emission in its unshot power.
    direct_.BookLocalShot(i, c, src.unshot[c], power[c], fraction);
    ledger_.unshot[c] -= power[c];
    src.unshot[c] = fraction < 1.0 ? src.unshot[c] - power[c] : 0.0;
  }
  tree_.Set(i, fraction < 1.0 ? UnshotKey(src) : 0.0);
  ++stats_.shots;
  // The shooter's rays ignore it and its twin (coplanar, behind them).
  ShootOwn(p, Skip(i, twinOf(i)), power, key, shotIndex, rays, i);
}

// A shot made here (a local patch's, or an outside shooter's): its rays
// traced, and with neighbours its packets made and forwarded. `cached`:
// the local patch whose centre mask B and C may take from the cache
// (kNoPatch: none).
void Environment::ShootOwn(const Patch& p, Skip skip, const double power[3], uint64_t key,
                           uint32_t shotIndex, uint32_t rays, uint32_t cached) {
  if (numNeighbours_ == 0) {
    // One environment, Sobol' points: a local patch's shots continue one
    // sequence (PatchStream), so that its rays over all its shots are one
    // stratified set, not a few independent ones. Not an emitter's: its
    // emission's many partial shots then made one long sequence whose
    // scramble, unlucky for one seed in six, moved the whole image (docs/
    // design/solve.md). With neighbours a foreign environment regenerates
    // a shot's rays from its key alone.
    uint64_t stream = key;
    uint32_t first = 0;
    if (options_.patchSequence && options_.sobol && skip.patch != kNoPatch &&
        p.ke[0] + p.ke[1] + p.ke[2] == 0.0f) {
      stream = PatchStream(options_.seed, p.globalId);
      first = raysShot_[skip.patch];
      raysShot_[skip.patch] += rays;
    }
    Distribute(p, skip, power, stream, rays, nullptr, nullptr, nullptr, nullptr, nullptr, first);
    return;
  }
  MaskBits out = exchange_.ScratchMask(0);
  out.SetAllOpen();
  PacketHeader shot = ShotHeader(p, power, key, shotIndex, index_, rays);
  for (int c = 0; c < 3; ++c) shot.direct[c] = static_cast<float>(direct_.shotDirect(c));
  if (options_.maskMethod == MaskMethod::kR) {
    out.CloseFrom(rays);  // bits past the shot's rays
    MaskBits routes[6];
    for (int f = 0; f < 6; ++f) routes[f] = exchange_.RouteMask(f);
    TraceAlive(p, skip, power, key, rays, false, out, routes);
    Forward(shot, out, routes);
  } else {
    // B and C: a local shooter's centre mask from the cache (cast on a miss).
    MaskBits centre, known, read;
    const bool hit = cached != kNoPatch && CachedCentre(cached, &centre, &known);
    MaskBits* knownPixels = hit && PartCentres() ? &known : nullptr;
    const bool readOnly = ReadsOnly(rays);
    if (readOnly) {
      shot.flags |= kReadsOnly;
      ++stats_.readShots;
      read = exchange_.ScratchMask(2);
      ReadPixels(shot, &read);
    }
    Distribute(p, skip, power, key, rays, nullptr, &out, hit ? &centre : nullptr, knownPixels,
               readOnly ? &read : nullptr);
    Forward(shot, out);
  }
  ++stats_.forwardsCreated;
  --newForwards_;
}

bool Environment::HasLocalUnshot() const {
  const uint32_t top = tree_.Top();
  if (top != kNoPatch && UnshotKey(energy_[top]) > 0.0) return true;
  return outside_.Best() >= 0;
}

// Outside shooter k (--sky, --sun) shoots, as a local patch does but with
// no patch to skip and no centre-mask cache.
void Environment::ShootOutside(uint32_t k) {
  OutsideSet::Entry& o = outside_[k];
  const Patch& p = o.shooter.patch;
  const uint32_t shotIndex = o.shots++;
  const uint64_t key = ShotKey(options_.seed, p.globalId, shotIndex);
  double fraction = 1.0;
  const OutsideKind kind = OutsideKindOf(p.globalId);
  const double emission = direct_.Gathers(kind) ? o.unshot[0] + o.unshot[1] + o.unshot[2] : 0.0;
  const uint32_t rays = ShotRays(o.unshot, emission, key, &fraction);
  // Per-pixel direct light: a sun shot's first bounce is the gather's
  // (direct), a sky shot's the solve's (indirect).
  direct_.BookOutsideShot(kind);
  double power[3];
  for (int c = 0; c < 3; ++c) {
    power[c] = fraction < 1.0 ? o.unshot[c] * fraction : o.unshot[c];
    ledger_.unshot[c] -= power[c];
    o.unshot[c] = fraction < 1.0 ? o.unshot[c] - power[c] : 0.0;
  }
  ++stats_.shots;
  // No patch to skip: its rays start outside the box (MakeShotRay), and
  // Distribute treats them as it does a foreign shooter's, clipped to the box.
  ShootOwn(p, Skip(kNoPatch), power, key, shotIndex, rays, kNoPatch);
}

void Environment::ShootForeign(uint32_t s) {
  ForeignQueue& queue = exchange_.queue();
  const ForeignQueue::Slot& slot = queue.slot(s);
  direct_.BookForeignShot(slot.header.direct);
  MaskBits in = queue.Mask(s);
  MaskBits out = exchange_.ScratchMask(0);
  if (options_.maskMethod != MaskMethod::kR) out.CopyFrom(in);  // R routes its rays instead
  Patch shooter = PatchFromHeader(slot.header);
  // The outgoing mask only where there is someone downstream to send it to
  // (R sends its route masks instead, TraceAlive).
  int next[6][3];
  bool forward = Downstream(slot.header.sourceEnv, next) > 0;
  MaskBits routes[6];
  if (options_.maskMethod == MaskMethod::kR) {
    for (int f = 0; f < 6; ++f) routes[f] = exchange_.RouteMask(f);
    TraceAlive(shooter, kNoPatch, slot.header.power, slot.header.shotKey, slot.header.rays, true,
               in, routes);
  } else {
    MaskBits read;
    const bool readOnly = forward && (slot.header.flags & kReadsOnly);
    if (readOnly) {
      read = exchange_.ScratchMask(2);
      ReadPixels(slot.header, &read);
    }
    Distribute(shooter, kNoPatch, slot.header.power, ForeignStream(slot.header.shotKey, index_),
               slot.header.rays, &in, forward ? &out : nullptr, nullptr, nullptr,
               readOnly ? &read : nullptr);
  }
  ++stats_.foreignShots;
  if (forward) Forward(slot.header, out, options_.maskMethod == MaskMethod::kR ? routes : nullptr);
  queue.Release(s);
}

// Delivery, in a fixed order (sender, then send order) for reproducible
// results.
void Environment::Deliver(const uint8_t* packet) {
  PacketHeader h = ReadHeader(packet);
  CHECK(h.toEnv == index_ && numNeighbours_ > 0);
  // A hemisphere mask waits for every upstream neighbour's. R's packets
  // come only from neighbours that send rays here, each ready at once;
  // those of one round for one shot go into one slot (ForeignQueue::Deliver).
  uint32_t expected = 1;
  if (options_.maskMethod != MaskMethod::kR) {
    int source[3];
    envGrid_.Cell(static_cast<int>(h.sourceEnv), source);
    expected = 0;
    for (int a = 0; a < 3; ++a) expected += cell_[a] != source[a];
  }
  exchange_.queue().Deliver(packet, h, options_.maskMethod, expected, exchange_.ScratchMask(1));
}

// The work rounds are measured in, counted, never timed (work.h): the
// form-factor rays' grid steps and WorkCosts' charges, and the centre casts
// every --mask-cache makes (a local shooter's later, cached casts are left
// out).
uint64_t Environment::workSteps() const {
  const WorkCosts& w = WorkCostsOf(options_.maskMethod);
  return grid_.steps() - resetSteps_ - centreSteps_ + centreWork_ +
         w.ray * (stats_.rays + stats_.readRays) + w.hit * stats_.hits +
         w.shot * (stats_.shots + stats_.foreignShots);
}

uint64_t Environment::shotWork() const {
  return stats_.castWork +
         WorkCostsOf(options_.maskMethod).shot * (stats_.shots + stats_.foreignShots);
}

uint64_t Environment::paceWork() const {
  return workSteps() - centreWork_ + stats_.castWork;
}

// One round: up to `shotBudget` shots, each the larger of the local patch
// or outside shooter with most unshot power (while `newForwards` remains,
// with neighbours) and the ready foreign shooter with most power; ends once
// the round's work reaches `roundWork` (0: no limit). Packets for
// neighbours go to the outbox.
void Environment::RunRound(uint32_t shotBudget, uint32_t newForwards, uint64_t roundWork) {
  newForwards_ = newForwards;
  // The round's work: grid steps counted, never timed, so the round ends
  // at the same shot whatever the machine, the ranks or the transport.
  const uint64_t work0 = workSteps();
  for (uint32_t k = 0; k < shotBudget; ++k) {
    if (roundWork > 0 && workSteps() - work0 >= roundWork) break;
    uint32_t local = tree_.Top();
    double localKey = local == kNoPatch ? 0.0 : tree_.Key(local);
    // An outside shooter (--sky, --sun) goes before the patches when it has
    // more unshot power (ties to the patch).
    const int outside = outside_.size() > 0 ? outside_.Best() : -1;
    if (outside >= 0) {
      const double* u = outside_[outside].unshot;
      const double key = u[0] + u[1] + u[2];
      if (key > localKey) {
        localKey = key;
        local = kOutsideIdBase;
      }
    }
    bool localOk = localKey > 0.0 && (numNeighbours_ == 0 || newForwards_ > 0);
    const ForeignQueue& queue = exchange_.queue();
    int s = numNeighbours_ > 0 ? queue.BestReady() : -1;
    if (s >= 0 && (!localOk || queue.slot(static_cast<uint32_t>(s)).key >= localKey)) {
      ShootForeign(static_cast<uint32_t>(s));
    } else if (localOk && local == kOutsideIdBase) {
      ShootOutside(static_cast<uint32_t>(outside));
    } else if (localOk) {
      ShootLocal(local);
    } else {
      break;
    }
  }
  stats_.gridSteps = grid_.steps() - resetSteps_;
}

}  // namespace vismask
