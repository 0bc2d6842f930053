#include "vismask/display.h"

#include "vismask/check.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace vismask {

namespace {

constexpr float kInvPi = 0.318309886183790672f;

bool Inside(bool triangle, glm::vec2 st) {
  if (st.x < 0.0f || st.y < 0.0f) return false;
  return triangle ? st.x + st.y <= 1.0f : st.x <= 1.0f && st.y <= 1.0f;
}

// The display radiosity at parameters `st` of patch `i`.
glm::vec3 CornerValue(const Environment& env, uint32_t i, glm::vec2 st, const double ambient[3]) {
  const Patch& p = env.patches()[i];
  const bool triangle = p.numCorners == 3;
  glm::vec2 roots[4];
  int n = RootCorners(triangle, roots);
  for (int k = 0; k < n; ++k)
    if (st == roots[k]) return env.vertexRadiosity()[p.vertex[k]];
  // On an edge of the patch along a cut: the line between the edge's two
  // lattice vertices, whose values are shared with the other side (ShareCuts).
  for (int k = 0; k < n; ++k) {
    uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % n];
    if (!env.IsCutVertex(a) || !env.IsCutVertex(b)) continue;
    glm::vec2 e = roots[(k + 1) % n] - roots[k], q = st - roots[k];
    if (std::fabs(e.x * q.y - e.y * q.x) > 1e-6f) continue;  // not on this edge
    float f = glm::dot(q, e) / glm::dot(e, e);
    return (1.0f - f) * env.vertexRadiosity()[a] + f * env.vertexRadiosity()[b];
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
    float w = env.elements()[leaf].area;
    sum += w * env.LeafRadiosity(i, leaf, ambient);
    weight += w;
  }
  return weight > 0.0f ? sum / weight : glm::vec3(0.0f);
}

}  // namespace

void DrawEnvironment(const View& view, const Environment& env, const double ambient[3],
                     Framebuffer* fb, Span<const Texture> textures) {
  Span<const Element> elements = env.elements();
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    const bool triangle = p.numCorners == 3;
    // The back of a one-sided patch reflects nothing: it is drawn black.
    const bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
    const PatchTexture* tex = facing ? env.patchTexture(i) : nullptr;
    CHECK(!tex || (tex->texture < textures.size() && textures[tex->texture].texels));
    // Depth-first over the tree, with a fixed stack (4 entries per level).
    struct Node {
      uint32_t e;
      glm::vec2 c[4];
    };
    Node stack[4 * 32 + 1];
    int top = 0;
    stack[top].e = i;
    int n = RootCorners(triangle, stack[top].c);
    ++top;
    while (top > 0) {
      Node node = stack[--top];
      const Element& el = elements[node.e];
      if (el.child != kNoElement) {
        for (uint32_t k = 0; k < 4; ++k) {
          Node& ch = stack[top++];
          ch.e = el.child + k;
          ChildCorners(triangle, node.c, k, ch.c);
        }
        continue;
      }
      DisplayPiece piece;
      piece.numCorners = static_cast<uint32_t>(n);
      // The polygon's id, not the patch's: the pieces of one polygon tile its
      // plane, so the raster may merge them into one fragment per pixel,
      // which leaves room at a silhouette where two faces of a block, each
      // cut into patches, meet a wall behind (with patch ids that pixel held
      // five or more fragments and lost the wall: dark dots along the edges).
      piece.id = p.surface;
      for (int k = 0; k < n; ++k) {
        piece.p[k] = PatchPoint(p, node.c[k]);
        piece.c[k] = facing ? kInvPi * CornerValue(env, i, node.c[k], ambient) : glm::vec3(0.0f);
      }
      if (n == 3) {
        piece.p[3] = piece.p[2];
        piece.c[3] = piece.c[2];
      }
      if (tex) {
        piece.texture = &textures[tex->texture];
        piece.ke = kInvPi * p.ke;
        for (int k = 0; k < n; ++k) piece.uv[k] = PatchUv(*tex, triangle, node.c[k]);
        piece.uv[3] = piece.uv[n - 1];
      }
      DrawPiece(view, piece, fb);
    }
  }
}

