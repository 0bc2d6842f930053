#include "vismask/display/display.h"

#include <cmath>
#include <glm/geometric.hpp>

#include "vismask/core/check.h"
#include "vismask/display/direct.h"

namespace vismask {

namespace {

bool Inside(bool triangle, glm::vec2 st) {
  if (st.x < 0.0f || st.y < 0.0f) return false;
  return triangle ? st.x + st.y <= 1.0f : st.x <= 1.0f && st.y <= 1.0f;
}

// The display radiosity at parameters `st` of patch `i`.
glm::vec3 CornerValue(const Environment& env, uint32_t i, glm::vec2 st, const double ambient[3]) {
  const Patch& p = env.patches()[i];
  const DisplayLattice& lattice = env.lattice();
  const bool triangle = p.numCorners == 3;
  glm::vec2 roots[4];
  int n = RootCorners(triangle, roots);
  for (int k = 0; k < n; ++k)
    if (st == roots[k]) return lattice.radiosity()[p.vertex[k]];
  // On an edge of the patch along a cut: the line between the edge's two
  // lattice vertices, whose values are shared with the other side (ShareVertices).
  // Likewise along an outline edge whose ends are shared with other
  // polygons (smoothing).
  for (int k = 0; k < n; ++k) {
    uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % n];
    bool cut = lattice.IsCutVertex(a) && lattice.IsCutVertex(b);
    if (!cut && !lattice.IsSmoothEdge(i, static_cast<uint32_t>(k))) continue;
    glm::vec2 e = roots[(k + 1) % n] - roots[k], q = st - roots[k];
    if (std::fabs(e.x * q.y - e.y * q.x) > 1e-6f) continue;  // not on this edge
    float f = glm::dot(q, e) / glm::dot(e, e);
    return (1.0f - f) * lattice.radiosity()[a] + f * lattice.radiosity()[b];
  }
  // The leaves touching `st`: probes a hair away in eight directions.
  constexpr float e = 1e-5f;
  const glm::vec2 dirs[8] = {{e, 0}, {-e, 0}, {0, e}, {0, -e}, {e, e}, {-e, e}, {e, -e}, {-e, -e}};
  uint32_t seen[8];
  int count = 0;
  glm::vec3 sum(0.0f);
  float weight = 0.0f;
  for (const glm::vec2& d : dirs) {
    glm::vec2 q = st + d;
    if (!Inside(triangle, q)) continue;
    uint32_t leaf = env.LeafAt(i, q);
    bool dup = false;
    for (int k = 0; k < count; ++k) dup |= seen[k] == leaf;
    if (dup) continue;
    seen[count++] = leaf;
    float w = env.ExposedArea(leaf);
    sum += w * env.LeafRadiosity(i, leaf, ambient);
    weight += w;
  }
  glm::vec3 b = weight > 0.0f ? sum / weight : glm::vec3(0.0f);
  if (lattice.smoothed()) {
    // What smoothing moved the corners by, interpolated over the patch.
    glm::vec3 d[4];
    for (int k = 0; k < n; ++k)
      d[k] = lattice.radiosity()[p.vertex[k]] - lattice.Unsmoothed(p.vertex[k]);
    if (triangle)
      b += (1.0f - st.x - st.y) * d[0] + st.x * d[1] + st.y * d[2];
    else
      b += (1.0f - st.x) * (1.0f - st.y) * d[0] + st.x * (1.0f - st.y) * d[1] + st.x * st.y * d[2] +
           (1.0f - st.x) * st.y * d[3];
  }
  return b;
}

// The environment's pieces into `fb` as fb->pass says; with `directOnly`
// only the patches that gather direct light per pixel.
void DrawPieces(const View& view, const Environment& env, const double ambient[3], Framebuffer* fb,
                Span<const Texture> textures, bool directOnly, const DirectLight& light,
                uint32_t viewer) {
  Span<const Element> elements = env.elements();
  uint32_t hint = kNoPatch;  // the last occluder of a shadow ray
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    const bool triangle = p.numCorners == 3;
    // The back of a one-sided patch reflects nothing: it is drawn black.
    const bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
    // Of two twins (two-sided meshes) only the one facing the eye is drawn:
    // they share corner[0] and their normals are exact negatives, so just
    // one of them faces it, and no coplanar back face takes a fragment.
    if (!facing && env.twinOf(i) != kNoPatch) continue;
    const PatchTexture* tex = facing ? env.patchTexture(i) : nullptr;
    CHECK(!tex || (tex->texture < textures.size() && textures[tex->texture].texels));
    // Per-pixel direct light: the leaves show their indirect radiosity
    // (LeafRadiosity), interpolated as the whole was; the direct part is
    // gathered at each shaded point.
    DirectHook hook;
    const bool direct = facing && env.direct().ShowsIndirect(i) && !light.empty();
    if (directOnly && !direct) continue;
    if (direct) {
      constexpr float kInvPi = 0.318309886183790672f;
      hook.light = &light;
      hook.viewer = viewer;
      hook.grid = &env.grid();
      hook.patch = i;
      hook.twin = env.twinOf(i);
      hook.normal = p.normal;
      hook.planePoint = p.corner[0];
      hook.scale = kInvPi * p.kd * (tex ? tex->scale : glm::vec3(1.0f));
      hook.samples = env.directSamples();
      hook.epsilon = env.rayEpsilon();
      hook.hint = &hint;
    }
    ForEachLeaf(elements, triangle, i, [&](uint32_t, const glm::vec2* c, int n) {
      DisplayPiece piece;
      piece.numCorners = static_cast<uint32_t>(n);
      // The polygon's id, not the patch's: the pieces of one polygon tile its
      // plane, so the raster may merge them into one fragment per pixel,
      // which leaves room at a silhouette where two faces of a block, each
      // cut into patches, meet a wall behind (with patch ids that pixel held
      // five or more fragments and lost the wall: dark dots along the edges).
      piece.id = p.surface;
      for (int k = 0; k < n; ++k) {
        piece.p[k] = PatchPoint(p, c[k]);
        piece.c[k] = facing ? DisplayRadiance(CornerValue(env, i, c[k], ambient)) : glm::vec3(0.0f);
      }
      if (n == 3) {
        piece.p[3] = piece.p[2];
        piece.c[3] = piece.c[2];
      }
      if (tex) {
        piece.texture = &textures[tex->texture];
        piece.ke = DisplayRadiance(p.ke);
        for (int k = 0; k < n; ++k) piece.uv[k] = PatchUv(*tex, triangle, c[k]);
        piece.uv[3] = piece.uv[n - 1];
      }
      if (direct) piece.direct = &hook;
      DrawPiece(view, piece, fb);
    });
  }
}

}  // namespace

