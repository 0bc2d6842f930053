// Environment, what it receives: the radiosity a ray brings to a patch
// (Receive), the leaf of the element tree it lands in (element_tree.cpp
// splits them), its display radiosity (LeafAt, LeafRadiosity) and the
// emission not yet shot that the pixels gather (EmissionUnshot), then the
// display radiosity at mesh vertices (ComputeVertexRadiosity). The rest of
// Environment is in environment.cpp (layout and init), trace.cpp (rays) and
// env_queue.cpp (shots and the queue).
#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "vismask/solve/environment.h"

namespace vismask {

// Patch j receives `share` (W per channel) at point `x`.
void Environment::Receive(uint32_t j, const double share[3], const glm::vec3& x) {
  const Patch& p = patches_[j];
  PatchEnergy& e = energy_[j];
  double invArea = 1.0 / p.area;
  // The leaf element the ray landed in, and the quarter of it.
  glm::vec2 st = PatchParam(p, x);
  uint32_t depth = 0;
  uint8_t path[32];
  uint32_t leaf = elements_.Descend(p.numCorners == 3, j, &st, path, &depth);
  Element& el = elements_[leaf];
  uint32_t quarter = ChildOf(p.numCorners == 3, &st);
  double hitPower = 0.0, indirect[3];
  for (int c = 0; c < 3; ++c) {
    double reflected = share[c] * p.kd[c];
    hitPower += reflected;
    el.received[c] += reflected;
    el.quarter[quarter][c] += reflected;
    e.b[c] += reflected * invArea;
    e.var[c] += (reflected * invArea) * (reflected * invArea);  // one ray's term
    e.unshot[c] += reflected;
    indirect[c] = reflected * (1.0 - direct_.shotDirect(c));
    if (elements_.hasIndirect()) elements_.AddIndirect(leaf, c, indirect[c]);
    ledger_.unshot[c] += reflected;
    ledger_.radiosity[c] += reflected;
    ledger_.absorbed[c] += share[c] - reflected;
  }
  el.squares += hitPower * hitPower;
  if (elements_.hasIndirect()) elements_.AddIndirectHit(leaf, quarter, indirect);
  tree_.Increase(j, UnshotKey(e));
  // Whether to split is asked at 64, 128, 256, ... hits.
  uint32_t hits = ++el.hits;
  if (hits >= options_.elements.minHits && (hits & (hits - 1)) == 0 &&
      el.depth < options_.elements.maxDepth && options_.elements.perPatch > 0) {
    const ElementTree::Split split = elements_.MaybeSplit(p, leaf, path, depth);
    if (split == ElementTree::Split::kSplit) MeasurePatchExposure(j, kFineExposure);
    stats_.splits += split == ElementTree::Split::kSplit;
    stats_.refusedSplits += split == ElementTree::Split::kRefused;
  }
}

// The leaf of patch `patch` at `st`.
uint32_t Environment::LeafAt(uint32_t patch, glm::vec2 st) const {
  return elements_.Descend(patches_[patch].numCorners == 3, patch, &st, nullptr, nullptr);
}

// A leaf's display radiosity: emission + received / area + kd * ambient,
// the reflected part scaled by PatchTexture::scale when textured; only the
// indirect part when DirectBook::ShowsIndirect.
glm::vec3 Environment::LeafRadiosity(uint32_t patch, uint32_t e, const double ambient[3]) const {
  const Patch& p = patches_[patch];
  const Element& el = elements_[e];
  glm::vec3 b;
  const PatchTexture* t = patchTexture(patch);
  // What was received, spread over the exposed part.
  const double over = elements_.OverExposed(e);
  // Per-pixel direct light: the patch's indirect radiosity, every leaf alike
  // (the direct part, which has the detail, is gathered per pixel).
  if (direct_.ShowsIndirect(patch)) {
    glm::dvec3 ind = elements_.Indirect(e) * over;
    for (int c = 0; c < 3; ++c)
      b[c] = static_cast<float>(static_cast<double>(p.ke[c]) +
                                (ind[c] + p.kd[c] * ambient[c]) * (t ? t->scale[c] : 1.0f));
    return b;
  }
  if (t) {
    // Reflected light as the material's mean reflectance would give it
    // (scale = kd_mat / kd): the display multiplies the texture back in.
    for (int c = 0; c < 3; ++c)
      b[c] = static_cast<float>(static_cast<double>(p.ke[c]) +
                                (el.received[c] / el.area * over + p.kd[c] * ambient[c]) *
                                    t->scale[c]);
    return b;
  }
  for (int c = 0; c < 3; ++c)
    b[c] = static_cast<float>(static_cast<double>(p.ke[c]) + el.received[c] / el.area * over +
                              p.kd[c] * ambient[c]);
  return b;
}

// What LeafRadiosity leaves out when it shows the indirect part: the
// leaf's received radiosity that came straight from this environment's
// emitters (the pixels gather it), scaled as LeafRadiosity scales.
glm::vec3 Environment::LeafSolvedDirect(uint32_t patch, uint32_t e) const {
  // All it received is indirect unless its pixels gather some emitters.
  if (direct_.light().empty() && !direct_.gathersForeign()) return glm::vec3(0.0f);
  const Element& el = elements_[e];
  const glm::dvec3 ind = elements_.Indirect(e);
  const PatchTexture* t = patchTexture(patch);
  const double over = elements_.OverExposed(e);
  glm::vec3 d;
  for (int c = 0; c < 3; ++c)
    d[c] =
        static_cast<float>((el.received[c] / el.area - ind[c]) * over * (t ? t->scale[c] : 1.0f));
  return d;
}

void Environment::ComputeVertexRadiosity(const double ambient[3]) {
  MeasureExposure();
  lattice_.Clear();
  filterSteps_ = direct_.showIndirect() ? IndirectFilterSteps() : 0;
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    const Patch& p = patches_[i];
    glm::vec2 corners[4];
    RootCorners(p.numCorners == 3, corners);
    // Each distinct corner once (triangles repeat their last vertex), with
    // the leaf element that holds it.
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      // A point just inside the corner, so the leaf is the corner's own.
      glm::vec2 centre = p.numCorners == 3 ? glm::vec2(1.0f / 3.0f) : glm::vec2(0.5f);
      glm::vec2 st = corners[k] + 1e-4f * (centre - corners[k]);
      uint8_t path[32];
      uint32_t depth = 0;
      const uint32_t leaf = elements_.Descend(p.numCorners == 3, i, &st, path, &depth);
      const float w = ExposedArea(leaf);
      glm::vec3 b = LeafRadiosity(i, leaf, ambient);
      float edge = std::sqrt(elements_[leaf].area / p.area);
      // The indirect part at the corner as the leaf's quarter there tells
      // it (ElementTree::CornerShift), where the leaf is wholly exposed and
      // the image is not smoothed (smoothing means too few hits a patch:
      // the shift would add noise where the smoothing takes it out); the
      // outline's extrapolation then starts from between the leaf's centre
      // and its quarter's.
      if (filterSteps_ == 0 && direct_.ShowsIndirect(i) && elements_.exposed(leaf) == 1.0f) {
        static constexpr uint32_t kQuadQuarter[4] = {0, 1, 3, 2};  // at corners 0..3
        double alpha = 0.0;
        const glm::dvec3 shift = elements_.CornerShift(
            p, leaf, path, depth, p.numCorners == 3 ? k : kQuadQuarter[k], &alpha);
        const PatchTexture* t = patchTexture(i);
        for (int c = 0; c < 3; ++c) b[c] += static_cast<float>(shift[c] * (t ? t->scale[c] : 1.0f));
        edge *= static_cast<float>(1.0 - 0.5 * alpha);
      }
      lattice_.Add(p.vertex[k], w, b, edge);
      if (lattice_.keepsSolvedDirect() && direct_.ShowsIndirect(i))
        lattice_.AddSolvedDirect(p.vertex[k], w, LeafSolvedDirect(i, leaf));
    }
  }
  lattice_.Finish(patches_, static_cast<int>(filterSteps_));
}

