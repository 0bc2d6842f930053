// Init: the scene loaded, cut into environments and meshed, the arenas
// measured and made, the camera chosen, the outputs opened (run.h).
#include "run.h"

namespace vismask::run {

Status PrepareScene(const Options& o, Prepared* p) {
  Status s = LoadScene(o.scene, &p->scene, o.load);
  if (!s.ok()) return s;
  s = LoadSceneTextures(p->scene, &p->textures);
  if (!s.ok()) return s;
  glm::vec3 extent = p->scene.bounds.hi - p->scene.bounds.lo;
  float maxExtent = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  p->patchSize = o.patchSize > 0.0f ? o.patchSize : maxExtent / kAutoPatchDivisions;
  p->tolerance = 1e-5f * maxExtent;
  p->smooth = o.smooth;
  for (int a = 0; a < 3; ++a) p->grid.n[a] = o.envs[a];
  p->grid.box = p->scene.bounds;
  // The scene's patches as the mesher will make them, about: the weight
  // --envs auto balances and the size of an automatic --round-work.
  double estimated = 0.0;
  for (const Polygon& poly : p->scene.polygons)
    estimated += EstimatedPatches(poly.corners.data(), static_cast<int>(poly.corners.size()),
                                  p->patchSize);
  if (o.roundWorkAuto)
    p->roundWork = AutoRoundWork(o, estimated, o.envs[0] * o.envs[1] * o.envs[2],
                                 EnvOptions().gridDensity);
  if (o.envsAuto) {
    // --envs auto:N: the shape with the least cut area, planes where the
    // estimated patches divide evenly (fed polygon by polygon, file order).
    if (!ChooseEnvShape(o.envsAutoCount, extent, p->grid.n))
      return Status::Error("vismask: --envs: auto:" + std::to_string(o.envsAutoCount) +
                           ": no grid of that many environments fits the scene (each axis "
                           "1..64, none split where the scene is flat)");
    WorkSplitter splitter;
    for (const Polygon& poly : p->scene.polygons) {
      const int n = static_cast<int>(poly.corners.size());
      splitter.Add(poly.corners.data(), n, poly.area,
                   EstimatedPatches(poly.corners.data(), n, p->patchSize));
    }
    splitter.Planes(&p->grid);
  }
  s = PartitionScene(p->scene, p->grid, &p->part);
  if (!s.ok()) return s;
  p->pieces.assign(p->grid.count(), {});
  for (uint32_t i = 0; i < p->part.scene.polygons.size(); ++i)
    p->pieces[p->part.env[i]].push_back(i);
  EnvOptions& e = p->envOptions;
  // 1e-6 of the scene's size, and at least 8 float steps of its largest
  // coordinate, so that the lift survives rounding far from the origin.
  glm::vec3 mag = glm::max(glm::abs(p->scene.bounds.lo), glm::abs(p->scene.bounds.hi));
  float largest = std::fmax(mag.x, std::fmax(mag.y, mag.z));
  e.rayEpsilon = std::fmax(1e-6f * glm::length(extent),
                           8.0f * std::numeric_limits<float>::epsilon() * largest);
  e.rays = RayCap(o);
  e.sobol = o.sobol;
  if (o.rayAlloc == Options::RayAlloc::kPower) {
    // The power a ray carries: the emitted power (channels summed, summed in
    // polygon order, the same on every rank) over --emitted-rays.
    double emitted = 0.0;
    for (const Polygon& poly : p->part.scene.polygons) {
      const glm::vec3& ke = p->part.scene.materials[poly.material].ke;
      emitted += (static_cast<double>(ke.x) + ke.y + ke.z) * poly.area;
    }
    if (o.twoSidedEmitters) emitted *= 2.0;  // every emitter's twin emits as much
    e.rayQuantum = emitted / static_cast<double>(o.emittedRays);
    e.minRays = o.minRays;
  }
  p->twins.all = o.twoSided;
  p->twins.emitters = o.twoSidedEmitters;
  e.seed = o.seed;
  e.maskMethod = o.maskMethod;
  e.maskRes = o.maskRes;
  e.roundShots = o.roundShots;
  e.queueCapacity = o.queue;
  e.elements.perPatch = o.elementsPerPatch;
  e.elements.maxDepth = o.elementDepth;
  e.elements.threshold = o.elementSpread;
  e.elements.chi2 = o.elementChi2;
  p->packetBytes =
      p->grid.count() > 1 ? PacketBytes(MaskShapeOf(o.maskMethod, o.maskRes, RayCap(o))) : 0;
  return Status::Ok();
}

// Meshes environments 0..end-1 in order, one at a time, giving each patch
// its global (environment-major) id, and prepares those from `first` on
// into `envs` (the earlier ones are meshed only to count their patches).
Status PrepareEnvs(const Prepared& p, uint32_t first, uint32_t end,
                   std::vector<std::unique_ptr<Environment>>* envs) {
  uint32_t nextId = 0;
  for (uint32_t e = 0; e < end; ++e) {
    Mesh mesh;
    Status s = MeshScene(p.part.scene, p.pieces[e], p.patchSize, kMaxPatches, &mesh);
    if (!s.ok()) return Status::Error("vismask: --patch-size: " + s.message());
    // Twins in the environment of their originals, after all of its patches.
    AddTwins(p.twins, &mesh);
    if (mesh.patches.size() > kMaxPatches)
      return Status::Error("vismask: --patch-size: the mesh needs " +
                           std::to_string(mesh.patches.size()) +
                           " patches with both sides, more than the limit of " +
                           std::to_string(kMaxPatches));
    for (Patch& patch : mesh.patches) patch.globalId += nextId;
    nextId += static_cast<uint32_t>(mesh.patches.size());
    if (e < first) continue;
    TextureMesh(p.part.scene, p.textures, &mesh);
    if (p.smooth) MarkSmoothVertices(p.scene, p.part, p.tolerance, &mesh);
    std::vector<uint32_t> ids(mesh.patches.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    envs->push_back(std::make_unique<Environment>());
    envs->back()->Prepare(p.grid, e, mesh, ids, p.envOptions);
  }
  return Status::Ok();
}

// Which scene textures environments [first, first + count) show: those of
// the textured materials of their polygon pieces that have uv.
std::vector<uint8_t> TexturesUsed(const Prepared& p, uint32_t first, uint32_t count) {
  std::vector<uint8_t> used(p.textures.images.size(), 0);
  for (uint32_t e = first; e < first + count; ++e)
    for (uint32_t i : p.pieces[e]) {
      const Polygon& poly = p.part.scene.polygons[i];
      uint32_t t = p.textures.ofMaterial[poly.material];
      if (t != kNoTexture && !poly.uv.empty()) used[t] = 1;
    }
  return used;
}

void PrintWarnings(const SceneTextures& t) {
  for (const std::string& w : t.warnings) os::PrintErr("%s\n", w.c_str());
}

// Init: load, partition, mesh and measure this rank's environments, check
// the memory budget, then make the arenas, build, and open the output files
// under temporary names. Heap allocation is allowed here only.
int Init(Render* r) {
  const Options& o = r->options;
  PfmImage ref;
  PgmImage mask;  // --exclude: checked here too, before any output exists
  Prepared p;
  auto load = [&]() -> int {
    // The reference image, read (heap, init) first: a bad one is refused
    // before the scene is loaded and built.
    if (r->isRoot() && !o.reference.empty()) {
      Status s = ReadPfm(o.reference, &ref);
      if (!s.ok()) return FailInit(r, Status::Error("vismask: --reference: " + s.ToString()));
      if (ref.width != o.width || ref.height != o.height)
        return FailInit(r, Status::Error("vismask: --reference: " + o.reference + " is " +
                                         std::to_string(ref.width) + "x" + std::to_string(ref.height) +
                                         ", the image is " + std::to_string(o.width) + "x" +
                                         std::to_string(o.height) + " (--width, --height)"));
    }
    if (r->isRoot() && !o.exclude.empty()) {
      Status s = ReadPgm(o.exclude, &mask);
      if (!s.ok()) return FailInit(r, Status::Error("vismask: --exclude: " + s.ToString()));
      if (mask.width != o.width || mask.height != o.height)
        return FailInit(r, Status::Error("vismask: --exclude: " + o.exclude + ": is " +
                                         std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                                         ", the image is " + std::to_string(o.width) + "x" +
                                         std::to_string(o.height)));
    }
    Status s = PrepareScene(o, &p);
    if (!s.ok()) return FailInit(r, s);
    for (int a = 0; a < 3; ++a) r->options.envs[a] = p.grid.n[a];  // --envs auto's shape
    if (o.roundWorkAuto) r->options.roundWork = p.roundWork;
    r->envGrid = p.grid;
    // Emitters that light nothing (a face wound the wrong way): one line each.
    if (r->isRoot())
      for (const std::string& w : EmitterWarnings(p.scene)) os::PrintErr("%s\n", w.c_str());
    if (r->isRoot()) PrintWarnings(p.textures);
    r->numPolygons = p.scene.polygons.size();
    r->patchSize = p.patchSize;
    r->layout = EnvsOfRank(static_cast<uint32_t>(p.grid.count()), r->transport->size(), r->transport->rank());
    s = PrepareEnvs(p, r->layout.first, r->layout.first + r->layout.count, &r->envs);
    if (!s.ok()) return FailInit(r, s);
    return kExitOk;
  };
  // Every rank reaches this collective, whether its load succeeded or not:
  // each learns the others' status and shared-vertex counts (every block
  // of the exchange is as large as the largest rank's).
  struct LoadReport {
    int64_t code;
    uint64_t shared;
    uint64_t smooth;
    uint64_t twins;
  };
  LoadReport mine{load(), 0, 0, 0};
  for (auto& e : r->envs) {
    mine.shared += e->numSharedVertices();
    mine.smooth += e->smoothVertices().size();
    mine.twins += e->numTwins();
  }
  std::vector<LoadReport> all(static_cast<size_t>(r->transport->size()));
  r->transport->AllGather(&mine, sizeof mine, all.data());
  for (const LoadReport& k : all) {
    if (k.code != kExitOk) return static_cast<int>(k.code);
    r->sharedCapacity = std::max(r->sharedCapacity, k.shared);
    r->anySmooth |= k.smooth > 0;
    r->numTwins += k.twins;
  }
  r->shareRule.tolerance = p.tolerance;
  r->shareRule.origin = p.scene.bounds.lo;
  // A hair below the cosine, so that equal normals share at --crease 0.
  r->shareRule.cosCrease = static_cast<float>(std::cos(o.creaseDeg * 3.14159265358979323846 / 180.0)) - 1e-6f;
  const std::vector<uint8_t> texturesUsed = TexturesUsed(p, r->layout.first, r->layout.count);
  for (const TextureImage& t : p.textures.images)
    r->textureInfo.push_back({t.path, t.width, t.height});
  Arena measure = Arena::Measure();
  r->LayoutRank(measure, p.packetBytes, r->transport->size(), r->isRoot(), p.textures, texturesUsed);
  uint64_t envBytes = 0;
  for (auto& e : r->envs) envBytes += e->footprint().total;
  uint64_t need = envBytes + ArenaRoundUp(measure.used());
  r->predictedBytes = need;
  // The budget: --mem-budget, or else the host's available memory shared by
  // the ranks on it (a run the machine cannot hold is refused here, not
  // killed by the kernel later).
  uint64_t budget = o.memBudget;
  int onHost = std::max(1, r->transport->ranksOnHost());
  if (budget == 0) budget = os::MemAvailableBytes() / static_cast<uint64_t>(onHost);
  if (budget > 0 && need > budget) {
    // Every rank checks its own need; each that is over says so.
    char whose[200];
    if (o.memBudget > 0)
      std::snprintf(whose, sizeof whose, "the budget of %llu bytes",
                    static_cast<unsigned long long>(budget));
    else
      std::snprintf(whose, sizeof whose,
                    "the memory available to it, %llu bytes (MemAvailable over %d rank%s on this "
                    "host; --mem-budget sets another budget)",
                    static_cast<unsigned long long>(budget), onHost, onHost > 1 ? "s" : "");
    os::PrintErr("vismask: --mem-budget: rank %d needs %llu bytes (environment arenas %llu + rank "
                 "buffers %llu), more than %s\n",
                 r->transport->rank(), static_cast<unsigned long long>(need),
                 static_cast<unsigned long long>(envBytes),
                 static_cast<unsigned long long>(ArenaRoundUp(measure.used())), whose);
    return kExitUsage;
  }
  // The system may refuse what the budget allowed (no --mem-budget, ulimit
  // -v, overcommit off): a user error naming the bytes, not a CHECK.
  auto refused = [&](const char* what, uint64_t bytes) {
    os::PrintErr("vismask: rank %d: the system refused %llu bytes for %s (this rank needs %llu "
                 "in all); lower --width/--height, --envs, --round-shots or run on more ranks\n",
                 r->transport->rank(), static_cast<unsigned long long>(bytes), what,
                 static_cast<unsigned long long>(need));
    return kExitUsage;
  };
  for (auto& e : r->envs) {
    if (!e->Build()) return refused("an environment's arena", e->footprint().total);
    r->envPtrs.push_back(e.get());
  }

  if (o.hasCamera) {
    r->camera = o.camera;
  } else {
    r->hasSide = true;
    r->sideChosen = !o.hasView;
    r->side = o.hasView ? o.view : ChooseViewSide(p.scene);
    r->camera = SideCamera(p.scene.bounds, r->side);
  }
  if (!MakeView(r->camera, o.width, o.height, &r->view))
    return FailInit(r, Status::Error("vismask: --camera: degenerate camera"));

  if (!Arena::Reserve(measure.used(), &r->rankArena))
    return refused("the rank's exchange and output buffers", ArenaRoundUp(measure.used()));
  r->LayoutRank(r->rankArena, p.packetBytes, r->transport->size(), r->isRoot(), p.textures,
                texturesUsed);
  if (!r->isRoot()) return kExitOk;
  for (size_t i = 0; i < r->reference.size(); ++i) r->reference[i] = ref.pixels[i];
  for (size_t i = 0; i < r->exclude.size(); ++i) {
    r->exclude[i] = mask.pixels[i] != 0;
    r->excludedPixels += r->exclude[i];
  }

  char why[os::kWhyBytes];
  if (!os::MakeDirs(o.outDir.c_str(), why)) {
    os::PrintErr("vismask: --out: %s\n", why);
    return kExitOutput;
  }
  if (!r->outLock.Acquire(o.outDir.c_str(), why)) {
    os::PrintErr("vismask: --out: %s\n", why);
    return kExitUsage;
  }
  for (int f = 0; f < kNumOutputs; ++f) {
    std::string path = o.outDir + "/" + kOutputNames[f];
    if (!r->files[f].Open(path.c_str(), why)) {
      os::PrintErr("vismask: %s\n", why);
      return kExitOutput;
    }
  }
  r->convergence = TextWriter(&r->files[kConvergenceCsv], r->convBuffer);
  return kExitOk;
}

}  // namespace vismask::run
