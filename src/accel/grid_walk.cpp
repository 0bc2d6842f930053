#include "grid_walk.h"

// Grid::Intersect and Grid::Occluded: the walk (grid_walk.h) for the CPU at
// hand, and every patch tested for a ray the grid cannot walk
// (src/accel/grid.cpp plans and builds the grid).
namespace vismask {

template <bool kAnyHit>
bool Grid::TestAll(const Ray& ray, Skip skip, Hit* hit) const {
  const PatchGeom* geom = geom_.data();
  uint32_t n = static_cast<uint32_t>(geom_.size());
  Hit best;
  best.t = ray.tMax;
  for (uint32_t p = 0; p < n; ++p) {
    float t;
    bool front;
    if (p == skip.patch || p == skip.twin || !IntersectPatch(geom[p], ray, &t, &front)) continue;
    if (kAnyHit) {
      if (hit) hit->patch = p;
      return true;
    }
    // The nearest; of equal t, TieWins (patches rise with p).
    if (best.patch == kNoPatch || t < best.t ||
        (t == best.t && TieWins(p, front, best.patch, best.front)))
      best = Hit{p, t, front};
  }
  if (best.patch == kNoPatch) return false;
  *hit = best;
  return true;
}

VISMASK_GRID_WALKS(false)

// The walk for the top cells' reference width and the CPU's popcount.
template <bool kAnyHit>
inline bool Grid::WalkAny(const Ray& ray, Skip skip, Hit* hit) const {
  if (popcnt_)
    return plan_.topWide ? Walk<kAnyHit, true, true>(ray, skip, hit)
                         : Walk<kAnyHit, false, true>(ray, skip, hit);
  return plan_.topWide ? Walk<kAnyHit, true, false>(ray, skip, hit)
                       : Walk<kAnyHit, false, false>(ray, skip, hit);
}

bool Grid::Intersect(const Ray& ray, Skip skip, Hit* hit) const {
  return WalkAny<false>(ray, skip, hit);
}

bool Grid::Occluded(const Ray& ray, Skip skip) const {
  return WalkAny<true>(ray, skip, nullptr);
}

bool Grid::Occluded(const Ray& ray, Skip skip, uint32_t* hint) const {
  uint32_t h = *hint;
  float t;
  bool front;
  if (h != kNoPatch && h != skip.patch && h != skip.twin &&
      IntersectPatch(geom_[h], ray, &t, &front))
    return true;
  Hit hit;
  if (!WalkAny<true>(ray, skip, &hit)) return false;
  *hint = hit.patch;
  return true;
}

}  // namespace vismask
