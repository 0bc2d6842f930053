// ElementTree: the receivers under an environment's patches, a quadtree per
// patch (element.h): the roots first (element i is patch i's), then a pool
// that splits draw four children at a time from, and with per-pixel direct
// light each element's indirect power. Carved from the environment's arena
// (Layout).
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/element.h"
#include "vismask/solve/patch.h"

namespace vismask {

class ElementTree {
 public:
  // Room for `numPatches` roots and options.perPatch pool elements a patch,
  // each with its exposed share, and with `indirect` three channels of
  // indirect power each (also from a measuring arena).
  void Layout(Arena& arena, uint32_t numPatches, const ElementOptions& options, bool indirect);
  // Every patch a single leaf of its area, the pool unused, no indirect power.
  void Reset(Span<const Patch> patches);

  Element& operator[](uint32_t e) { return elements_[e]; }
  const Element& operator[](uint32_t e) const { return elements_[e]; }
  size_t size() const { return elements_.size(); }
  Span<const Element> all() const { return elements_; }
  uint32_t used() const { return used_; }
  // Checkpoint: the elements used, beside the arena's bytes (which hold them).
  void SetUsed(uint32_t used) { used_ = used; }

  // The leaf of patch `patch` (a triangle or not) holding `st`, which is
  // left in the leaf's own parameters; with `path`, the children taken are
  // appended there (*depth of them, at most the element depth).
  uint32_t Descend(bool triangle, uint32_t patch, glm::vec2* st, uint8_t* path,
                   uint32_t* depth) const;
  // A point of patch `patch` (a triangle or not) drawn in proportion to the
  // power its leaves received (channels summed), uniform in the chosen
  // leaf's parameters, from three uniforms: its parameters (s, t). In a
  // quad leaf measured part buried (exposed share in (0, 1)), uniform in
  // its open cells instead: a ray from under a block would only meet the
  // block's inside. False, and nothing drawn, when the patch is a single
  // leaf not part buried, or received nothing.
  bool SampleByPower(bool triangle, uint32_t patch, const float u[3], glm::vec2* st) const;
  // A patch that is still one leaf knows more than its total: the power
  // each quarter of it received. Once it has kQuarterHits hits its rays
  // leave by that (QuarterOrigins), not uniformly: a patch larger than the
  // light's detail on it (the Cornell box's floor under the lamp, in the
  // --max-seconds 0.3 plan's 50-unit patches) then shoots from where its
  // light landed. Each quarter also counts kQuarterPrior hits' worth
  // spread evenly, so that one no ray happened to reach still sends some.
  static constexpr uint32_t kQuarterHits = 16;
  static constexpr double kQuarterPrior = 1.0;
  // Cells of the leaf's parameter square (kOpenSide x kOpenSide; a
  // triangle's four child triangles) with the share of the patch's rays
  // each sends, made once a shot.
  struct QuarterOrigins {
    bool triangle = false;
    int count = 0;       // cells (16) or child triangles (4)
    float cdf[16] = {};  // cumulative shares (kOpenSide^2 cells), the last 1
    // A point (s, t) of the patch from three uniforms.
    glm::vec2 Point(const float u[3]) const;
  };
  // False, and `out` untouched, unless patch `patch` is one leaf with
  // kQuarterHits hits or more.
  bool MakeQuarterOrigins(bool triangle, uint32_t patch, QuarterOrigins* out) const;
  // What MaybeSplit did.
  enum class Split { kNone, kSplit, kRefused };
  // Splits leaf `e` of patch `p` (reached from the root by the children
  // `path[0..depth)`) if its quarters differ beyond noise; kRefused when
  // the pool is used up.
  Split MaybeSplit(const Patch& p, uint32_t e, const uint8_t* path, uint32_t depth);

