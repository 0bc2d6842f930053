// Environments made by hand from a scene, as init makes them in one
// process, for tests that drive rounds or Solve directly.
#pragma once
#include <memory>
#include <vector>

#include "vismask/core/span.h"
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

}  // namespace vismask::test
