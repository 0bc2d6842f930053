// Init: the scene prepared (src/app/prepare.cpp), the memory budget checked,
// the arenas measured and made, the camera set, the outputs opened (run.h).
#include "run.h"

namespace vismask::run {

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

namespace {

// The memory budget of a rank's init (--mem-budget, or its share of the
// host's), how messages name it, and what rank 0 holds for the reference.
struct InitBudget {
  uint64_t budget = 0;
  char whose[200] = "";
  uint64_t referenceBytes = 0;  // the reference image and the mask, all through init
};

InitBudget BudgetOf(const RunState& r) {
  const Options& o = r.options;
  InitBudget b;
  // The budget: --mem-budget, or else the host's available memory shared by
  // the ranks on it (a run the machine cannot hold is refused here, not
  // killed by the kernel later). It covers init's own peak.
  b.budget = o.memBudget;
  int onHost = std::max(1, r.transport->ranksOnHost());
  if (b.budget == 0) b.budget = os::MemAvailableBytes() / static_cast<uint64_t>(onHost);
  if (o.memBudget > 0)
    std::snprintf(b.whose, sizeof b.whose, "the budget of %llu bytes",
                  static_cast<unsigned long long>(b.budget));
  else
    std::snprintf(b.whose, sizeof b.whose,
                  "the memory available to it, %llu bytes (MemAvailable over %d rank%s on this "
                  "host; --mem-budget sets another budget)",
                  static_cast<unsigned long long>(b.budget), onHost, onHost > 1 ? "s" : "");
  // Rank 0 holds the reference image and the mask all through init.
  b.referenceBytes = r.isRoot() ? (o.reference.empty() ? 0 : uint64_t(o.width) * o.height * 12) +
                                      (o.exclude.empty() ? 0 : uint64_t(o.width) * o.height)
                                : 0;
  return b;
}

// --reference and --exclude read and checked on rank 0 (kExitOk if fine).
int ReadReferenceImages(RunState* r, PfmImage* ref, PgmImage* mask) {
  const Options& o = r->options;
  // The reference image, read (heap, init) first: a bad one is refused
  // before the scene is loaded and built.
  if (r->isRoot() && !o.reference.empty()) {
    Status s = ReadPfm(o.reference, ref);
    if (!s.ok()) return FailInit(r, Status::Error("vismask: --reference: " + s.ToString()));
    if (ref->width != o.width || ref->height != o.height)
      return FailInit(r,
                      Status::Error("vismask: --reference: " + o.reference + " is " +
                                    std::to_string(ref->width) + "x" + std::to_string(ref->height) +
                                    ", the image is " + std::to_string(o.width) + "x" +
                                    std::to_string(o.height) + " (--width, --height)"));
  }
  if (r->isRoot() && !o.exclude.empty()) {
    Status s = ReadPgm(o.exclude, mask);
    if (!s.ok()) return FailInit(r, Status::Error("vismask: --exclude: " + s.ToString()));
    if (mask->width != o.width || mask->height != o.height)
      return FailInit(r, Status::Error("vismask: --exclude: " + o.exclude + ": is " +
                                       std::to_string(mask->width) + "x" +
                                       std::to_string(mask->height) + ", the image is " +
                                       std::to_string(o.width) + "x" + std::to_string(o.height)));
  }
  return kExitOk;
}

// Load: the scene counted, prepared and cut, this rank's environments
// meshed and prepared, each step against the budget.
int LoadRank(RunState* r, const InitBudget& b, Prepared* p) {
  const Options& o = r->options;
  // Pass 0: the statements counted, so that the parser's arrays are
  // judged against the budget before they exist.
  p->clock.report = r->isRoot() && !o.quiet && !o.initAgain;
  Status s = CountScene(o, p);
  if (!s.ok()) return FailInit(r, s);
  const uint64_t held = b.referenceBytes;
  if (b.budget > 0 && p->info.ParserBytes() + held + kInitBaseBytes > b.budget) {
    os::PrintErr(
        "vismask: --mem-budget: rank %d needs %llu bytes at init to read the scene "
        "(%llu vertices, %llu texture coordinates and %llu normals), more than %s\n",
        r->transport->rank(),
        static_cast<unsigned long long>(p->info.ParserBytes() + held + kInitBaseBytes),
        static_cast<unsigned long long>(p->info.vertices),
        static_cast<unsigned long long>(p->info.uvs),
        static_cast<unsigned long long>(p->info.normals), b.whose);
    return kExitUsage;
  }
  r->rankEnvs = EnvsOfRank(static_cast<uint32_t>(o.envs[0] * o.envs[1] * o.envs[2]),
                           r->transport->size(), r->transport->rank());
  p->budget = b.budget;
  p->held = held;
  p->overBudget = [r, &b](uint64_t need, const char* what) {
    os::PrintErr("vismask: --mem-budget: rank %d needs %llu bytes at init %s, more than %s\n",
                 r->transport->rank(), static_cast<unsigned long long>(need), what, b.whose);
  };
  s = PrepareScene(o, p, r->rankEnvs.first, r->rankEnvs.first + r->rankEnvs.count, r->isRoot());
  // (An error with no text: over the budget, which this rank has said.)
  if (!s.ok()) return s.message().empty() ? kExitUsage : FailInit(r, s);
  for (int a = 0; a < 3; ++a) r->options.envs[a] = p->grid.n[a];  // --envs auto's shape
  if (o.roundWorkAuto) r->options.roundWork = p->roundWork;
  r->envGrid = p->grid;
  // Emitters that light nothing (a face wound the wrong way): one line each.
  if (r->isRoot() && !o.initAgain)
    for (const std::string& w : p->emitterWarnings) os::PrintErr("%s\n", w.c_str());
  if (r->isRoot() && !o.initAgain) PrintWarnings(p->textures);
  r->numPolygons = p->info.numPolygons;
  r->patchSize = p->patchSize;
  // Before meshing: the pieces and a bound on the meshes and staged
  // copies (the arenas are not known yet).
  const uint64_t early = p->InitPeak(r->rankEnvs.first, r->rankEnvs.first + r->rankEnvs.count,
                                     r->isRoot(), 0, 0, held);
  if (b.budget > 0 && early > b.budget) {
    os::PrintErr(
        "vismask: --mem-budget: rank %d needs %llu bytes at init (its pieces of the "
        "scene and a bound on meshing its %llu patches; the arenas come on top), more "
        "than %s\n",
        r->transport->rank(), static_cast<unsigned long long>(early),
        static_cast<unsigned long long>(OwnPatches(*p)), b.whose);
    return kExitUsage;
  }
  s = PrepareEnvs(*p, r->rankEnvs.first, r->rankEnvs.first + r->rankEnvs.count, &r->envs);
  if (!s.ok()) return FailInit(r, s);
  return kExitOk;
}

// The light of every environment's emitters and the transit masks: this
// rank's environments cast theirs, every rank gets all. Collective.
void BuildForeignLight(RunState* r, const EnvGrid& envGrid) {
  if (r->foreignCounts.empty()) return;
  const int ranks = r->transport->size();
  const uint32_t total = r->rankEnvs.total;
  r->foreign.Build(
      r->foreignStaged, envGrid, r->options.outside,
      [&](uint32_t env) { return RankOfEnv(env, total, ranks); },
      [&](int rank) { return EnvsOfRank(total, ranks, rank).first; });
  std::vector<EmitterRecord>().swap(r->foreignStaged);
  for (size_t k = 0; k < r->envPtrs.size(); ++k) {
    Environment& env = *r->envPtrs[k];
    env.UncountedOnGrid([&](const Grid& grid) {
      r->foreign.Cast(env.index(), static_cast<uint32_t>(k), grid, env.rayEpsilon(),
                      [&](uint32_t i) { return env.twinOf(i); });
    });
  }
  Span<float> mine = r->foreign.mine();
  r->transport->AllGather(mine.data(), mine.bytes(), r->foreign.all().data());
  Span<float> sun = r->foreign.sunMine();  // empty without --sun, as on every rank
  if (!sun.empty()) r->transport->AllGather(sun.data(), sun.bytes(), r->foreign.sunAll().data());
}

// Several environments gathering every environment's emitters
// (foreign_light.h): every rank's emitter patches, each rank's block
// padded to `most`, into r->foreignStaged in global id order, and the
// counts the light and masks need. Collective (every rank has the same
// options and environment count, so all or none come here).
int GatherEmitters(RunState* r, uint64_t most) {
  const Options& o = r->options;
  if (r->rankEnvs.total <= 1 || !GathersForeign(o) || (most == 0 && !o.outside.HasSun()))
    return kExitOk;
  const int ranks = r->transport->size();
  std::vector<EmitterRecord> mine, all(most * size_t(ranks));
  AppendEmitters(r->envs, &mine);
  const size_t real = mine.size();
  mine.resize(most);
  for (size_t n = real; n < mine.size(); ++n) mine[n].env = kNoPatch;  // padding
  r->transport->AllGather(mine.data(), mine.size() * sizeof(EmitterRecord), all.data());
  std::vector<EmitterRecord>& staged = r->foreignStaged;
  for (const EmitterRecord& e : all)
    if (e.env != kNoPatch) staged.push_back(e);
  r->foreignCounts = ForeignCountsOf(o, r->rankEnvs.total, ranks, r->rankEnvs.perRank, &staged);
  return kExitOk;
}

// Every rank reaches this collective, whether its load succeeded or not:
// each learns the others' status and shared-vertex counts (every block
// of the exchange is as large as the largest rank's). The first failing
// rank's code, or kExitOk; *exportMesh: the whole mesh's counts.
int GatherLoads(RunState* r, int code, GlbMesh* exportMesh) {
  struct LoadReport {
    int64_t code;
    uint64_t shared;
    uint64_t smooth;
    uint64_t twins;
    uint64_t vertices;   // --export: lattice vertices
    uint64_t triangles;  // and triangles (a quad patch gives two)
    uint64_t emitters;   // emitter patches (GatherEmitters)
  };
  LoadReport mine{code, 0, 0, 0, 0, 0, 0};
  uint64_t emitters = 0;  // the most emitter patches a rank holds
  for (auto& e : r->envs) {
    for (const Patch& p : e->preparedPatches()) mine.emitters += Emits(p) ? 1 : 0;
    mine.shared += e->lattice().numShared();
    mine.smooth += e->lattice().smoothVertices().size();
    mine.twins += e->numTwins();
    mine.vertices += e->footprint().numVertices;
    mine.triangles += e->footprint().numTriangles;
  }
  std::vector<LoadReport> all(static_cast<size_t>(r->transport->size()));
  r->transport->AllGather(&mine, sizeof mine, all.data());
  for (const LoadReport& k : all) {
    if (k.code != kExitOk) return static_cast<int>(k.code);
    r->sharedCapacity = std::max(r->sharedCapacity, k.shared);
    r->anySmooth |= k.smooth > 0;
    r->numTwins += k.twins;
    exportMesh->vertices += k.vertices;
    exportMesh->triangles += k.triangles;
    emitters = std::max(emitters, k.emitters);
  }
  return GatherEmitters(r, emitters);
}

// Rank 0's output directory: made, locked, an interrupted commit finished,
// killed runs' temporaries removed, the outputs opened under temporary names.
int OpenOutputs(RunState* r) {
  const Options& o = r->options;
  char why[os::kWhyBytes];
  if (!os::MakeDirs(o.outDir.c_str(), why)) {
    os::PrintErr("vismask: --out: %s\n", why);
    return kExitOutput;
  }
  if (!r->outLock.Acquire(o.outDir.c_str(), why)) {
    os::PrintErr("vismask: --out: %s\n", why);
    // Another run's directory is a usage error; a lock file that cannot
    // be made (read-only, a directory or a link in its place) is an output
    // that cannot be written.
    return r->outLock.inUse() ? kExitUsage : kExitOutput;
  }
  // A commit that a killed run left half done is finished first: the folder
  // then holds that run's whole set, as its run.json lists it.
  int renamed = 0;
  const int finished = os::FinishInterruptedCommit(o.outDir.c_str(), &renamed, why);
  if (finished < 0) {
    os::PrintErr("vismask: --out: %s\n", why);
    return kExitOutput;
  }
  if (finished > 0)
    os::PrintErr(
        "vismask: warning: --out: finished the commit an interrupted run left in '%s' (%d "
        "file%s renamed)\n",
        o.outDir.c_str(), renamed, renamed == 1 ? "" : "s");
  // Temporary files of runs that were killed (SIGKILL, a power cut): they
  // never look complete, but pile up. Those whose pid is gone are removed,
  // with one line.
  int stale = 0;
  char staleFirst[os::kMaxPath + 256] = "";
  auto removeStale = [&](const std::string& path) {
    stale += os::RemoveStaleTemporaries(path.c_str(), stale == 0 ? staleFirst : nullptr,
                                        sizeof staleFirst);
  };
  for (int f = 0; f < kNumOutputs; ++f) removeStale(o.outDir + "/" + kOutputNames[f]);
  removeStale(o.outDir + "/.vismask.commit");
  if (!o.exportPath.empty()) removeStale(o.exportPath);
  if (stale > 0)
    os::PrintErr("vismask: warning: removed %d temporary file%s that killed runs left (%s%s)\n",
                 stale, stale == 1 ? "" : "s", staleFirst, stale > 1 ? ", ..." : "");
  for (int f = 0; f < kNumOutputs; ++f) {
    std::string path = o.outDir + "/" + kOutputNames[f];
    if (!r->files[f].Open(path.c_str(), why)) {
      os::PrintErr("vismask: %s\n", why);
      return kExitOutput;
    }
  }
  if (!o.exportPath.empty() && !r->exportFile.Open(o.exportPath.c_str(), why)) {
    os::PrintErr("vismask: --export: %s\n", why);
    return kExitOutput;
  }
  r->convergence = TextWriter(&r->files[kConvergenceCsv], r->convBuffer);
  return kExitOk;
}

}  // namespace

CameraChoice ChooseCamera(const Options& o, const Prepared& p) {
  CameraChoice c;
  if (o.hasCamera) {
    c.camera = o.camera;
  } else if (!o.hasView && p.scene.camera.has) {
    // The scene file's own camera (glTF) wins over a chosen side.
    c.fromScene = true;
    c.camera.eye = p.scene.camera.eye;
    c.camera.target = p.scene.camera.target;
    c.camera.up = p.scene.camera.up;
    c.camera.fovyDeg = p.scene.camera.fovyDeg;
  } else {
    c.hasSide = true;
    c.sideChosen = !o.hasView;
    c.side = o.hasView ? o.view : p.side;
    c.camera = SideCamera(p.scene.bounds, c.side);
    // Where the sides see mostly back faces or one wall: a view from inside.
    c.viewProbed = p.viewProbed && !o.hasView;
    c.viewChoice = p.view;
    if (c.viewProbed && p.view.inside) {
      c.hasSide = false;
      c.inside = true;
      c.camera = InsideCamera(p.scene.bounds, p.view.candidate);
    }
  }
  return c;
}

// Init: load, partition, mesh and measure this rank's environments, check
// the memory budget, then make the arenas, build, and open the output files
// under temporary names. Heap allocation is allowed here only.
int Init(RunState* r) {
  const Options& o = r->options;
  PfmImage ref;
  PgmImage mask;  // --exclude: checked here too, before any output exists
  Prepared p;
  const InitBudget b = BudgetOf(*r);
  const uint64_t budget = b.budget;
  int code = ReadReferenceImages(r, &ref, &mask);
  if (code == kExitOk) code = LoadRank(r, b, &p);
  GlbMesh exportMesh;
  code = GatherLoads(r, code, &exportMesh);
  if (code != kExitOk) return code;
  // --export: the file's size follows from the mesh; a .glb holds 4 GiB
  // and 32-bit indices.
  if (!o.exportPath.empty() && (exportMesh.triangles == 0 || exportMesh.vertices >= 0xffffffffull ||
                                GlbMaxFileBytes(exportMesh) > kGlbMaxBytes)) {
    std::string why = exportMesh.triangles == 0
                          ? "the mesh has no triangles"
                          : "the mesh's " + std::to_string(exportMesh.vertices) + " vertices and " +
                                std::to_string(exportMesh.triangles) + " triangles need up to " +
                                std::to_string(GlbMaxFileBytes(exportMesh)) +
                                " bytes, more than a .glb holds (4 GiB); raise --patch-size";
    return FailInit(r, Status::Error("vismask: --export: " + o.exportPath + ": " + why));
  }
  r->shareRule.tolerance = p.tolerance;
  r->shareRule.origin = p.scene.bounds.lo;
  // A hair below the cosine, so that equal normals share at --crease 0.
  r->shareRule.cosCrease =
      static_cast<float>(std::cos(o.creaseDeg * 3.14159265358979323846 / 180.0)) - 1e-6f;
  const std::vector<uint8_t> texturesUsed = TexturesUsed(p, r->rankEnvs.first, r->rankEnvs.count);
  for (const TextureImage& t : p.textures.images)
    r->textureInfo.push_back({t.path, t.width, t.height});
  Arena measure = Arena::Measure();
  r->LayoutRank(measure, p.packetBytes, r->transport->size(), r->isRoot(), p.textures,
                texturesUsed);
  r->LayoutSkyMap(measure, p.outside);
  uint64_t envBytes = 0;
  for (auto& e : r->envs) envBytes += e->footprint().total;
  uint64_t need = envBytes + ArenaRoundUp(measure.used());
  r->predictedBytes = need;
  // Init at its peak: the staged copies of the environments with their
  // arenas (or, earlier, the passes or the meshing), whichever is larger.
  r->initPeakBytes =
      p.InitPeak(r->rankEnvs.first, r->rankEnvs.first + r->rankEnvs.count, r->isRoot(), envBytes,
                 ArenaRoundUp(measure.used()), b.referenceBytes);
  if (budget > 0 && std::max(need, r->initPeakBytes) > budget) {
    // Every rank checks its own need; each that is over says so.
    os::PrintErr(
        "vismask: --mem-budget: rank %d needs %llu bytes (environment arenas %llu + rank "
        "buffers %llu; %llu at the peak of init), more than %s\n",
        r->transport->rank(), static_cast<unsigned long long>(std::max(need, r->initPeakBytes)),
        static_cast<unsigned long long>(envBytes),
        static_cast<unsigned long long>(ArenaRoundUp(measure.used())),
        static_cast<unsigned long long>(r->initPeakBytes), b.whose);
    return kExitUsage;
  }
  // What init no longer needs goes before the arenas are made.
  p.part = Partition();
  p.scene.polygons = std::vector<Polygon>();
  p.info.held.reset();  // a glTF scene
  p.pieces = std::vector<std::vector<uint32_t>>();
  // The system may refuse what the budget allowed (no --mem-budget, ulimit
  // -v, overcommit off): a user error naming the bytes, not a CHECK.
  auto refused = [&](const char* what, uint64_t bytes) {
    os::PrintErr(
        "vismask: rank %d: the system refused %llu bytes for %s (this rank needs %llu "
        "in all); lower --width/--height, --envs, --round-shots or run on more ranks\n",
        r->transport->rank(), static_cast<unsigned long long>(bytes), what,
        static_cast<unsigned long long>(need));
    return kExitUsage;
  };
  const double gridStart = os::Seconds();
  for (auto& e : r->envs) {
    if (!e->Build()) return refused("an environment's arena", e->footprint().total);
    r->envPtrs.push_back(e.get());
  }
  p.clock.Done("grid and arenas", os::Seconds() - gridStart);
  r->initStages = p.clock.stages;

  r->cam = ChooseCamera(o, p);
  if (!MakeView(r->cam.camera, o.width, o.height, &r->view))
    return FailInit(r, Status::Error("vismask: --camera: degenerate camera"));

  if (!Arena::Reserve(measure.used(), &r->rankArena))
    return refused("the rank's exchange and output buffers", ArenaRoundUp(measure.used()));
  r->LayoutRank(r->rankArena, p.packetBytes, r->transport->size(), r->isRoot(), p.textures,
                texturesUsed);
  // --sky FILE.hdr: the map's texels into the rank's arena, one copy that
  // its environments read (their options share the map); the heap's go.
  if (SkyMap* map = p.outside.skyMap.get()) {
    Span<float> texels = r->LayoutSkyMap(r->rankArena, p.outside);
    std::copy(map->staged.begin(), map->staged.end(), texels.begin());
    map->texels = texels;
    std::vector<float>().swap(map->staged);
  }
  BuildForeignLight(r, p.grid);
  r->envFb.Clear();  // kept clear between uses (RenderImage clears only what it drew)
  if (!r->isRoot()) return kExitOk;
  for (size_t i = 0; i < r->reference.size(); ++i) r->reference[i] = ref.pixels[i];
  for (size_t i = 0; i < r->exclude.size(); ++i) {
    r->exclude[i] = mask.pixels[i] != 0;
    r->excludedPixels += r->exclude[i];
  }

  return OpenOutputs(r);
}

}  // namespace vismask::run
