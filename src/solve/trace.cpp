// Environment, its rays: a shot's form-factor rays traced through this
// environment's grid (Distribute: radiosity received, Method A/B/C masks
// marked; TraceAlive: Method R's rays in flight), and where a ray leaves the
// environment's box. The rest of Environment is in environment.cpp (init),
// env_receive.cpp (receiving, elements, display), env_queue.cpp (shots and
// the queue), env_read.cpp (B's reading shots) and env_flight.cpp (power in
// flight); shot_ray.h has the ray helpers they share.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "shot_ray.h"
#include "vismask/core/fminmax.h"
#include "vismask/solve/centre_raster.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"
#include "vismask/solve/sobol.h"

namespace vismask {

namespace {

// --sky FILE.hdr: the per-ray shares of sky shooter `id`'s shot (SkyShares,
// outside.h): the map's radiance summed over every ray of the shot, in ray
// order, as every environment that traces one of them sums it. No map, or
// not the sky: every ray carries power / rays.
SkyShares SkySharesOf(const OutsideLight& lit, bool sobol, const Frame& frame, uint32_t id,
                      uint64_t stream, uint32_t rays, const double power[3]) {
  SkyShares s;
  if (!lit.skyMap || OutsideKindOf(id) != OutsideKind::kSky || rays == 0) return s;
  s.map = lit.skyMap.get();
  RayPoints points(sobol, stream);
  double sum[3] = {0, 0, 0};
  for (uint32_t r = 0; r < rays; ++r) {
    float u[5];
    points.Next(r, u, true);
    const glm::vec3 l = s.map->Radiance(-frame.ToWorld(CosineDirection(u[3], u[4])));
    for (int c = 0; c < 3; ++c) sum[c] += l[c];
  }
  s.rays = rays;
  for (int c = 0; c < 3; ++c) {
    s.sum[c] = sum[c];
    s.even[c] = power[c] / rays;
  }
  return s;
}

// What a shot's rays start from, the same for Distribute and TraceAlive:
// the shooter's sampler, its ray points from `stream`, the even share of
// `power` a ray carries, and the sky map's shares (SkySharesOf).
struct ShotSetup {
  ShotSetup(const EnvOptions& options, const Patch& shooter, const double power[3], uint64_t stream,
            uint32_t rays, uint32_t first = 0)
      : sampler(MakePatchSampler(shooter)),
        points(options.sobol, stream, first),
        sky(SkySharesOf(options.outside, options.sobol, sampler.frame, shooter.globalId, stream,
                        rays, power)) {
    for (int c = 0; c < 3; ++c) share[c] = power[c] / rays;
  }
  PatchSampler sampler;
  RayPoints points;
  SkyShares sky;
  double share[3];
};

// Method C: an open pixel of *out whose rays only hit closes; *hit becomes
// the pixels left to the centre ray: open, and with both kinds of ray or
// none. Word by word (bits past the last pixel are 0 in all three).
void SplitByRays(MaskBits* out, MaskBits* hit, const MaskBits& passed) {
  Span<uint64_t> o = out->words(), h = hit->words();
  const Span<uint64_t> q = passed.words();
  for (size_t w = 0; w < o.size(); ++w) {
    const uint64_t open = o[w], hits = h[w], passes = q[w];
    o[w] = open & ~(hits & ~passes);
    h[w] = open & ~(hits ^ passes);
  }
}

}  // namespace

// What a shot's rays did here, summed in ray order and booked once a shot
// (Distribute and TraceAlive share it).
struct Environment::ShotTally {
  explicit ShotTally(const Patch& shooter)
      : outside(OutsideKindOf(shooter.globalId) != OutsideKind::kNone) {}
  uint64_t traced = 0, hits = 0;
  double lost[3] = {0, 0, 0};     // left the scene
  double backHit[3] = {0, 0, 0};  // absorbed by back faces
  bool outside;                   // an outside shooter's rays (EnergyLedger::outsideLost)
};

// Ray r of a shot of `shooter` from its five uniforms: ShotRay for a
// patch, its origin moved into the patch's open cells when it has them
// (Patch::openCells: u[1] picks the cell, u[2] the point across it, as
// ElementTree::SampleByPower does in a leaf); for an outside shooter
// (outside.h) its direction (cosine for the sky, the sun's cone for the
// sun) from a point of its face, the origin moved back along the ray to
// OutsideLift() outside the scene's box, so that the ray crosses geometry
// lying on the box's face (a floor on its bottom) rather than starting in
// its plane.
Ray Environment::MakeShotRay(const Patch& shooter, const PatchSampler& sampler, const float u[5],
                             glm::vec3* local) const {
  const OutsideKind kind = OutsideKindOf(shooter.globalId);
  if (kind == OutsideKind::kNone) {
    Ray ray = ShotRay(sampler, u, options_.rayEpsilon, local);
    if (shooter.openCells != 0) {
      float a = u[1], b = u[2];
      ElementTree::OpenCellsPoint(shooter.openCells, &a, &b);
      ray.o = PatchPoint(shooter, glm::vec2(a, b)) + options_.rayEpsilon * sampler.frame.n;
    }
    return ray;
  }
  const Frame& f = sampler.frame;
  glm::vec3 d;
  if (kind == OutsideKind::kSky) {
    *local = CosineDirection(u[3], u[4]);
    d = f.ToWorld(*local);
  } else {
    d = SunRayDirection(options_.outside, u[3], u[4]);
    *local = glm::vec3(glm::dot(d, f.t), glm::dot(d, f.b), glm::dot(d, f.n));
  }
  // Back along the ray to OutsideLift() off the face (a ray so grazing that
  // this would take it far: less, from 1e-3 of the way in).
  const float cosine = FMax(glm::dot(d, f.n), 1e-3f);
  Ray ray;
  ray.o = sampler.Point(u[0], u[1], u[2]) - (OutsideLift() / cosine) * d;
  ray.d = d;
  ray.tMin = 0.0f;
  ray.tMax = std::numeric_limits<float>::infinity();
  return ray;
}

// A ray's first hit here: a front side receives `share`, a back side absorbs it.
// Centre rays start rayEpsilon in front of a patch, OutsideLift() behind an
// outside shooter (outside the box).
float Environment::CentreLift(uint32_t id) const {
  return OutsideKindOf(id) == OutsideKind::kNone ? options_.rayEpsilon : -OutsideLift();
}
float Environment::OutsideLift() const {
  return 4.0f * options_.rayEpsilon;
}

void Environment::Land(const Ray& ray, const Hit& hit, const double share[3], ShotTally* tally) {
  ++tally->hits;
  if (!hit.front) {
    for (int c = 0; c < 3; ++c) tally->backHit[c] += share[c];
    return;
  }
  Receive(hit.patch, share, ray.o + hit.t * ray.d);
}

// The tally into the ledger and the statistics.
void Environment::Book(const ShotTally& tally) {
  for (int c = 0; c < 3; ++c) {
    ledger_.escaped[c] += tally.lost[c];
    ledger_.absorbed[c] += tally.backHit[c];
    if (tally.outside) ledger_.outsideLost[c] += tally.lost[c] + tally.backHit[c];
  }
  stats_.rays += tally.traced;
  stats_.hits += tally.hits;
}

// The face by which a ray from inside leaves this environment's box (the
// nearest far plane: 2 * axis + (step > 0)), or -1 if beyond it lies no
// environment: the ray leaves the scene.
int Environment::ExitFace(const Ray& ray) const {
  // The face through which the ray leaves this box: the nearest far plane.
  float best = std::numeric_limits<float>::infinity();
  int axis = 0, step = 0;
  for (int a = 0; a < 3; ++a) {
    if (ray.d[a] == 0.0f) continue;
    float t = ((ray.d[a] > 0.0f ? box_.hi[a] : box_.lo[a]) - ray.o[a]) / ray.d[a];
    if (t < best) {
      best = t;
      axis = a;
      step = ray.d[a] > 0.0f ? 1 : -1;
    }
  }
  int next = cell_[axis] + step;
  if (next < 0 || next >= envGrid_.n[axis]) return -1;
  return 2 * axis + (step > 0);
}

// One environment: a local patch's rays leave from where its light landed
// (ElementTree::SampleByPower, MakeQuarterOrigins). With neighbours a
// foreign environment regenerates the shot's rays from the packet alone,
// so they leave uniformly from the patch's open cells (MakeShotRay).
bool Environment::OriginsByPower(const Patch& shooter, bool foreign) const {
  return options_.originsByPower && !foreign && numNeighbours_ == 0 &&
         OutsideKindOf(shooter.globalId) == OutsideKind::kNone &&
         shooter.ke[0] + shooter.ke[1] + shooter.ke[2] == 0.0f;
}

// Traces `rays` rays of one shooter through this environment. Rays whose
// pixel is closed in `in` are skipped; with a mask method, `out` loses the
// pixels of rays that hit here (A), of centre rays that hit (B), or of
// pixels the rays only hit and those whose centre ray hits (C).
// `centre`, when given, is this shooter's slot of the centre-mask cache
// (CachedCentre): B reads every pixel from it; C reads the pixels set in
// *known, and casts the others it needs into it.
// `read` (--centre-rays read, B): the pixels downstream will read; B
// decides only those (ReadPixels).
void Environment::Distribute(const Patch& shooter, Skip skip, const double power[3],
                             uint64_t stream, uint32_t rays, const MaskBits* in, MaskBits* out,
                             MaskBits* centreMask, MaskBits* known, MaskBits* read,
                             uint32_t first) {
  const bool masks = shape_.res > 0;
  const bool foreign = in != nullptr || skip.patch == kNoPatch;
  // Method C: which open pixels the rays hit in, and which they passed.
  const bool methodC = masks && out && options_.maskMethod == MaskMethod::kC;
  // A local ray's pixel matters to the methods that mark pixels by rays: B's
  // mask comes from the centre rays alone.
  const bool marks = masks && out && options_.maskMethod != MaskMethod::kB;
  MaskBits hitPixels, passedPixels;
  if (methodC) {
    hitPixels = exchange_.ScratchMask(2);
    passedPixels = exchange_.ScratchMask(3);
    hitPixels.SetAllClosed();
    passedPixels.SetAllClosed();
  }
  ShotSetup shot(options_, shooter, power, stream, rays, first);
  ShotTally tally(shooter);
  const glm::vec3 centre = MaskCentre(shooter);
  const bool byPower = OriginsByPower(shooter, foreign);
  ElementTree::QuarterOrigins origins;
  const bool quarters =
      byPower && elements_.MakeQuarterOrigins(shooter.numCorners == 3, skip.patch, &origins);
  for (uint32_t r = 0; r < rays; ++r) {
    float u[5];
    shot.points.Next(r, u, true);
    glm::vec3 local;
    Ray ray = quarters ? QuarterRay(shooter, shot.sampler, origins, u, options_.rayEpsilon, &local)
                       : MakeShotRay(shooter, shot.sampler, u, &local);
    glm::vec2 st;
    if (!quarters && byPower &&
        elements_.SampleByPower(shooter.numCorners == 3, skip.patch, u, &st))
      ray.o = PatchPoint(shooter, st) + options_.rayEpsilon * shot.sampler.frame.n;
    double ratio[3];
    if (shot.sky.map) shot.sky.Of(ray.d, shot.share, ratio);
    uint32_t pixel = 0;
    if (foreign) {
      float t0, t1;
      if (!Slabs(ray, box_, &t0, &t1)) continue;  // never passes through here
      if (masks) {
        pixel = EntryPixel(ray, t0, centre, shot.sampler.frame, local, exchange_.directions());
        if (in && !in->IsOpen(pixel)) continue;  // occluded upstream
      }
    } else if (marks) {
      pixel = exchange_.directions().CosinePixel(u[4], local);
    }
    ++tally.traced;
    Hit hit;
    if (!grid_.Intersect(ray, skip, &hit)) {
      if (methodC) passedPixels.Open(pixel);
      if (ExitFace(ray) < 0)  // leaves the scene
        for (int c = 0; c < 3; ++c) tally.lost[c] += shot.share[c];
      continue;
    }
    if (masks && out && options_.maskMethod == MaskMethod::kA) out->Close(pixel);
    if (methodC) hitPixels.Open(pixel);
    Land(ray, hit, shot.share, &tally);
  }
  Book(tally);

  // Method B: the mask from the centre alone, one ray through each pixel
  // still open upstream (the paper's B). Mixing in A's marks would close
  // every pixel where any off-centre ray hit, losing the rays of that pixel
  // that pass on: power that then never arrives (the closed box's ledger).
  // Method C: a pixel whose rays all hit closes, one whose rays all passed
  // stays open; only pixels with both, or with no ray, take the centre ray.
  // B deciding only the open pixels some ray downstream will read (*read,
  // ReadsOnly; the others stay as they are), or every open pixel with a
  // cache of known pixels (PartCentres): it casts only the pixels whose
  // centre ray is not known yet, into the cache. Its bits are CastCentres'
  // whichever pixels a shot decides, so a pixel means the same to every
  // shot that reads it from the cache.
  if (masks && out && options_.maskMethod == MaskMethod::kB && (read || known)) {
    MaskBits decide = exchange_.ScratchMask(3);
    decide.CopyFrom(*out);
    if (read) decide.And(*read);
    if (known) {
      decide.AndNot(*known);
      known->Or(decide);
      centreMask->AndNot(decide);
      CastCentres(shooter, skip, &decide);  // open: cast and unoccluded
      centreMask->Or(decide);
    } else {
      CastCentres(shooter, skip, &decide);
      centreMask = &decide;
    }
    if (read) {
      read->And(*out);
      read->AndNot(*centreMask);  // read, open, and occluded from the centre
      out->AndNot(*read);
    } else {
      out->And(*centreMask);
    }
  } else if (masks && out && options_.maskMethod == MaskMethod::kB) {
    if (centreMask)
      out->And(*centreMask);
    else
      CastCentres(shooter, skip, out);
  } else if (methodC) {
    SplitByRays(out, &hitPixels, passedPixels);
    if (centreMask) {
      // Cast only the pixels left whose centre ray is not known yet, into the cache.
      passedPixels.CopyFrom(hitPixels);
      passedPixels.AndNot(*known);
      known->Or(passedPixels);
      centreMask->AndNot(passedPixels);
      CastCentres(shooter, skip, &passedPixels);  // open: cast and unoccluded
      centreMask->Or(passedPixels);
      hitPixels.AndNot(*centreMask);  // left, and occluded from the centre
    } else {
      passedPixels.CopyFrom(hitPixels);
      CastCentres(shooter, skip, &hitPixels);  // closes the occluded ones
      passedPixels.AndNot(hitPixels);
      hitPixels.CopyFrom(passedPixels);
    }
    out->AndNot(hitPixels);
  }
}

// Casts the centre ray of every pixel open in *mask and closes those that
// hit, after closing those that lead to no neighbour (KeepExits).
void Environment::CastCentres(const Patch& shooter, Skip skip, MaskBits* mask) {
  PatchSampler sampler = MakePatchSampler(shooter);
  const glm::vec3 centre = MaskCentre(shooter);
  const CentreRays rays{centre + CentreLift(shooter.globalId) * sampler.frame.n, sampler.frame,
                        &exchange_.directions()};
  // From inside this box, a direction that cannot leave through a face
  // with a neighbour beyond it reaches no other environment: nobody
  // downstream reads its pixel, which closes without a ray.
  bool inside = true;
  for (int a = 0; a < 3; ++a) inside &= centre[a] >= box_.lo[a] && centre[a] <= box_.hi[a];
  if (inside && exchange_.exits().size() < 6)
    stats_.maskNoExit += KeepExits(exchange_.exits(), rays, mask);
  uint32_t cast = mask->CountOpen();
  stats_.maskRays += cast;
  // By patch or by ray, whichever costs less (the same bits either way):
  // a patch's view costs about four centre rays' walks (env_read.cpp's
  // costs, docs/design/masks.md).
  uint64_t work;
  if (4 * patches_.size() <= cast) {
    stats_.maskRaysByPatch += cast;
    RasterCentres(patches_, geom_, skip, rays, mask);
    work = 4 * patches_.size() * centreStepsPerRay_;
  } else {
    work = WalkCentres(grid_, skip, rays, mask);
    centreSteps_ += work;
  }
  stats_.castWork += work;
  // The round's work counts the casts that every --mask-cache makes: a
  // foreign shooter's, and a local shooter's first (later ones may come
  // from the cache).
  if (skip.patch == kNoPatch || shotCount_[skip.patch] == 1) centreWork_ += work;
}

// Local patch i's slot of the centre-mask cache: false when the cache has
// no slots. *centre: a pixel is open iff its centre ray from the shooter's
// centre hits nothing here. B: every pixel, cast on a miss. C, and B with
// --centre-rays read (PartCentres): the pixels set in *known (none after
// a miss), which Distribute adds to.
bool Environment::CachedCentre(uint32_t i, MaskBits* centre, MaskBits* known) {
  bool miss = false;
  if (!exchange_.cache().Find(i, centre, known, &miss)) return false;
  if (miss && !PartCentres()) CastCentres(patches_[i], Skip(i, twinOf(i)), centre);
  return true;
}

// Method R: regenerates the shot's rays from its key and traces those
// whose bit is set in `alive` (a foreign shot: the rays that entered this
// box). A ray that leaves the box for a neighbour is routed: its bit is
// set in routes[ExitFace], the packet for the neighbour across that face
// (the six route masks are cleared first); rays absorbed here or escaping
// the scene end.
void Environment::TraceAlive(const Patch& shooter, Skip skip, const double power[3],
                             uint64_t shotKey, uint32_t rays, bool foreign, const MaskBits& alive,
                             MaskBits* routes) {
  DCHECK(alive.bits() >= rays);
  // Only the shot's rays are read from the routes (Forward packs them alone).
  for (int f = 0; f < 6; ++f) routes[f].ClosePrefix(rays);
  ShotSetup shot(options_, shooter, power, shotKey, rays);
  ShotTally tally(shooter);
  uint64_t left = 0;
  // With a sky map: the rays that left less those that entered, each
  // counted by its share's ratio to power / rays (SkyShares).
  double flight[3] = {0, 0, 0}, ratio[3];
  auto trace = [&](uint32_t r, const float u[5]) {
    glm::vec3 local;
    Ray ray = MakeShotRay(shooter, shot.sampler, u, &local);
    ++tally.traced;
    if (shot.sky.map) {
      shot.sky.Of(ray.d, shot.share, ratio);
      if (foreign)
        for (int c = 0; c < 3; ++c) flight[c] -= ratio[c];
    }
    Hit hit;
    if (grid_.Intersect(ray, skip, &hit)) {
      Land(ray, hit, shot.share, &tally);
      return;
    }
    int face = ExitFace(ray);
    if (face < 0) {
      for (int c = 0; c < 3; ++c) tally.lost[c] += shot.share[c];
    } else {
      routes[face].Open(r);  // on to the neighbour across the face it leaves by
      ++left;
      if (shot.sky.map)
        for (int c = 0; c < 3; ++c) flight[c] += ratio[c];
    }
  };
  if (shot.points.randomAccess()) {
    // Sobol' points by index: the live rays only, word by word, in ray order
    // (only the words of the shot's rays: Unpack leaves the others alone).
    Span<uint64_t> words = alive.words();
    const size_t used = std::min<size_t>(words.size(), (size_t(rays) + 63) / 64);
    for (size_t w = 0; w < used; ++w)
      for (uint64_t bits = words[w]; bits != 0; bits &= bits - 1) {
        const uint32_t r = static_cast<uint32_t>(64 * w) + CountTrailingZeros(bits);
        float u[5];
        shot.points.Next(r, u);
        trace(r, u);
      }
  } else {
    // Sequential draws: every environment draws every ray, so that ray r is
    // the same ray everywhere.
    for (uint32_t r = 0; r < rays; ++r) {
      float u[5];
      shot.points.Next(r, u);
      if (alive.IsOpen(r)) trace(r, u);
    }
  }
  Book(tally);
  // A foreign environment gets only the rays that enter its box (every
  // environment before it on a ray's way routed it on), so every ray it
  // traces came in; the sum over environments is the power still on its way.
  const uint64_t entered = foreign ? tally.traced : 0;
  for (int c = 0; c < 3; ++c)
    ledger_.inFlight[c] +=
        shot.sky.map ? flight[c] * shot.sky.even[c]
                     : (static_cast<double>(left) - static_cast<double>(entered)) * shot.share[c];
}

}  // namespace vismask
