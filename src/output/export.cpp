// --export FILE.glb: the solved mesh as binary glTF (gltf.h), gathered to
// rank 0 like patches.csv and written through fixed buffers (run.h).
#include "../app/run.h"

namespace vismask::run {

// One environment's part of the file. Its vertex radiosity must be current
// (RenderImage).
GlbMesh ExportMeshOf(const Environment& env) {
  GlbMesh m;
  Span<const glm::vec3> v = env.lattice().vertices();
  m.vertices = v.size();
  for (const Patch& p : env.patches()) m.triangles += p.numCorners == 4 ? 2 : 1;
  Span<const glm::vec3> b = env.lattice().radiosity();
  for (size_t i = 0; i < v.size(); ++i) {
    const glm::vec3 radiance = DisplayRadiance(b[i]);
    for (int a = 0; a < 3; ++a) {
      if (i == 0 || v[i][a] < m.lo[a]) m.lo[a] = v[i][a];
      if (i == 0 || v[i][a] > m.hi[a]) m.hi[a] = v[i][a];
      if (radiance[a] > m.maxRadiance) m.maxRadiance = radiance[a];
    }
  }
  return m;
}

namespace {

// One stream of fixed-size items (vertices, then triangles) through the
// rank's chunk buffer: rank 0 writes full chunks to the file, the others
// send them to rank 0. A chunk is a whole number of items and is sent only
// when full (or at the end), so rank 0 receives the same sizes it expects.
class Stream {
 public:
  Stream(RunState* r, size_t itemBytes) : r_(r), item_(itemBytes) {
    CHECK(r->exportChunk.size() % itemBytes == 0);
  }
  uint8_t* Next() {
    if (used_ + item_ > r_->exportChunk.size()) Flush();
    uint8_t* p = r_->exportChunk.data() + used_;
    used_ += item_;
    return p;
  }
  void Flush() {
    if (used_ == 0) return;
    if (r_->isRoot())
      r_->exportFile.Write(r_->exportChunk.data(), used_);
    else
      r_->transport->Send(0, r_->exportChunk.data(), used_);
    used_ = 0;
  }
  // Rank 0: another rank's `bytes` of this stream, in the chunks it sends.
  void Relay(int src, uint64_t bytes) {
    CHECK(used_ == 0);
    while (bytes > 0) {
      size_t n =
          bytes < r_->exportChunk.size() ? static_cast<size_t>(bytes) : r_->exportChunk.size();
      r_->transport->Recv(src, r_->exportChunk.data(), n);
      r_->exportFile.Write(r_->exportChunk.data(), n);
      bytes -= n;
    }
  }

 private:
  RunState* r_;
  size_t item_;
  size_t used_ = 0;
};

}  // namespace

// The file is the head, every vertex (environment order: rank 0's, then
// each other rank's), then every triangle in the same order, its indices
// offset by the vertices of the environments before its own.
void WriteExport(RunState* r) {
  if (r->options.exportPath.empty()) return;
  Transport* t = r->transport.get();
  for (uint32_t i = 0; i < r->rankEnvs.perRank; ++i) r->exportMine[i] = GlbMesh{};
  for (size_t i = 0; i < r->envPtrs.size(); ++i) r->exportMine[i] = ExportMeshOf(*r->envPtrs[i]);
  GatherByEnv(r, r->exportMine, r->exportAll, r->exportByEnv);
  GlbMesh whole;
  for (const GlbMesh& m : r->exportByEnv) MergeGlbMesh(m, &whole);
  r->exportWhole = whole;
  // Each rank's bytes of the two streams, and the first vertex of each of
  // this rank's environments.
  const int ranks = t->size();
  auto rankBytes = [&](int k, size_t item, bool vertices) {
    RankEnvs re = EnvsOfRank(r->rankEnvs.total, ranks, k);
    uint64_t n = 0;
    for (uint32_t e = re.first; e < re.first + re.count; ++e)
      n += vertices ? r->exportByEnv[e].vertices : r->exportByEnv[e].triangles;
    return n * item;
  };
  uint64_t firstVertex = 0;
  for (uint32_t e = 0; e < r->rankEnvs.first; ++e) firstVertex += r->exportByEnv[e].vertices;

  if (r->isRoot()) {
    size_t head = WriteGlbHead(whole, r->exportHead);
    r->exportFile.Write(r->exportHead.data(), head);
    r->exportBytes = head + GlbBinBytes(whole);
  }
  const float scale = GlbRadianceScale(whole);
  Stream vertices(r, kGlbVertexBytes);
  for (Environment* env : r->envPtrs) {
    Span<const glm::vec3> pos = env->lattice().vertices();
    Span<const glm::vec3> b = env->lattice().radiosity();
    for (size_t v = 0; v < pos.size(); ++v)
      PutGlbVertex(pos[v], DisplayRadiance(b[v]), scale, vertices.Next());
  }
  vertices.Flush();
  if (r->isRoot())
    for (int k = 1; k < ranks; ++k) vertices.Relay(k, rankBytes(k, kGlbVertexBytes, true));

  Stream triangles(r, kGlbTriangleBytes);
  for (Environment* env : r->envPtrs) {
    const uint32_t base = static_cast<uint32_t>(firstVertex);
    for (const Patch& p : env->patches()) {
      const uint32_t* v = p.vertex;
      PutGlbTriangle(base + v[0], base + v[1], base + v[2], triangles.Next());
      if (p.numCorners == 4)
        PutGlbTriangle(base + v[0], base + v[2], base + v[3], triangles.Next());
    }
    firstVertex += env->lattice().vertices().size();
  }
  triangles.Flush();
  if (r->isRoot())
    for (int k = 1; k < ranks; ++k) triangles.Relay(k, rankBytes(k, kGlbTriangleBytes, false));
}

}  // namespace vismask::run
