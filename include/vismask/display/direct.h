// Direct light gathered per pixel (the two-pass method: Wallace, Cohen and
// Greenberg 1987). The solve keeps, per leaf element, the part of its
// received radiosity that did not come straight from an emitter's own
// emission (its indirect radiosity, Environment::Indirect); the display
// interpolates that as it did the whole, and adds, at each point the raster
// shades, the irradiance from the emitters gathered there (this file).
//
// The estimate at a point x is, per source (an emitting polygon, or the
// sun), E0(x) * V(x): E0 the unoccluded irradiance, exact (Lambert's
// formula for a polygon of uniform exitance: E = Ke/(2 pi) * sum over its
// edges of the angle they subtend times the cosine of their plane with the
// normal), and V the visible share, estimated with shadow rays to sample
// points on the sources weighted by what each would bring (a ratio
// estimator): each source's own samples give its V, so a source hidden
// from x counts as nothing and one in full view as its E0, whatever share
// of the samples each drew; a source drawing less than one sample in
// expectation counts by what its samples bring over all drawn. Where every
// sample agrees (fully lit, or umbra) V is 1 or 0 exactly for the whole,
// so the noise is only in penumbrae. The shadow rays are
// adaptive: one to each corner of the emitters' outlines and the first
// kFirstDirectSamples; the rest of the N only where those disagree. (A
// straight silhouette edge across a convex emitter leaves a corner on each
// side, so a penumbra of such an edge always disagrees at the corners; an
// occluder seen wholly inside an emitter's outline, missed by the corners
// and by all the first samples, is missed: the bias of this shortcut.)
//
// The emitters are a list of area sources: today the environment's patches
// with Ke > 0, grouped by polygon (the patches of one polygon: for E0 only
// its outline edges count, the shared inner edges cancel). A sample point
// is chosen by a 2D point u: u.x picks a group in proportion to its own
// unoccluded irradiance at x (Unoccluded computes it group by group), then
// a patch of the group in proportion to its power (area times Ke, channels
// summed), each time stretched back to [0, 1) within the choice; the point
// is uniform over the patch (a quad as two triangles by area). So the
// samples go to the groups in the shares they bring at x: with many
// emitters, most of them far, faint or facing away from x, the samples are
// not spent on those. The sun (--sun) is a second kind of
// source: E0 its irradiance times the cosine at x, V from rays along
// directions uniform in its disc that must leave the scene (an unbounded
// occlusion test); the corners of its disc are kSunRimRays points on its
// rim. A sample picks the kind with u.x, the sun with the share
// of E0 it brings at x, and stretches u.x back to [0, 1) within the kind.
// The sky (--sky) stays in the solve (docs/design/direct-light.md).
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "vismask/accel/grid.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/outside.h"
#include "vismask/solve/patch.h"

namespace vismask {

class ForeignLight;

constexpr uint32_t kFirstDirectSamples = 4;
// The most outline corners GatherDirect sends a ray to (more: it samples
// every point fully).
constexpr uint32_t kMaxCornerRays = 16;
// The rays GatherDirect sends to the sun's rim (its disc's corners): a
// straight shadow edge across the disc leaves rim points on both sides.
constexpr uint32_t kSunRimRays = 8;
// The samples a piece covering `cover` of a pixel gathers there, of the N
// (`samples`) a whole pixel gets: N x cover rounded up, at least
// kMinPartSamples (or N, if fewer). The piece's estimate is weighted by
// `cover` in the pixel, so its share of the samples keeps the pixel's
// error where the pieces splitting it (element edges across a penumbra)
// each gathering N would spend N per piece (docs/design/direct-light.md).
constexpr uint32_t kMinPartSamples = 8;
uint32_t PartSamples(uint32_t samples, float cover);

class DirectLight {
 public:
  // One emitter patch: sampled for V (in its group's order).
  struct Emitter {
    uint32_t patch;  // local index
    float cdfHi;     // the cumulative share of its group's power up to and including this one
    float split;     // a quad: the share of its area in triangle (0, 1, 2); a triangle: 1
    // Ke / pi over the pdf per unit area within the group:
    // Ke * (the group's weight) / (weight / area) / pi.
    glm::vec3 scale;
  };
  // One emitting polygon (its patches, coplanar, one Ke): E0 from its edges
  // that no other of its patches shares.
  struct Group {
    glm::vec3 normal;  // the patches' (unit)
    glm::vec3 point;   // one of its corners
    glm::vec3 ke;
    uint32_t firstEdge, numEdges;
    uint32_t firstPatch, numPatches;  // in emitters_
  };
  struct Edge {
    glm::vec3 a, b;  // in the winding of the patch it came from
  };
  struct Corner {
    glm::vec3 point;
    uint32_t group;
    uint32_t patch;  // an emitter patch with this corner (its transit masks)
  };
  struct Counts {
    uint32_t emitters = 0, groups = 0, edges = 0, corners = 0;
  };
  // One group at the point being gathered: its cumulative share of the area
  // emitters' unoccluded irradiance there (channels summed), its own part
  // of it (per channel), and its samples' weights, all and those that
  // reached it (the gather's sums).
  struct Tally {
    float cdf;
    glm::vec3 e0, seen, all;
  };

  // What `patches` need (init: uses the heap).
  static Counts Count(Span<const Patch> patches);
  // Carves the lists from `arena` (also a measuring one).
  void Layout(Arena& arena, const Counts& counts);
  // Fills them from `patches` (which must outlive this; init: uses the heap).
  void Build(Span<const Patch> patches);
  // The sun of `light` as a source (none when it has no --sun).
  void SetSun(const OutsideLight& light);
  bool empty() const { return emitters_.empty() && !hasSun_; }
  bool hasSun() const { return hasSun_; }

