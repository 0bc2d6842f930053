#include "vismask/display.h"

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

void DrawEnvironment(const View& view, Environment* envp, const double ambient[3], Framebuffer* fb) {
  envp->ComputeVertexRadiosity(ambient);
  const Environment& env = *envp;
  Span<const Element> elements = env.elements();
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    const bool triangle = p.numCorners == 3;
    // The back of a one-sided patch reflects nothing: it is drawn black.
    const bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
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
      piece.id = p.globalId;
      for (int k = 0; k < n; ++k) {
        piece.p[k] = PatchPoint(p, node.c[k]);
        piece.c[k] = facing ? kInvPi * CornerValue(env, i, node.c[k], ambient) : glm::vec3(0.0f);
      }
      if (n == 3) {
        piece.p[3] = piece.p[2];
        piece.c[3] = piece.c[2];
      }
      DrawPiece(view, piece, fb);
    }
  }
}

}  // namespace vismask
