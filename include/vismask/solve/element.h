// Elements: receivers finer than shooters (Cohen, Greenberg, Immel & Brock
// 1986). Every patch is the root of a quadtree of elements over its own
// parameter space; a patch shoots as a whole, but each ray it receives lands
// in one leaf element, which is what the image shows. A leaf splits into
// four when the power it has received since it was made is spread unevenly
// over its four quarters, beyond what the Monte Carlo noise of those hits
// explains (a chi-square test against an even spread, each hit's power
// squared giving the variance): at shadow boundaries, contact shadows and
// corners, and only once enough rays have landed there to tell. The
// children start from what landed in their quarter (exact since the split
// parent was made; its older history is shared by area). Children come from
// a pool reserved at init; when it runs out, refinement stops.
//
// Parameter space: a quad's (s, t) in [0, 1]^2, bilinear over corners
// 0, 1, 2, 3 (s along 0->1, t along 0->3); a triangle's (s, t) are the
// barycentric weights of corners 1 and 2. A quad element's children are its
// four quarters (k = [s >= 1/2] + 2 [t >= 1/2]); a triangle's are the three
// corner triangles and the middle one (midpoint subdivision).
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "vismask/core/span.h"
#include "vismask/solve/patch.h"

namespace vismask {

constexpr uint32_t kNoElement = 0xffffffffu;

struct Element {
  double received[3];    // reflected power received (W), history included
  double quarter[4][3];  // the part of it received in each child's region since made
  double squares;        // the sum of each received share's square (channels summed) since made
  float area;
  uint32_t child;  // first of four consecutive children; kNoElement for a leaf
  uint32_t hits;   // rays received since made
  uint32_t depth;  // 0 for a patch's root
};

struct ElementOptions {
  uint32_t perPatch = 8;   // pool: this many elements per patch on average, beyond the roots
  uint32_t maxDepth = 4;   // a leaf of this depth never splits
  uint32_t minHits = 64;   // hits a leaf needs before it may split
  float threshold = 0.1f;  // the least relative RMS spread of the quarters' densities that splits
  float chi2 = 20.0f;      // ... when also significant: chi-square (3 dof) of the quarters against
                           // an even spread, above this (20: p = 2e-4)
};

// (s, t) of the point `x` on patch `p` (clamped to the patch).
glm::vec2 PatchParam(const Patch& p, const glm::vec3& x);
// The point of patch `p` at (s, t).
glm::vec3 PatchPoint(const Patch& p, glm::vec2 st);
// Where a shooter's centre rays (its masks, Methods B and C, and the share
// of its power in flight) leave from: its centre (CentreOf), or with open
// cells (Patch::openCells) the centre of the open cell nearest their mean,
// so that a patch whose centre lies under a block does not cast them all
// from inside it. The same on every rank: the packet carries the cells.
glm::vec3 MaskCentre(const Patch& p);
// The child of an element holding `st` (in the element's own parameters),
// with `st` mapped into the child's parameters.
uint32_t ChildOf(bool triangle, glm::vec2* st);
// Corner `k` of child `child`, in the parent's parameters, from the
// parent's corners `in` (3 for a triangle, 4 for a quad, in the patch's).
void ChildCorners(bool triangle, const glm::vec2* in, uint32_t child, glm::vec2* out);
// The parameter-space corners of a patch's root.
int RootCorners(bool triangle, glm::vec2* out);

// Calls visit(e, corners, n) for every leaf e of patch `patch`'s tree (a
// triangle or not) in `elements`, depth-first, with its n corners in the
// patch's parameters. A fixed stack (four entries a level): no allocation.
template <typename Visit>
void ForEachLeaf(Span<const Element> elements, bool triangle, uint32_t patch, Visit visit) {
  struct Node {
    uint32_t e;
    glm::vec2 c[4];
  };
  Node stack[4 * 32 + 1];
  int top = 0;
  stack[top].e = patch;
  const int n = RootCorners(triangle, stack[top].c);
  ++top;
  while (top > 0) {
    const Node node = stack[--top];
    const Element& el = elements[node.e];
    if (el.child == kNoElement) {
      visit(node.e, static_cast<const glm::vec2*>(node.c), n);
      continue;
    }
    for (uint32_t k = 0; k < 4; ++k) {
      Node& ch = stack[top++];
      ch.e = el.child + k;
      ChildCorners(triangle, node.c, k, ch.c);
    }
  }
}

}  // namespace vismask
