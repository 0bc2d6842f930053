// Environment, its rays: a shot's form-factor rays traced through this
// environment's grid (Distribute: radiosity received, Method A/B/C masks
// marked; TraceAlive: Method R's rays in flight), and where a ray leaves the
// environment's box. The rest of Environment is in environment.cpp (init),
// env_receive.cpp (receiving, elements, display) and env_queue.cpp (shots
// and the queue).
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/core/fminmax.h"
#include "vismask/core/os.h"
#include "vismask/solve/centre_raster.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/rng.h"
#include "vismask/solve/sampling.h"
#include "vismask/solve/sobol.h"

namespace vismask {

namespace {

// The entry and exit parameters of `ray` through `box` (slab test).
bool Slabs(const Ray& ray, const Bounds& box, float* t0, float* t1) {
  float lo = -std::numeric_limits<float>::infinity(), hi = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (ray.d[a] == 0.0f) {
      if (ray.o[a] < box.lo[a] || ray.o[a] > box.hi[a]) return false;
      continue;
    }
    float inv = 1.0f / ray.d[a];
    float ta = (box.lo[a] - ray.o[a]) * inv, tb = (box.hi[a] - ray.o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    lo = FMax(lo, ta);
    hi = FMin(hi, tb);
  }
  *t0 = lo;
  *t1 = hi;
  return hi >= lo && hi > 0.0f;
}

// The five uniforms of ray r of a shot, (point: triangle, u, v; direction:
// u, v): scrambled Sobol' point r (direction in the two best-stratified
// dimensions), or with `sobol` off the next five PCG32 draws of the shot's
// stream, in which case rays must be taken in order.
class RayPoints {
 public:
  RayPoints(bool sobol, uint64_t stream)
      : sobol_(sobol), qmc_(Mix64(stream ^ 0xd1b54a32d192ed03ull)), rng_(ShotRng(stream)) {}
  // Ray r; with Sobol', `sequential` promises r is the previous call's + 1
  // (starting at 0), which walks the points one XOR at a time; otherwise
  // the point is reached from the last one drawn (ShotSampler::Seek).
  void Next(uint32_t r, float u[5], bool sequential = false) {
    if (!sobol_) {
      for (int k = 0; k < 5; ++k) u[k] = rng_.NextFloat();
      return;
    }
    float p[kSobolDims];
    if (sequential)
      qmc_.Next(p);
    else
      qmc_.Seek(r, p);
    u[0] = p[4];
    u[1] = p[2];
    u[2] = p[3];
    u[3] = p[0];
    u[4] = p[1];
  }
  bool randomAccess() const { return sobol_; }

