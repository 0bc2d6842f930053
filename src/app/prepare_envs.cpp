// Init's meshing (run.h): the environments a rank holds meshed and staged
// one at a time, and the bounds on what init holds at its peak.
#include "run.h"

namespace vismask::run {

uint64_t Prepared::StagedBound(uint32_t e) const {
  // Environment::Prepare's copies until Build: per patch the patch, its
  // geometry, texture, twin id and smooth edges; per lattice vertex its
  // position, a smooth-vertex record, a cut flag and normal.
  constexpr uint64_t kPerPatch = sizeof(Patch) + sizeof(PatchGeom) + sizeof(PatchTexture) + 8;
  constexpr uint64_t kPerVertex = sizeof(glm::vec3) + sizeof(SmoothVertex) + 20;
  return static_cast<uint64_t>(envPatches[e]) * kPerPatch +
         static_cast<uint64_t>(envVertices[e]) * kPerVertex;
}

uint64_t Prepared::MeshBound(uint32_t e) const {
  // The Mesh an environment is made from (freed once it is staged): its
  // patches and positions (1.5 times, AddTwins growing them past their
  // reserve), twin ids, textures, patch ids, the grid plan's scratch; its
  // smooth-vertex records twice (found, kept) and a seen flag.
  constexpr uint64_t kPerPatch = 3 * sizeof(Patch) / 2 + 6 + sizeof(PatchTexture) + 4 + 64;
  constexpr uint64_t kPerVertex = 3 * sizeof(glm::vec3) / 2 + 2 * sizeof(SmoothVertex) + 1;
  return static_cast<uint64_t>(envPatches[e]) * kPerPatch +
         static_cast<uint64_t>(envVertices[e]) * kPerVertex;
}

uint64_t Prepared::InitPeak(uint32_t first, uint32_t end, bool root, uint64_t envArenas,
                            uint64_t rankArena, uint64_t held) const {
  uint64_t pieceBytes = 0, stagedBytes = 0, meshBytes = 0;
  for (uint32_t e = first; e < end; ++e) {
    pieceBytes += envPieceBytes[e];
    stagedBytes += StagedBound(e);
    meshBytes = std::max(meshBytes, MeshBound(e));  // one mesh at a time
  }
  // Per environment of the whole grid: its counts.
  held += kInitBaseBytes + textureBytes + 4 * sizeof(double) * envPatches.size();
  const uint64_t parse =
      info.ParserBytes() + pieceBytes + ViewProbe::HeapBytes(outside) + (root ? checkBytes : 0);
  const uint64_t mesh = pieceBytes + stagedBytes + meshBytes;
  // The pieces are freed before the arenas are made, but their small blocks
  // may stay in the process's heap: counted, so that the bound holds for
  // the resident set too.
  const uint64_t build = pieceBytes + stagedBytes + envArenas + rankArena;
  return held + std::max(parse, std::max(mesh, build));
}

// Environment by environment, as meshing each would refuse it.
Status CheckEnvSizes(const Prepared& p, uint32_t total) {
  for (uint32_t e = 0; e < total; ++e) {
    if (p.envPatches[e] > static_cast<double>(kMaxPatches))
      return Status::Error("vismask: --patch-size: " +
                           MeshSizeError(p.envPatches[e], p.patchSize, kMaxPatches).message());
    if (p.envPatches[e] + p.envTwins[e] > static_cast<double>(kMaxPatches))
      return Status::Error("vismask: --patch-size: the mesh needs " +
                           std::to_string(static_cast<uint64_t>(p.envPatches[e] + p.envTwins[e])) +
                           " patches with both sides, more than the limit of " +
                           std::to_string(kMaxPatches));
  }
  return Status::Ok();
}

// Meshes environments [first, end), which `p` holds, in order, one at a
// time, giving each patch its global (environment-major) id from p.idBase
// on, and prepares them into `envs`.
Status PrepareEnvs(const Prepared& p, uint32_t first, uint32_t end,
                   std::vector<std::unique_ptr<Environment>>* envs) {
  CHECK(p.first <= first && end <= p.end);
  uint32_t nextId = p.idBase;
  for (uint32_t e = p.first; e < first; ++e) nextId += static_cast<uint32_t>(p.envPatches[e]);
  const double t0 = os::Seconds();
  double textureSeconds = 0.0;
  for (uint32_t e = first; e < end; ++e) {
    Mesh mesh;
    Status s = MeshScene(p.part.scene, p.pieces[e], p.patchSize, kMaxPatches, &mesh);
    if (!s.ok()) return Status::Error("vismask: --patch-size: " + s.message());
    // Twins in the environment of their originals, after all of its patches.
    AddTwins(p.twins, &mesh, &p.part.scene);
    if (mesh.patches.size() > kMaxPatches)
      return Status::Error(
          "vismask: --patch-size: the mesh needs " + std::to_string(mesh.patches.size()) +
          " patches with both sides, more than the limit of " + std::to_string(kMaxPatches));
    CHECK_EQ(static_cast<double>(mesh.patches.size()), p.envPatches[e]);
    for (Patch& patch : mesh.patches) patch.globalId += nextId;
    nextId += static_cast<uint32_t>(mesh.patches.size());
    const double tt = os::Seconds();
    TextureMesh(p.part.scene, p.textures, &mesh);
    textureSeconds += os::Seconds() - tt;
    if (p.smooth) MarkSmoothVertices(p.scene, p.part, p.tolerance, &mesh, &p.sourceIds);
    // Patch::surface is the piece's index in the whole partition (the
    // raster's fragment id, compared across ranks): the rank's pieces are
    // those of its environments, after the pieces of all before them.
    for (Patch& patch : mesh.patches) patch.surface += p.pieceBase;
    std::vector<uint32_t> ids(mesh.patches.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    envs->push_back(std::make_unique<Environment>());
    envs->back()->Prepare(p.grid, e, mesh, ids, p.envOptions);
  }
  p.clock.Done("texture means", textureSeconds);
  p.clock.Done("meshing", os::Seconds() - t0 - textureSeconds);
  return Status::Ok();
}

uint64_t OwnPatches(const Prepared& p) {
  double n = 0.0;
  for (uint32_t e = p.first; e < p.end; ++e) n += p.envPatches[e];
  return static_cast<uint64_t>(n);
}

}  // namespace vismask::run