  // The unoccluded irradiance at x (unit normal n), per channel: the area
  // emitters' and the sun's. With `tally` (numGroups() entries), also each
  // area group's part and cumulative share of the area emitters' part
  // there (the last group that brings any at 1, all 0 when none does),
  // which Sample picks a group by; its sums are set to 0.
  glm::vec3 Unoccluded(const glm::vec3& x, const glm::vec3& n, Span<Tally> tally = {}) const;
  // The sun's part of it: its irradiance times the cosine between n and the
  // direction towards its centre (0 below the horizon).
  glm::vec3 UnoccludedSun(const glm::vec3& n) const;
  // One shadow sample from x toward the source point u picks: what it
  // would bring (*weight, per channel, over the pdf of its choice; 0 when
  // the point faces away or lies below x's horizon, or no group brings
  // any) and whether the ray reaches it (through `grid`, ends excluded by
  // `epsilon` scene units, receiver and `twin` skipped; *hint:
  // Grid::Occluded's, or null). `tally`: what Unoccluded at x gave.
  // `sunShare`: the share of the samples that go to the sun (u.x below
  // it), the rest to the area emitters; a sun ray must leave the scene.
  // *source (unless null): the group sampled, numGroups() for the sun.
  // Allocates nothing.
  bool Sample(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
              const glm::vec3& n, glm::vec2 u, Span<const Tally> tally, float epsilon,
              uint32_t* hint, glm::vec3* weight, float sunShare = 0.0f, uint32_t* source = nullptr,
              uint32_t viewer = kNoViewer) const;

  uint32_t numGroups() const { return static_cast<uint32_t>(groups_.size()); }
  // numGroups() tallies laid out with the lists, for the point being
  // gathered (the display gathers one point at a time).
  Span<Tally> tallies() const { return tallies_; }

  // The emitters' outline corners (each polygon's, where its outline turns), and whether the ray
  // from x (normal n) to corner k reaches it
  // (*usable false when the corner lies on or below x's horizon, or x
  // behind its polygon: the ray tells nothing).
  uint32_t numCorners() const { return static_cast<uint32_t>(corners_.size()); }
  bool CornerVisible(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                     const glm::vec3& n, uint32_t k, float epsilon, uint32_t* hint, bool* usable,
                     uint32_t viewer = kNoViewer) const;

  // Whether the ray from x (normal n) towards point k of kSunRimRays on the
  // sun's rim leaves the scene (*usable false when that direction lies on
  // or below x's horizon: the ray tells nothing).
  bool SunRimVisible(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                     const glm::vec3& n, uint32_t k, float epsilon, uint32_t* hint, bool* usable,
                     uint32_t viewer = kNoViewer) const;

  // Every environment's emitters (foreign_light.h): the patches Build was
  // given are all of them, and a shadow ray from a point of environment
  // `viewer` (Sample's, CornerVisible's) to another environment's emitter
  // must also pass `transit`'s masks. kNoViewer: the grid holds every
  // emitter (one environment's own light).
  static constexpr uint32_t kNoViewer = 0xffffffffu;
  void SetTransit(const ForeignLight* transit) { transit_ = transit; }

  // A point of emitter patch `p` from u in [0, 1)^2, uniform in area
  // (`split`: Emitter::split).
  static glm::vec3 PointOn(const Patch& p, float split, glm::vec2 u);

 private:
  Span<Emitter> emitters_;
  Span<Group> groups_;
  Span<Edge> edges_;
  Span<Corner> corners_;
  Span<Tally> tallies_;
  Span<const Patch> patches_;
  // The sun: its irradiance on a surface facing it, the unit direction
  // towards it and its angular diameter (degrees).
  bool hasSun_ = false;
  glm::vec3 sun_{0.0f}, sunToward_{0.0f, 0.0f, 1.0f};
  float sunDegrees_ = 0.0f;
  const ForeignLight* transit_ = nullptr;

  bool SampleArea(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                  const glm::vec3& n, glm::vec2 u, Span<const Tally> tally, float epsilon,
                  uint32_t* hint, glm::vec3* weight, uint32_t* source, uint32_t viewer) const;
  bool Passes(uint32_t patch, uint32_t viewer, const glm::vec3& x, const glm::vec3& n) const;
  bool SampleSun(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                 const glm::vec3& n, glm::vec2 u, float epsilon, uint32_t* hint, glm::vec3* weight,
                 uint32_t viewer) const;
  bool PassesSun(uint32_t viewer, const glm::vec3& x, const glm::vec3& n, const glm::vec3& d) const;
};

// The k-th sample of pixel `pixel` (row-major index) of the per-pixel
// gather: the light point (Halton bases 2 and 3, so every prefix is spread,
// rotated per pixel by a hash of the index: Cranley-Patterson) and the
// sub-pixel offset (bases 5 and 7, another rotation). From the pixel index
// alone, so every rank and transport draws the same.
glm::vec2 DirectLightSample(uint32_t pixel, uint32_t k);
glm::vec2 DirectPixelOffset(uint32_t pixel, uint32_t k);

// DirectLightSample(pixel, k) (kLight) or DirectPixelOffset(pixel, k)
// (kOffset) for one pixel and many k, the same floats: the pixel's
// rotations hashed once, and the radical inverses of the first kTabled k
// read from tables (filled once, by the same function).
class DirectPixelSequence {
 public:
  enum class Kind { kLight, kOffset };
  static constexpr uint32_t kTabled = 1024;
  DirectPixelSequence(uint32_t pixel, Kind kind);
  glm::vec2 operator()(uint32_t k) const;

 private:
  int row_;  // the first of its two bases among 2, 3, 5, 7
  uint64_t h_, h2_;
};

}  // namespace vismask