 private:
  bool sobol_;
  ShotSampler qmc_;
  Rng rng_;
};

// Ray r of a shot from its five uniforms (RayPoints): its origin on the
// shooter lifted `lift` off the plane, its direction cosine-distributed about
// the normal (*local: in the shooter's frame). Every hit from t = 0 counts
// (the shooter and its twin are skipped): a ray from near a corner hits the
// wall beside it however close. A tMin > 0 instead let such rays through the
// wall and out of a closed box, a bias of ~4e-6 of the shot power a bounce,
// which rho = 0.999 amplifies to -0.4% (docs/STABILITY.md).
Ray ShotRay(const PatchSampler& sampler, const float u[5], float lift, glm::vec3* local) {
  *local = CosineDirection(u[3], u[4]);
  Ray ray;
  ray.o = sampler.Point(u[0], u[1], u[2]) + lift * sampler.frame.n;
  ray.d = sampler.frame.ToWorld(*local);
  ray.tMin = 0.0f;
  ray.tMax = std::numeric_limits<float>::infinity();
  return ray;
}

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

// The pixel of the direction from the shooter's centre to where `ray`
// (local direction `local`) enters a foreign environment at t0: the
// centre's view of the same crossing, so off-centre rays are not judged by
// a parallel ray that crosses elsewhere.
uint32_t EntryPixel(const Ray& ray, float t0, const glm::vec3& centre, const Frame& frame,
                    const glm::vec3& local, const MaskDirections& dirs) {
  glm::vec3 q = ray.o + FMax(t0, 0.0f) * ray.d - centre;
  glm::vec3 l(glm::dot(q, frame.t), glm::dot(q, frame.b), glm::dot(q, frame.n));
  float len = glm::length(l);
  return dirs.Pixel(len > 0.0f && l.z > 0.0f ? l / len : local);
}

glm::vec3 CentreOf(const Patch& p) {
  glm::vec3 centre(0.0f);
  for (uint32_t k = 0; k < p.numCorners; ++k) centre += p.corner[k];
  return centre / static_cast<float>(p.numCorners);
}

}  // namespace

Ray Environment::MakeShotRay(const PatchSampler& sampler, uint32_t id, const float u[5],
                             glm::vec3* local) const {
  const OutsideKind kind = OutsideKindOf(id);
  if (kind == OutsideKind::kNone) return ShotRay(sampler, u, options_.rayEpsilon, local);
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

// auto's costs, in centre rays cast (a centre ray's walk: about 1 200 to
// 1 600 instructions, callgrind, the Cornell box in 2 environments at the
// defaults and at R = 100, 4 096 rays). Regenerating a ray downstream (its
// sample, ray, box test and entry pixel) costs about half of one (640 to
// 760); a read pixel takes about half a centre ray a ray of the shot (some
// rays share pixels, some pixels are known or closed upstream); about 0.4
// of a mask's pixels take a centre ray where every open one is cast
// (KeepExits and the closing upstream pass over the rest); and casting a
// mask patch by patch costs about four centre rays a patch (CastCentres).
// The source's own cast counts in full, though a local shooter's mask is
// kept for its later shots: which shots read must not depend on the cache.
constexpr double kRegenCost = 0.5;
constexpr double kReadCast = 0.5;
constexpr double kCastShare = 0.4;
constexpr double kPatchCast = 4.0;
constexpr int kReadEnvs = 8;

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

bool Environment::ReadsOnly(uint32_t rays) const {
  if (options_.maskMethod != MaskMethod::kB || numNeighbours_ == 0) return false;
  if (options_.centreRays != CentreChoice::kAuto) return options_.centreRays == CentreChoice::kRead;
  return rays * readPerRay_ < allCost_;
}

template <typename Visit>
void Environment::ForEachEntryPixel(const PacketHeader& h, int env, const PatchSampler& sampler,
                                    const glm::vec3& centre, Visit visit) const {
  const Bounds box = envGrid_.EnvBox(env);
  RayPoints points(options_.sobol, ForeignStream(h.shotKey, static_cast<uint32_t>(env)));
  for (uint32_t r = 0; r < h.rays; ++r) {
    float u[5];
    points.Next(r, u, true);
    glm::vec3 local;
    Ray ray = MakeShotRay(sampler, h.shooterId, u, &local);
    float t0, t1;
    if (!Slabs(ray, box, &t0, &t1)) continue;
    visit(EntryPixel(ray, t0, centre, sampler.frame, local, maskDirections_));
  }
}

void Environment::ReadPixels(const PacketHeader& h, MaskBits* read) {
  read->SetAllClosed();
  const Patch shooter = PatchFromHeader(h);  // as the receivers make it
  const PatchSampler sampler = MakePatchSampler(shooter);
  const glm::vec3 centre = CentreOf(shooter);
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
    ForEachEntryPixel(h, e, sampler, centre, [read](uint32_t pixel) { read->Open(pixel); });
  }
}

double Environment::ReadShare(const PacketHeader& h, const MaskBits& mask, int to) {
  const Patch shooter = PatchFromHeader(h);
  const PatchSampler sampler = MakePatchSampler(shooter);
  stats_.readRays += h.rays;
  uint32_t open = 0;
  ForEachEntryPixel(h, to, sampler, CentreOf(shooter),
                    [&](uint32_t pixel) { open += mask.IsOpen(pixel); });
  return h.rays > 0 ? static_cast<double>(open) / h.rays : 0.0;
}

void Environment::Land(const Ray& ray, const Hit& hit, const double share[3], ShotTally* tally) {
  ++tally->hits;
  if (!hit.front) {
    for (int c = 0; c < 3; ++c) tally->backHit[c] += share[c];
    return;
  }
  Receive(hit.patch, share, ray.o + hit.t * ray.d);
}

void Environment::Book(const ShotTally& tally) {
  for (int c = 0; c < 3; ++c) {
    ledger_.escaped[c] += tally.lost[c];
    ledger_.absorbed[c] += tally.backHit[c];
    if (tally.outside) ledger_.outsideLost[c] += tally.lost[c] + tally.backHit[c];
  }
  stats_.rays += tally.traced;
  stats_.hits += tally.hits;
}

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

void Environment::Distribute(const Patch& shooter, Skip skip, const double power[3],
                             uint64_t stream, uint32_t rays, const MaskBits* in, MaskBits* out,
                             MaskBits* centreMask, MaskBits* known, MaskBits* read) {
  const bool masks = shape_.res > 0;
  const bool foreign = in != nullptr || skip.patch == kNoPatch;
  // Method C: which open pixels the rays hit in, and which they passed.
  const bool methodC = masks && out && options_.maskMethod == MaskMethod::kC;
  // A local ray's pixel matters to the methods that mark pixels by rays: B's
  // mask comes from the centre rays alone.
  const bool marks = masks && out && options_.maskMethod != MaskMethod::kB;
  MaskBits hitPixels, passedPixels;
  if (methodC) {
    hitPixels = ScratchMask(2);
    passedPixels = ScratchMask(3);
    hitPixels.SetAllClosed();
    passedPixels.SetAllClosed();
  }
  PatchSampler sampler = MakePatchSampler(shooter);
  RayPoints points(options_.sobol, stream);
  double share[3];
  for (int c = 0; c < 3; ++c) share[c] = power[c] / rays;
  const SkyShares sky = SkySharesOf(options_.outside, options_.sobol, sampler.frame,
                                    shooter.globalId, stream, rays, power);
  ShotTally tally;
  tally.outside = OutsideKindOf(shooter.globalId) != OutsideKind::kNone;
  glm::vec3 centre(0.0f);
  for (uint32_t k = 0; k < shooter.numCorners; ++k) centre += shooter.corner[k];
  centre /= static_cast<float>(shooter.numCorners);
  for (uint32_t r = 0; r < rays; ++r) {
    float u[5];
    points.Next(r, u, true);
    glm::vec3 local;
    Ray ray = MakeShotRay(sampler, shooter.globalId, u, &local);
    double ratio[3];
    if (sky.map) sky.Of(ray.d, share, ratio);
    uint32_t pixel = 0;
    if (foreign) {
      float t0, t1;
      if (!Slabs(ray, box_, &t0, &t1)) continue;  // never passes through here
      if (masks) {
        pixel = EntryPixel(ray, t0, centre, sampler.frame, local, maskDirections_);
        if (in && !in->IsOpen(pixel)) continue;  // occluded upstream
      }
    } else if (marks) {
      pixel = maskDirections_.CosinePixel(u[4], local);
    }
    ++tally.traced;
    Hit hit;
    if (!grid_.Intersect(ray, skip, &hit)) {
      if (methodC) passedPixels.Open(pixel);
      if (LeavesScene(ray))
        for (int c = 0; c < 3; ++c) tally.lost[c] += share[c];
      continue;
    }
    if (masks && out && options_.maskMethod == MaskMethod::kA) out->Close(pixel);
    if (methodC) hitPixels.Open(pixel);
    Land(ray, hit, share, &tally);
  }
  Book(tally);

  // Method B: the mask from the centre alone, one ray through each pixel
  // still open upstream (the paper's B). Mixing in A's marks would close
  // every pixel where any off-centre ray hit, losing the rays of that pixel
  // that pass on: about 14% of the power of the closed box in 2x2x2.
  // Method C: a pixel whose rays all hit closes, one whose rays all passed
  // stays open; only pixels with both, or with no ray, take the centre ray.
  // B deciding only the open pixels some ray downstream will read (*read,
  // ReadsOnly; the others stay as they are), or every open pixel with a
  // cache of known pixels (PartCentres): it casts only the pixels whose
  // centre ray is not known yet, into the cache. Its bits are CastCentres'
  // whichever pixels a shot decides, so a pixel means the same to every
  // shot that reads it from the cache.
  if (masks && out && options_.maskMethod == MaskMethod::kB && (read || known)) {
    MaskBits decide = ScratchMask(3);
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
    // An open pixel whose rays only hit closes; hitPixels becomes the
    // pixels left to the centre ray: open here, and with both kinds of ray
    // or none. Word by word (bits past the last pixel are 0 in all three).
    Span<uint64_t> o = out->words(), h = hitPixels.words(), q = passedPixels.words();
    for (size_t w = 0; w < o.size(); ++w) {
      uint64_t open = o[w], hit = h[w], passed = q[w];
      o[w] = open & ~(hit & ~passed);
      h[w] = open & ~(hit ^ passed);
    }
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

void Environment::CastCentres(const Patch& shooter, Skip skip, MaskBits* mask) {
  PatchSampler sampler = MakePatchSampler(shooter);
  glm::vec3 centre(0.0f);
  for (uint32_t k = 0; k < shooter.numCorners; ++k) centre += shooter.corner[k];
  centre /= static_cast<float>(shooter.numCorners);
  const CentreRays rays{centre + CentreLift(shooter.globalId) * sampler.frame.n, sampler.frame,
                        &maskDirections_};
  // From inside this box, a direction that cannot leave through a face
  // with a neighbour beyond it reaches no other environment: nobody
  // downstream reads its pixel, which closes without a ray.
  bool inside = true;
  for (int a = 0; a < 3; ++a) inside &= centre[a] >= box_.lo[a] && centre[a] <= box_.hi[a];
  if (inside && numExits_ < 6)
    stats_.maskNoExit += KeepExits(Span<const Patch>(exits_, numExits_), rays, mask);
  uint32_t cast = mask->CountOpen();
  stats_.maskRays += cast;
  // By patch or by ray, whichever costs less (the same bits either way):
  // a patch's view costs about four centre rays' walks (measured with
  // callgrind on the experiments' set-up: even at R = 33, 368 patches and
  // about 1 500 open pixels).
  uint64_t work;
  if (4 * patches_.size() <= cast) {
    stats_.maskRaysByPatch += cast;
    RasterCentres(patches_, geom_, skip, rays, mask);
    work = 4 * patches_.size() * centreStepsPerRay_;
  } else {
    work = WalkCentres(grid_, skip, rays, mask);
    centreSteps_ += work;
  }
  // The round's work counts the casts that every --mask-cache makes: a
  // foreign shooter's, and a local shooter's first (later ones may come
  // from the cache).
  if (skip.patch == kNoPatch || shotCount_[skip.patch] == 1) centreWork_ += work;
}

bool Environment::CachedCentre(uint32_t i, MaskBits* centre, MaskBits* known) {
  if (cacheTag_.empty()) return false;
  const bool methodC = PartCentres();
  size_t slot = i % cacheTag_.size(), w = shape_.words(), per = methodC ? 2 : 1;
  *centre = MaskBits(cacheWords_.subspan(slot * per * w, w), shape_);
  if (methodC) *known = MaskBits(cacheWords_.subspan((slot * per + 1) * w, w), shape_);
  if (cacheTag_[slot] != i) {
    centre->SetAllOpen();
    if (methodC)
      known->SetAllClosed();
    else
      CastCentres(patches_[i], Skip(i, twinOf(i)), centre);
    cacheTag_[slot] = i;
  }
  return true;
}

void Environment::TraceAlive(const Patch& shooter, Skip skip, const double power[3],
                             uint64_t shotKey, uint32_t rays, bool foreign, const MaskBits& alive,
                             MaskBits* routes) {
  DCHECK(alive.bits() >= rays);
  // Only the shot's rays are read from the routes (Forward packs them alone).
  for (int f = 0; f < 6; ++f) routes[f].ClosePrefix(rays);
  PatchSampler sampler = MakePatchSampler(shooter);
  RayPoints points(options_.sobol, shotKey);
  double share[3];
  for (int c = 0; c < 3; ++c) share[c] = power[c] / rays;
  const SkyShares sky = SkySharesOf(options_.outside, options_.sobol, sampler.frame,
                                    shooter.globalId, shotKey, rays, power);
  ShotTally tally;
  tally.outside = OutsideKindOf(shooter.globalId) != OutsideKind::kNone;
  uint64_t left = 0;
  // With a sky map: the rays that left less those that entered, each
  // counted by its share's ratio to power / rays (SkyShares).
  double flight[3] = {0, 0, 0}, ratio[3];
  auto trace = [&](uint32_t r, const float u[5]) {
    glm::vec3 local;
    Ray ray = MakeShotRay(sampler, shooter.globalId, u, &local);
    ++tally.traced;
    if (sky.map) {
      sky.Of(ray.d, share, ratio);
      if (foreign)
        for (int c = 0; c < 3; ++c) flight[c] -= ratio[c];
    }
    Hit hit;
    if (grid_.Intersect(ray, skip, &hit)) {
      Land(ray, hit, share, &tally);
      return;
    }
    int face = ExitFace(ray);
    if (face < 0) {
      for (int c = 0; c < 3; ++c) tally.lost[c] += share[c];
    } else {
      routes[face].Open(r);  // on to the neighbour across the face it leaves by
      ++left;
      if (sky.map)
        for (int c = 0; c < 3; ++c) flight[c] += ratio[c];
    }
  };
  if (points.randomAccess()) {
    // Sobol' points by index: the live rays only, word by word, in ray order
    // (only the words of the shot's rays: Unpack leaves the others alone).
    Span<uint64_t> words = alive.words();
    const size_t used = std::min<size_t>(words.size(), (size_t(rays) + 63) / 64);
    for (size_t w = 0; w < used; ++w)
      for (uint64_t bits = words[w]; bits != 0; bits &= bits - 1) {
        const uint32_t r = static_cast<uint32_t>(64 * w) + CountTrailingZeros(bits);
        float u[5];
        points.Next(r, u);
        trace(r, u);
      }
  } else {
    // Sequential draws: every environment draws every ray, so that ray r is
    // the same ray everywhere.
    for (uint32_t r = 0; r < rays; ++r) {
      float u[5];
      points.Next(r, u);
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
        sky.map ? flight[c] * sky.even[c]
                : (static_cast<double>(left) - static_cast<double>(entered)) * share[c];
}

double Environment::TimeRays(uint32_t rays) const {
  if (patches_.empty()) return 0.0;
  Rng rng(0x5eed, 41);
  const uint32_t n = static_cast<uint32_t>(patches_.size());
  uint64_t hits = 0;
  double start = os::Seconds();
  for (uint32_t k = 0; k < rays; ++k) {
    uint32_t i = static_cast<uint32_t>((uint64_t(k) * 2654435761u) % n);
    PatchSampler sampler = MakePatchSampler(patches_[i]);
    float u[5];
    for (float& x : u) x = rng.NextFloat();
    glm::vec3 local;
    Ray ray = ShotRay(sampler, u, options_.rayEpsilon, &local);
    Hit hit;
    hits += grid_.Intersect(ray, Skip(i, twinOf(i)), &hit) ? 1 : 0;
  }
  double seconds = os::Seconds() - start;
  return hits > rays ? 0.0 : seconds;  // (hits read, so the loop stays)
}

}  // namespace vismask