  // The share of leaf e's area that is not buried inside a closed solid
  // (the part of a floor under a block), as Environment::MeasureExposure
  // measured it; kUnmeasured for a leaf made since.
  static constexpr float kUnmeasured = -1.0f;
  float exposed(uint32_t e) const { return exposed_[e]; }
  // With the share, which of the kOpenSide x kOpenSide cells of the leaf's
  // parameter square are open (bit a * kOpenSide + b for the cell at
  // (a, b) along its first and last edges; a triangle's folded as the
  // measure folds them): SampleByPower's origins avoid the buried ones.
  static constexpr int kOpenSide = 4;
  void SetExposed(uint32_t e, float share, uint16_t open) {
    exposed_[e] = share;
    open_[e] = open;
  }
  uint16_t open(uint32_t e) const { return open_[e]; }
  // Leaf e's open cells when it is a quad measured part buried, else 0
  // (Patch::openCells of a root).
  uint16_t PartOpen(bool triangle, uint32_t e) const {
    return PartBuried(triangle, e) ? open_[e] : 0;
  }
  // (ua, ub) uniform in a unit square moved into its open cells `open`
  // (nonzero): ua picks one, in cell order, and is stretched back; kept
  // kMargin inside the square (PatchSampler::Point's margin).
  static constexpr float kMargin = 1e-5f;
  static void OpenCellsPoint(uint16_t open, float* ua, float* ub);
  // What spreads leaf e's received power over its exposed part: 1 / its
  // exposed share, 1 until measured or where wholly buried (the leaf then
  // weighs nothing in its vertices, and any value will do).
  double OverExposed(uint32_t e) const {
    const double share = exposed_[e];
    return share > 0.0 ? 1.0 / share : 1.0;
  }

  // Per-pixel direct light: leaf e's indirect power (W, channel c), added
  // to; and its indirect radiosity (0 without).
  bool hasIndirect() const { return !indirect_.empty(); }
  void AddIndirect(uint32_t e, int c, double power) { indirect_[3 * size_t(e) + c] += power; }
  glm::dvec3 Indirect(uint32_t e) const {
    if (indirect_.empty()) return glm::dvec3(0.0);
    return glm::dvec3(indirect_[3 * e], indirect_[3 * e + 1], indirect_[3 * e + 2]) /
           static_cast<double>(elements_[e].area);
  }
  // ... and of a hit's indirect power `power` (W per channel) on leaf e, in
  // its quarter q: the quarters' sums and the sum of the hits' squared
  // powers (channels summed) since the leaf was made, for CornerShift.
  void AddIndirectHit(uint32_t e, uint32_t q, const double power[3]) {
    float* s = &indirectQuarter_[12 * size_t(e) + 3 * q];
    for (int c = 0; c < 3; ++c) s[c] += static_cast<float>(power[c]);
    const double sum = power[0] + power[1] + power[2];
    indirectSquares_[e] += sum * sum;
  }
  // The display's shift of leaf e's indirect radiosity towards its quarter
  // q (the one at the corner being drawn), from the indirect power its
  // quarters received: the quarter's density minus the leaf's, times the
  // share of the quarters' spread that is not noise, alpha = 1 - kCornerDof
  // / chi2 (0 below kCornerDof; chi2 of the quarters against their areas
  // with the hits' squared powers as variance, as MaybeSplit's). A leaf
  // then shows its corners as a split would, as far as its rays can tell.
  // Leaf e of patch p is reached from the root by path[0..depth); *alpha
  // gets alpha.
  static constexpr double kCornerDof = 4.0;
  glm::dvec3 CornerShift(const Patch& p, uint32_t e, const uint8_t* path, uint32_t depth,
                         uint32_t q, double* alpha) const;

 private:
  double SubtreePower(uint32_t e) const;
  // The areas of the quarters of leaf e of patch p (MaybeSplit's path).
  void QuarterAreas(const Patch& p, const uint8_t* path, uint32_t depth, double out[4]) const;
  // A quad leaf measured part buried: some of its cells open, not all.
  bool PartBuried(bool triangle, uint32_t e) const {
    return !triangle && exposed_[e] > 0.0f && exposed_[e] < 1.0f && open_[e] != 0;
  }
  ElementOptions options_;
  Span<Element> elements_;
  Span<double> indirect_;
  Span<float> indirectQuarter_;   // with indirect_: 4 quarters x 3 channels an element
  Span<double> indirectSquares_;  // with indirect_: one an element
  Span<float> exposed_;
  Span<uint16_t> open_;
  uint32_t used_ = 0;
};

}  // namespace vismask