void CollectCuts(Span<Environment* const> envs, Span<CutRecord> out) {
  size_t n = 0;
  for (const Environment* env : envs) {
    Span<const uint32_t> cut = env->cutVertices();
    for (size_t k = 0; k < cut.size(); ++k) {
      CHECK(n < out.size());
      uint32_t v = cut[k];
      CutRecord& r = out[n++];
      float w = env->vertexWeights()[v];
      glm::vec3 x = env->vertices()[v], nrm = env->cutNormals()[k], b = env->vertexRadiosity()[v];
      for (int a = 0; a < 3; ++a) {
        r.pos[a] = x[a];
        r.normal[a] = nrm[a];
        r.sum[a] = b[a] * w;
      }
      r.weight = w;
      r.env = env->index();
      r.vertex = v;
    }
  }
  for (; n < out.size(); ++n) out[n] = CutRecord{};
}

void ShareCuts(Span<Environment* const> envs, Span<CutRecord> all, float tolerance) {
  // Padding last; the rest in a fixed order (ties below break on it too).
  auto less = [](const CutRecord& a, const CutRecord& b) {
    if ((a.weight > 0.0f) != (b.weight > 0.0f)) return a.weight > 0.0f;
    if (a.env != b.env) return a.env < b.env;
    return a.vertex < b.vertex;
  };
  std::sort(all.begin(), all.end(), less);
  size_t used = 0;
  while (used < all.size() && all[used].weight > 0.0f) ++used;
  for (Environment* env : envs) {
    Span<const uint32_t> cut = env->cutVertices();
    const Bounds& box = env->box();
    for (size_t k = 0; k < cut.size(); ++k) {
      uint32_t v = cut[k];
      glm::vec3 x = env->vertices()[v], n = env->cutNormals()[k];
      // The cut plane it lies on (the first, at a corner of the box).
      int axis = 0;
      for (int a = 2; a >= 0; --a)
        if (std::fabs(x[a] - box.lo[a]) <= tolerance || std::fabs(x[a] - box.hi[a]) <= tolerance)
          axis = a;
      glm::vec3 e(0.0f);
      e[axis] = 1.0f;
      glm::vec3 d = glm::cross(e, n);
      float len = glm::length(d);
      if (!(len > 0.5f)) continue;  // the surface lies in the cut plane
      d /= len;
      // The other side's display function along the cut line: its records
      // on this line with this normal, the nearest at or below x and above.
      const CutRecord* below = nullptr;
      const CutRecord* above = nullptr;
      float tBelow = 0.0f, tAbove = 0.0f;
      for (size_t i = 0; i < used; ++i) {
        const CutRecord& r = all[i];
        if (r.env == env->index()) continue;
        if (r.normal[0] * n.x + r.normal[1] * n.y + r.normal[2] * n.z < 0.999f) continue;
        glm::vec3 q(r.pos[0], r.pos[1], r.pos[2]);
        glm::vec3 off = q - x;
        if (std::fabs(off[axis]) > tolerance || std::fabs(glm::dot(off, n)) > tolerance) continue;
        float t = glm::dot(off, d);
        if (t <= tolerance && (!below || t > tBelow)) {
          below = &r;
          tBelow = t;
        }
        if (t >= -tolerance && (!above || t < tAbove)) {
          above = &r;
          tAbove = t;
        }
      }
      if (!below || !above) continue;  // x is beyond the other side's cut edge
      float f = tAbove - tBelow > tolerance ? -tBelow / (tAbove - tBelow) : 0.0f;
      float w = env->vertexWeights()[v];
      glm::vec3 sum = env->vertexRadiosity()[v] * w;
      float weight = w;
      for (int c = 0; c < 3; ++c) sum[c] += (1.0f - f) * below->sum[c] + f * above->sum[c];
      weight += (1.0f - f) * below->weight + f * above->weight;
      if (weight > 0.0f) env->SetVertexRadiosity(v, sum / weight);
    }
  }
}

}  // namespace vismask
