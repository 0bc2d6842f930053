// Environments made by hand from a scene, as init makes them in one
// process, for tests that drive rounds or Solve directly.
#pragma once
#include <memory>
#include <vector>

#include "grid_test_util.h"
#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/element_tree.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/partition.h"

namespace vismask::test {

struct TestEnvs {
  std::vector<std::unique_ptr<Environment>> owned;
  std::vector<Environment*> ptrs;
  Span<Environment* const> span() const {
    return Span<Environment* const>(ptrs.data(), ptrs.size());
  }
};

// The scene at `path` split by `shape` (its n; its box is set to the
// scene's), meshed at `patchSize`, one environment per cell with options
// `eo` and global patch ids in environment order. Fails the test (fatally)
// when the scene does not load, split or mesh.
void MakeTestEnvs(const char* path, const EnvGrid& shape, float patchSize, const EnvOptions& eo,
                  TestEnvs* out);

// One patch, the unit quad at y = 0 (gridtest::AddSubdividedQuad), and
// its element tree laid out in an arena of its own (`indirect`: with the
// per-pixel direct light's arrays) and reset: for tests of ElementTree.
struct UnitQuadTree {
  explicit UnitQuadTree(bool indirect) : arena(1 << 16) {
    gridtest::AddSubdividedQuad(1, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1, 1, &scene);
    patches = Span<const Patch>(scene.patches.data(), scene.patches.size());
    tree.Layout(arena, 1, ElementOptions{}, indirect);
    tree.Reset(patches);
  }
  UnitQuadTree(const UnitQuadTree&) = delete;
  UnitQuadTree& operator=(const UnitQuadTree&) = delete;
  gridtest::TestScene scene;
  Arena arena;
  ElementTree tree;
  Span<const Patch> patches;
};

}  // namespace vismask::test
