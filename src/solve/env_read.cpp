// Environment, Method B's reading shots (--centre-rays): whether a local
// shot decides only the pixels its rays will read downstream (auto's costs,
// FillReadCosts and ReadsOnly), those pixels (ReadPixels), and the share of
// a shot's rays an environment downstream traces through an open pixel
// (ReadShare). Rays are regenerated as the environments downstream trace them.
#include <cmath>

#include "shot_ray.h"
#include "vismask/solve/centre_raster.h"
#include "vismask/solve/environment.h"

namespace vismask {

// auto's costs, in centre rays cast (a centre ray's walk is the unit; the
// weights are instruction counts relative to it: docs/design/masks.md).
// Regenerating a ray downstream (its sample, ray, box test and entry pixel)
// costs about half of one; a read pixel about half a centre ray a ray of
// the shot (some rays share pixels, some pixels are known or closed
// upstream); a mask where every open pixel is cast takes a centre ray for
// fewer than half its pixels (KeepExits and the closing upstream pass over
// the rest); and casting a mask patch by patch costs about four centre rays
// a patch (CastCentres).
// The source's own cast counts in full, though a local shooter's mask is
// kept for its later shots: which shots read must not depend on the cache.
constexpr double kRegenCost = 0.5;
constexpr double kReadCast = 0.5;
constexpr double kCastShare = 0.4;
constexpr double kPatchCast = 4.0;
constexpr int kReadEnvs = 8;

// auto's counts for shots from here, in centre rays cast, from the grid
// and the patch count (Layout): per ray of a shot, what reading costs
// (every ray regenerated for each environment beyond a forwarding one
// and for each packet's share, and the read pixels' casts); what casting
// every open pixel costs, here and in each forwarding environment
// downstream; and whether any shot from here, of the fewest rays a shot
// may have, reads.
void Environment::FillReadCosts(uint32_t numPatches) {
  readPerRay_ = 0.0;
  allCost_ = 0.0;
  mayRead_ = false;
  if (numNeighbours_ == 0 || options_.maskMethod != MaskMethod::kB) return;
  mayRead_ = options_.centreRays == CentreChoice::kRead;
  // Beyond kReadEnvs environments auto never reads: a read shot's
  // regeneration grows with every environment beyond every forwarding one
  // (a 5x5x5 run of 64-ray shots did not finish in minutes), which the
  // counts below understate. The counts, a pass over every environment,
  // are only needed up to there; beyond, they stay 0 and ReadsOnly says no.
  if (options_.centreRays != CentreChoice::kAuto || envGrid_.count() > kReadEnvs) return;
  double forwarders = 0.0;
  const int count = envGrid_.count();
  double regenerated = 0.0, casting = 0.0;
  for (int e = 0; e < count; ++e) {
    // e's neighbours downstream of here (Downstream), and the environments
    // beyond it (ReadPixels), e itself among them.
    int c[3];
    envGrid_.Cell(e, c);
    int next = 0;
    double beyond = 1.0;
    for (int a = 0; a < 3; ++a) {
      const int n = envGrid_.n[a];
      if (c[a] == cell_[a]) {
        next += (c[a] > 0) + (c[a] + 1 < n);
        beyond *= n;
      } else if (c[a] > cell_[a]) {
        next += c[a] + 1 < n;
        beyond *= n - c[a];
      } else {
        next += c[a] > 0;
        beyond *= c[a] + 1;
      }
    }
    if (next == 0) continue;
    regenerated += (beyond - 1.0) + next;
    casting += 1.0;
    forwarders += e != static_cast<int>(index_);
  }
  readPerRay_ = kRegenCost * regenerated + kReadCast * casting;
  // Casting every open pixel, here and in each forwarding environment
  // downstream, patch by patch where that is cheaper (CastCentres). Not
  // what the cache already knows: the choice, and so the output, must not
  // depend on --mask-cache.
  const double byPatch = kPatchCast * static_cast<double>(numPatches);
  allCost_ = (1.0 + forwarders) * std::min(kCastShare * shape_.pixels(), byPatch);
  // Some local shot may read if one of the fewest rays a shot may have would.
  const uint32_t fewest =
      options_.rayQuantum > 0.0 ? std::max(options_.minRays, 1u) : options_.rays;
  mayRead_ = ReadsOnly(fewest);
}

// Method B: whether local patch i's shot of `rays` rays decides only the
// pixels its rays will read downstream (ReadPixels), its packets carrying
// the share of the receiver's rays that pass (ReadShare) as their power in
// flight and priority, rather than every open pixel that leads to a
// neighbour. The source decides and says so in the packets' flags, which
// every environment downstream follows. auto: whichever costs fewer
// centre rays' worth by FillReadCosts' counts.
bool Environment::ReadsOnly(uint32_t rays) const {
  if (options_.maskMethod != MaskMethod::kB || numNeighbours_ == 0) return false;
  if (options_.centreRays != CentreChoice::kAuto) return options_.centreRays == CentreChoice::kRead;
  return rays * readPerRay_ < allCost_;
}

// Calls visit(pixel) with the entry pixel (Distribute's: where the ray
// enters the box, seen from the shooter's centre) of every ray of h that
// environment `env` traces for it: its stream (ForeignStream), its box.
template <typename Visit>
void Environment::ForEachEntryPixel(const PacketHeader& h, int env, const Patch& shooter,
                                    const PatchSampler& sampler, const glm::vec3& centre,
                                    Visit visit) const {
  const Bounds box = envGrid_.EnvBox(env);
  RayPoints points(options_.sobol, ForeignStream(h.shotKey, static_cast<uint32_t>(env)));
  for (uint32_t r = 0; r < h.rays; ++r) {
    float u[5];
    points.Next(r, u, true);
    glm::vec3 local;
    Ray ray = MakeShotRay(shooter, sampler, u, &local);
    float t0, t1;
    if (!Slabs(ray, box, &t0, &t1)) continue;
    visit(EntryPixel(ray, t0, centre, sampler.frame, local, exchange_.directions()));
  }
}

// --centre-rays read: opens in *read (closed first) the pixel of every ray
// that an environment downstream of this one will trace for the shot `h`
// (Distribute's foreign rays: its stream, its box, the pixel of where the
// ray enters it seen from the shooter's centre), every one it may reach.
void Environment::ReadPixels(const PacketHeader& h, MaskBits* read) {
  read->SetAllClosed();
  const Patch shooter = PatchFromHeader(h);  // as the receivers make it
  const PatchSampler sampler = MakePatchSampler(shooter);
  const glm::vec3 centre = MaskCentre(shooter);
  int source[3];
  envGrid_.Cell(static_cast<int>(h.sourceEnv), source);
  for (int e = 0; e < envGrid_.count(); ++e) {
    if (e == static_cast<int>(index_)) continue;
    // Downstream of here, however far: beyond this cell on every axis on
    // which this cell is beyond the source (Downstream, step by step).
    int c[3];
    envGrid_.Cell(e, c);
    bool beyond = true;
    for (int a = 0; a < 3; ++a)
      if (cell_[a] != source[a]) beyond &= (c[a] - cell_[a]) * (cell_[a] - source[a]) >= 0;
    if (!beyond) continue;
    stats_.readRays += h.rays;
    ForEachEntryPixel(h, e, shooter, sampler, centre,
                      [read](uint32_t pixel) { read->Open(pixel); });
  }
}

// --centre-rays read: the share of h's rays that environment `to` will
// trace through pixels open in `mask` (its rays regenerated here).
double Environment::ReadShare(const PacketHeader& h, const MaskBits& mask, int to) {
  const Patch shooter = PatchFromHeader(h);
  const PatchSampler sampler = MakePatchSampler(shooter);
  stats_.readRays += h.rays;
  uint32_t open = 0;
  ForEachEntryPixel(h, to, shooter, sampler, MaskCentre(shooter),
                    [&](uint32_t pixel) { open += mask.IsOpen(pixel); });
  return h.rays > 0 ? static_cast<double>(open) / h.rays : 0.0;
}

}  // namespace vismask
