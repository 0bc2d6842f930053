// DisplayLattice: its layout, its copy from the staged lattice, and the
// vertex radiosity's mean and outline extrapolation.
#include "vismask/solve/display_lattice.h"

#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace vismask {

void DisplayLattice::Layout(Arena& arena, const Staged& staged, bool smoothing) {
  const size_t n = staged.vertices.size();
  vertices_ = arena.Alloc<glm::vec3>(n);
  radiosity_ = arena.Alloc<glm::vec3>(n);
  weight_ = arena.Alloc<float>(n);
  cut_ = arena.Alloc<uint32_t>(staged.cut.size());
  isCut_ = arena.Alloc<uint8_t>(n);
  outline_ = arena.Alloc<uint8_t>(n);
  frac_ = arena.Alloc<float>(n);
  mark_ = arena.Alloc<uint8_t>(n);
  inward_ = arena.Alloc<glm::vec3>(n);
  interior_ = arena.Alloc<uint8_t>(smoothing ? n : 0);
  raw_ = arena.Alloc<glm::vec3>(smoothing ? 2 * n : 0);
  cutNormal_ = arena.Alloc<glm::vec3>(staged.cut.size());
  solvedDirect_ = arena.Alloc<glm::vec3>(smoothing && !staged.cut.empty() ? n : 0);
  smooth_ = arena.Alloc<SmoothVertex>(staged.smooth.size());
  smoothMatched_ = arena.Alloc<uint8_t>(staged.smooth.size());
  smoothEdges_ = arena.Alloc<uint8_t>(staged.smoothEdges.size());
  numCut_ = static_cast<uint32_t>(staged.cut.size());
  numShared_ = staged.numShared;
}

void DisplayLattice::Build(const Staged& staged, Span<const Patch> patches) {
  for (size_t v = 0; v < staged.vertices.size(); ++v) vertices_[v] = staged.vertices[v];
  for (size_t v = 0; v < isCut_.size(); ++v) isCut_[v] = 0;
  for (size_t k = 0; k < staged.cut.size(); ++k) {
    isCut_[staged.cut[k]] = 1;
    cut_[k] = staged.cut[k];
    cutNormal_[k] = staged.cutNormal[k];
  }
  // The outline vertices to extrapolate: touched by one or two quads (and
  // no triangle), not on a cut, and every touching quad's opposite corner an
  // interior vertex (four quads), else the outline is too ragged or narrow
  // to tell inward from along.
  std::vector<uint8_t> quads(outline_.size(), 0), inward(outline_.size(), 0);
  for (const Patch& p : patches)
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      uint8_t& q = quads[p.vertex[k]];
      q = p.numCorners == 4 && q != 0xff ? q + 1 : 0xff;
    }
  for (const Patch& p : patches)
    if (p.numCorners == 4)
      for (uint32_t k = 0; k < 4; ++k) inward[p.vertex[k]] += quads[p.vertex[(k + 2) % 4]] == 4;
  for (size_t v = 0; v < outline_.size(); ++v) {
    uint8_t q = quads[v];
    bool outline = q >= 1 && q <= 2 && !isCut_[v] && inward[v] == q;
    outline_[v] = outline ? q : 0;
  }
  if (!interior_.empty()) MarkInterior(staged, patches);
  for (size_t k = 0; k < staged.smooth.size(); ++k) smooth_[k] = staged.smooth[k];
  for (size_t i = 0; i < staged.smoothEdges.size(); ++i) smoothEdges_[i] = staged.smoothEdges[i];
}

// Interior vertices: the corners' angles around them add up to a full turn.
void DisplayLattice::MarkInterior(const Staged& staged, Span<const Patch> patches) {
  std::vector<double> angle(interior_.size(), 0.0);
  std::vector<uint32_t> ends(interior_.size(), 0);
  for (const Patch& p : patches)
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      const glm::vec3 &a = p.corner[k], &b = p.corner[(k + 1) % p.numCorners],
                      &c = p.corner[(k + p.numCorners - 1) % p.numCorners];
      glm::vec3 u = glm::normalize(b - a), w = glm::normalize(c - a);
      angle[p.vertex[k]] += std::acos(std::max(-1.0, std::min(1.0, double(glm::dot(u, w)))));
      ends[p.vertex[k]] += 2;
    }
  for (size_t v = 0; v < interior_.size(); ++v)
    interior_[v] = !isCut_[v] && angle[v] > 6.283185307179586 - 1e-3 && ends[v] < 256
                       ? static_cast<uint8_t>(ends[v])
                       : 0;
  for (const SmoothVertex& sv : staged.smooth) interior_[sv.vertex] = 0;
  // Smoothed only where every neighbour is interior too: an outline
  // vertex holds the value half a leaf inside, and extrapolated it is
  // exact for a linear field but twice as noisy; either beside a smoothed
  // vertex would move it.
  std::vector<uint8_t> keep(interior_.size(), 1);
  for (const Patch& p : patches)
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % p.numCorners];
      if (!interior_[b]) keep[a] = 0;
      if (!interior_[a]) keep[b] = 0;
    }
  for (size_t v = 0; v < interior_.size(); ++v)
    if (!keep[v]) interior_[v] = 0;
}