namespace {
// The automatic smoothing's steps times the hits a patch received, at the
// automatic patch size (IndirectFilterSteps).
constexpr double kFilterHits = 600.0;
}  // namespace

// The indirect part's smoothing: what --indirect-filter gives, else from
// the hits a patch received, h, and the patch size L against the automatic
// one, L0: 600 (L0 / L)^2 / h steps, rounded, within [0, 16]. The noise a
// step takes out falls as h grows; the bias it adds (the indirect part's
// curvature over a lattice step) grows as L^2. Fitted on the Cornell box
// against its path-traced reference without the silhouettes (stop 65): at
// L0, the best steps came to 11, 10, 8, 5, 3, 2 and 1-2 at h = 56, 61, 75,
// 111, 193, 353 and 462 (about 600 / h), and at L = 2.5 L0 none helped
// at h = 194 (600 / 6.25 / 194 = 0.5).
uint32_t Environment::IndirectFilterSteps() const {
  if (options_.indirectFilter >= 0) return static_cast<uint32_t>(options_.indirectFilter);
  const double h =
      static_cast<double>(stats_.hits) / static_cast<double>(std::max<size_t>(patches_.size(), 1));
  const double steps =
      std::floor(kFilterHits * options_.filterPatchScale / std::max(h, 1e-3) + 0.5);
  return static_cast<uint32_t>(std::min(std::max(steps, 0.0), 16.0));
}

void Environment::EmissionUnshot(double out[3]) const {
  direct_.EmissionUnshot(out);
  AddOutsideEmission(out);
}

void Environment::EmissionLeft(double out[3]) const {
  direct_.EmissionLeft(out);
  AddOutsideEmission(out);
}

void Environment::AddOutsideEmission(double out[3]) const {
  for (uint32_t k = 0; k < outside_.size(); ++k)
    if (direct_.Gathers(OutsideKindOf(outside_[k].shooter.patch.globalId)))
      for (int c = 0; c < 3; ++c) out[c] += outside_[k].unshot[c];
}

}  // namespace vismask