// Antialiased with direct light per pixel, two passes: every piece's
// coverage and interpolated radiance, then (MarkShown) each piece's direct
// light gathered only in the pixels where its fragment shows. A piece
// hidden behind nearer ones in this environment's own image casts no shadow
// rays (one pass gathered 1.6 times a pixel on the Cornell box at 512²; the
// two took its output time from 2.87 to 2.24 s), and what other
// environments composite in later only hides more.
void DrawEnvironment(const View& view, const Environment& env, const double ambient[3],
                     Framebuffer* fb, Span<const Texture> textures, const ForeignLight* foreign) {
  const bool all = foreign && !foreign->empty();
  const DirectLight& light = all ? foreign->light() : env.direct().light();
  const uint32_t viewer = all ? env.index() : DirectLight::kNoViewer;
  if (!fb->aa || light.empty()) {
    DrawPieces(view, env, ambient, fb, textures, false, light, viewer);
    return;
  }
  fb->pass = DrawPass::kCoverage;
  DrawPieces(view, env, ambient, fb, textures, false, light, viewer);
  MarkShown(fb);
  fb->pass = DrawPass::kDirect;
  DrawPieces(view, env, ambient, fb, textures, true, light, viewer);
  fb->pass = DrawPass::kWhole;
}

}  // namespace vismask