int64_t DisplayLattice::FindSmooth(uint32_t v) const {
  const SmoothVertex* it =
      std::lower_bound(smooth_.begin(), smooth_.end(), v,
                       [](const SmoothVertex& s, uint32_t x) { return s.vertex < x; });
  return it != smooth_.end() && it->vertex == v ? it - smooth_.begin() : -1;
}

void DisplayLattice::Clear() {
  for (size_t v = 0; v < radiosity_.size(); ++v) {
    radiosity_[v] = glm::vec3(0.0f);
    weight_[v] = 0.0f;
    frac_[v] = 0.0f;
    inward_[v] = glm::vec3(0.0f);
  }
  for (glm::vec3& d : solvedDirect_) d = glm::vec3(0.0f);
}

void DisplayLattice::Finish(Span<const Patch> patches, int smoothSteps) {
  const size_t n = radiosity_.size();
  for (size_t v = 0; v < n; ++v)
    if (weight_[v] > 0.0f) radiosity_[v] /= weight_[v];
  for (size_t v = 0; v < solvedDirect_.size(); ++v)
    if (weight_[v] > 0.0f) solvedDirect_[v] /= weight_[v];
  smoothed_ = smoothSteps > 0 && !interior_.empty();
  if (!smoothed_) {
    Extrapolate(patches);
    return;
  }
  // raw: the values without smoothing (outline extrapolated), which the
  // display's leaves inside a patch are moved from; acc: a step's sums. The
  // smoothed vertices' neighbours are interior, so the outline's means are
  // never read, and are extrapolated once, from the smoothed values.
  glm::vec3* raw = raw_.data();
  glm::vec3* acc = raw_.data() + n;
  for (size_t v = 0; v < n; ++v) acc[v] = radiosity_[v];
  Extrapolate(patches);
  for (size_t v = 0; v < n; ++v) {
    raw[v] = radiosity_[v];
    radiosity_[v] = acc[v];
  }
  // inward_.x (Extrapolate's scratch, cleared there) counts the edge
  // neighbours that hold a value, the same every step: a vertex no exposed
  // leaf touches (weight 0) holds none, and is neither taken in nor smoothed.
  auto holds = [&](uint32_t v) { return weight_[v] > 0.0f ? 1.0f : 0.0f; };
  for (size_t v = 0; v < n; ++v) inward_[v] = glm::vec3(0.0f);
  for (const Patch& p : patches)
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % p.numCorners];
      inward_[a].x += holds(b);
      inward_[b].x += holds(a);
    }
  for (int step = 0; step < smoothSteps; ++step) {
    for (size_t v = 0; v < n; ++v) acc[v] = glm::vec3(0.0f);
    for (const Patch& p : patches)
      for (uint32_t k = 0; k < p.numCorners; ++k) {
        uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % p.numCorners];
        acc[a] += holds(b) * radiosity_[b];
        acc[b] += holds(a) * radiosity_[a];
      }
    for (size_t v = 0; v < n; ++v)
      if (interior_[v] && weight_[v] > 0.0f && inward_[v].x > 0.0f)
        radiosity_[v] = 0.5f * radiosity_[v] + 0.5f * acc[v] / inward_[v].x;
  }
  Extrapolate(patches);
}

void DisplayLattice::Extrapolate(Span<const Patch> patches) {
  // On a polygon's outline the nodal average is the value half a leaf
  // inside, not at the outline: in a concave corner, where the radiosity
  // falls towards the edge, it is too bright there. Extrapolate along
  // the quads' diagonals from the interior vertices beyond them (exact for a
  // linear gradient): f(0) = n0 + (n0 - n1) (s/2) / (1 - s/2), with s the
  // corner leaves' edge as a share of the patch's (s = 1: 2 n0 - n1).
  for (size_t v = 0; v < radiosity_.size(); ++v) inward_[v] = glm::vec3(0.0f);
  for (const Patch& p : patches) {
    if (p.numCorners != 4) continue;
    for (uint32_t k = 0; k < 4; ++k)
      if (outline_[p.vertex[k]]) inward_[p.vertex[k]] += radiosity_[p.vertex[(k + 2) % 4]];
  }
  for (size_t v = 0; v < radiosity_.size(); ++v) {
    uint8_t q = outline_[v];
    if (q == 0) continue;
    float s = frac_[v] / static_cast<float>(q), f = 0.5f * s / (1.0f - 0.5f * s);
    glm::vec3 inward = inward_[v] / static_cast<float>(q);
    glm::vec3 b = radiosity_[v] + f * (radiosity_[v] - inward);
    radiosity_[v] = glm::max(b, glm::vec3(0.0f));
  }
}

}  // namespace vismask
