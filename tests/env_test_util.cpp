#include "env_test_util.h"

#include <gtest/gtest.h>

#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"

namespace vismask::test {

void MakeTestEnvs(const char* path, const EnvGrid& shape, float patchSize, const EnvOptions& eo,
                  TestEnvs* out) {
  Scene scene;
  ASSERT_TRUE(LoadScene(path, &scene).ok()) << path;
  EnvGrid grid = shape;
  grid.box = scene.bounds;
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  uint32_t nextId = 0;
  for (uint32_t e = 0; e < static_cast<uint32_t>(grid.count()); ++e) {
    std::vector<uint32_t> pieces;
    for (uint32_t i = 0; i < part.scene.polygons.size(); ++i)
      if (part.env[i] == e) pieces.push_back(i);
    Mesh mesh;
    ASSERT_TRUE(MeshScene(part.scene, pieces, patchSize, 1u << 20, &mesh).ok());
    for (Patch& p : mesh.patches) p.globalId += nextId;
    nextId += static_cast<uint32_t>(mesh.patches.size());
    std::vector<uint32_t> ids(mesh.patches.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    out->owned.push_back(std::make_unique<Environment>());
    out->owned.back()->Init(grid, e, mesh, ids, eo);
    out->ptrs.push_back(out->owned.back().get());
  }
}

}  // namespace vismask::test
