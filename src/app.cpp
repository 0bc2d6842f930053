#include "vismask/app.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "vismask/display.h"
#include "vismask/emitter_check.h"
#include "vismask/environment.h"
#include "vismask/image_io.h"
#include "vismask/mesh.h"
#include "vismask/options.h"
#include "vismask/partition.h"
#include "vismask/os.h"
#include "vismask/phase.h"
#include "vismask/raster.h"
#include "vismask/scene.h"
#include "vismask/smoothing.h"
#include "vismask/solver.h"
#include "vismask/text_writer.h"
#include "vismask/texture.h"
#include "vismask/transport.h"

namespace vismask {

namespace {

constexpr int kExitOk = 0;
constexpr int kExitOutput = 1;
constexpr int kExitUsage = 2;
constexpr int kExitStalled = 4;  // (3 is the transport's kExitLostRank)
constexpr uint64_t kMaxPatches = 50000000;
constexpr size_t kTextBufferBytes = 64 * 1024;

enum OutputFile { kPng, kPfm, kPatchesCsv, kConvergenceCsv, kRunJson, kNumOutputs };
const char* const kOutputNames[kNumOutputs] = {"image.png", "image.pfm", "patches.csv",
                                               "convergence.csv", "run.json"};

// What rank 0 needs of every environment for run.json, gathered at output.
struct EnvSummary {
  EnergyLedger ledger;
  EnvStats stats;
  // The stated error of patches.csv's b (see ErrorSums).
  double relVarArea;   // sum over patches and channels with b > 0 of area * var / b^2
  double weight;       // sum of the areas counted there
  double bArea[3];     // sum of b * area, as written (with the correction when on)
  double ambientArea[3];  // sum of kd * ambient * area
  uint64_t arenaBytes;
  uint64_t patches;
  uint64_t vertices;
  uint64_t gridCells;
  uint64_t gridRefs;
  uint64_t elementsUsed;     // roots included
  uint64_t elementCapacity;
  uint64_t leaves;
  uint64_t elementDepth;     // the deepest leaf
};

// One row of patches.csv as a rank sends it to rank 0.
struct PatchRecord {
  uint32_t id;
  uint32_t env;
  float c[3];
  float n[3];
  float area;
  float kd[3];
  float ke[3];
  double b[3];
};
constexpr size_t kPatchChunk = 2048;  // records per transfer to rank 0
constexpr int kBandRows = 16;         // framebuffer rows per transfer to rank 0

// Everything a render needs after init, carved from arenas at init.
struct Render {
  Options options;
  std::unique_ptr<Transport> transport;
  RankEnvs layout;
  size_t numPolygons = 0;
  uint64_t numTwins = 0;  // twin patches, all ranks (--two-sided, --two-sided-emitters)
  float patchSize = 0.0f;
  std::vector<std::unique_ptr<Environment>> envs;  // this rank's, made at init
  std::vector<Environment*> envPtrs;
  Camera camera;  // the one used (--camera or a side's)
  bool hasSide = false;  // the camera is a side's: --view or chosen (not --camera)
  bool sideChosen = false;  // chosen by ChooseViewSide (not --view)
  ViewSide side = ViewSide::kFront;
  View view;
  Arena rankArena = Arena::Measure();  // exchange and output buffers of this rank
  ExchangeBuffers exchange;
  Framebuffer fb;
  Framebuffer incoming;  // rank 0 with several ranks: kBandRows rows of another rank's image
  Span<float> reference;  // rank 0 with --reference: the reference image, RGB floats
  Span<uint8_t> exclude;  // rank 0 with --exclude: nonzero where a pixel is left out of the error
  size_t excludedPixels = 0;
  Span<uint8_t> rgb8;
  Span<uint8_t> pngScratch;
  Span<char> convBuffer;
  Span<char> textBuffer;
  Span<PatchRecord> records;
  Span<EnvSummary> summaryMine, summaryAll, summary;  // summary: by environment
  Span<AmbientReport> ambientMine, ambientAll, ambient;
  os::DirLock outLock;  // rank 0: --out is ours until the process ends
  os::OutFile files[kNumOutputs];
  TextWriter convergence;
  double initSeconds = 0.0;
  double ambientB[3] = {0, 0, 0};  // the ambient term of the last image drawn
  // Display values shared across cuts and smoothed polygons (display.h).
  Span<VertexRecord> sharedMine, sharedAll;
  Span<uint32_t> sharedScratch;   // ShareVertices' sort of the smooth records, and those at one point
  uint64_t sharedCapacity = 0;    // the most shared vertices any rank's environments hold
  bool anySmooth = false;         // some rank has smooth vertices
  ShareRule shareRule;
  TextureSet textures;              // the textures this rank's patches show (texture.h)
  // Every scene texture, for run.json (read-only after init).
  struct TextureInfo {
    std::string path;
    uint32_t width, height;
  };
  std::vector<TextureInfo> textureInfo;
  uint64_t predictedBytes = 0;  // this rank's arenas, as measured before they were made

  bool isRoot() const { return transport->rank() == 0; }

  // The rank's own arena: exchange buffers, framebuffer, gathered reports;
  // on rank 0 also the second framebuffer, the 8-bit image, the PNG scratch
  // and the writers' buffers.
  // The textures: a display resource like the framebuffer, so the rank's, and
  // one copy serves all its environments (the solve read them at init only,
  // into each patch's kd); only those its environments use (`used`).
  uint64_t rankExchangeBytes = 0, rankImageBytes = 0, rankOutputBytes = 0, rankTextureBytes = 0;
  void LayoutRank(Arena& arena, uint32_t packetBytes, int ranks, bool root,
                  const SceneTextures& sceneTextures, const std::vector<uint8_t>& used) {
    size_t mark = arena.used();
    auto part = [&](uint64_t* bytes) {
      *bytes += arena.used() - mark;
      mark = arena.used();
    };
    rankExchangeBytes = rankImageBytes = rankOutputBytes = rankTextureBytes = 0;
    exchange.Layout(arena, layout, ranks, packetBytes, ranks > 1 ? 6 * options.roundShots : 0);
    part(&rankExchangeBytes);
    fb.Layout(arena, options.width, options.height, options.aa);
    part(&rankImageBytes);
    records = arena.Alloc<PatchRecord>(kPatchChunk);
    summaryMine = arena.Alloc<EnvSummary>(layout.perRank);
    summaryAll = arena.Alloc<EnvSummary>(size_t(ranks) * layout.perRank);
    summary = arena.Alloc<EnvSummary>(layout.total);
    ambientMine = arena.Alloc<AmbientReport>(layout.perRank);
    ambientAll = arena.Alloc<AmbientReport>(size_t(ranks) * layout.perRank);
    ambient = arena.Alloc<AmbientReport>(layout.total);
    part(&rankOutputBytes);
    // Shared vertices: every rank's block holds sharedCapacity records.
    sharedMine = arena.Alloc<VertexRecord>(sharedCapacity);
    sharedAll = arena.Alloc<VertexRecord>(size_t(ranks) * sharedCapacity);
    sharedScratch = arena.Alloc<uint32_t>(anySmooth ? 2 * size_t(ranks) * sharedCapacity : 0);
    part(&rankImageBytes);
    textures.Layout(arena, sceneTextures, used);
    part(&rankTextureBytes);
    if (!root) return;
    if (ranks > 1) incoming.Layout(arena, options.width, std::min(options.height, kBandRows), options.aa);
    if (!options.reference.empty())
      reference = arena.Alloc<float>(size_t(options.width) * size_t(options.height) * 3);
    if (!options.exclude.empty())
      exclude = arena.Alloc<uint8_t>(size_t(options.width) * size_t(options.height));
    rgb8 = arena.Alloc<uint8_t>(size_t(options.width) * size_t(options.height) * 3);
    part(&rankImageBytes);
    pngScratch = arena.Alloc<uint8_t>(PngScratchBytes(options.width, options.height));
    convBuffer = arena.Alloc<char>(kTextBufferBytes);
    textBuffer = arena.Alloc<char>(kTextBufferBytes);
    part(&rankOutputBytes);
  }
};

// Gathers one fixed-size record per environment from every rank into
// `byEnv`, in environment order (rank blocks are padded to perRank).
template <class T>
void GatherByEnv(Render* r, Span<T> mine, Span<T> all, Span<T> byEnv) {
  r->transport->AllGather(mine.data(), mine.bytes(), all.data());
  int ranks = r->transport->size();
  for (int k = 0; k < ranks; ++k) {
    RankEnvs re = EnvsOfRank(r->layout.total, ranks, k);
    for (uint32_t i = 0; i < re.count; ++i) byEnv[re.first + i] = all[size_t(k) * r->layout.perRank + i];
  }
}

int Fail(const Status& s) {
  std::string text = s.ToString() + "\n";
  os::WriteErr(text.data(), text.size());
  return kExitUsage;
}

// A user error found at init: every rank finds it, rank 0 reports it.
int FailInit(const Render* r, const Status& s) {
  if (r->isRoot()) return Fail(s);
  return kExitUsage;
}

// The init work `render` and `footprint` share: the scene loaded, checked
// and cut into environments. Heap; dropped at the end of init.
struct Prepared {
  Scene scene;
  SceneTextures textures;  // decoded map_Kd images
  EnvGrid grid;
  Partition part;
  float patchSize = 0.0f;
  float tolerance = 0.0f;  // points this close are one: cut and smooth vertices
  bool smooth = true;      // --smooth
  std::vector<std::vector<uint32_t>> pieces;  // polygon pieces of each environment
  TwinOptions twins;  // --two-sided, --two-sided-emitters
  EnvOptions envOptions;
  uint32_t packetBytes = 0;
};

// The most rays one shot traces: Method R's packet bits.
uint32_t RayCap(const Options& o) {
  return o.rayAlloc == Options::RayAlloc::kPower ? o.maxRays : o.rays;
}

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

// The radiosity patches.csv holds for patch i: the solved b, plus kd times
// the ambient term with --correct-unshot on.
double OutputB(const Render& r, const Environment& env, size_t i, int c) {
  double b = env.energy()[i].b[c];
  if (r.options.correctUnshot) b += static_cast<double>(env.patches()[i].kd[c]) * r.ambientB[c];
  return b;
}

// The stated error's sums over one environment's patches: the Monte Carlo
// variance of each b relative to b (area-weighted), b * area, and the
// ambient term's share.
void ErrorSums(const Render& r, const Environment& env, EnvSummary* s) {
  for (size_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    for (int c = 0; c < 3; ++c) {
      double b = OutputB(r, env, i, c);
      s->bArea[c] += b * p.area;
      s->ambientArea[c] += static_cast<double>(p.kd[c]) * r.ambientB[c] * p.area;
      if (b > 0.0) {
        s->relVarArea += p.area * env.energy()[i].var[c] / (b * b);
        s->weight += p.area;
      }
    }
  }
}

PatchRecord RecordOf(const Render& r, const Environment& env, size_t i) {
  const Patch& p = env.patches()[i];
  PatchRecord rec{};
  rec.id = p.globalId;
  rec.env = env.index();
  glm::vec3 c(0.0f);
  for (uint32_t k = 0; k < p.numCorners; ++k) c += p.corner[k];
  c /= static_cast<float>(p.numCorners);
  for (int a = 0; a < 3; ++a) {
    rec.c[a] = c[a];
    rec.n[a] = p.normal[a];
    rec.kd[a] = p.kd[a];
    rec.ke[a] = p.ke[a];
    rec.b[a] = OutputB(r, env, i, a);
  }
  rec.area = p.area;
  return rec;
}

void WriteRecord(TextWriter* w, const PatchRecord& p) {
  w->Printf("%u,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.17g,%.17g,%.17g\n",
            p.id, p.env, p.c[0], p.c[1], p.c[2], p.n[0], p.n[1], p.n[2], p.area, p.kd[0], p.kd[1],
            p.kd[2], p.ke[0], p.ke[1], p.ke[2], p.b[0], p.b[1], p.b[2]);
}

// patches.csv in id order: rank 0's environments, then every other rank's,
// sent to rank 0 in chunks (ids rise with environment and rank).
void WritePatchesCsv(Render* r) {
  Transport* t = r->transport.get();
  uint64_t count = 0;
  for (Environment* env : r->envPtrs) count += env->patches().size();
  if (!r->isRoot()) {
    t->Send(0, &count, sizeof count);
    size_t n = 0;
    for (Environment* env : r->envPtrs) {
      for (size_t i = 0; i < env->patches().size(); ++i) {
        r->records[n++] = RecordOf(*r, *env, i);
        if (n == kPatchChunk) {
          t->Send(0, r->records.data(), n * sizeof(PatchRecord));
          n = 0;
        }
      }
    }
    if (n > 0) t->Send(0, r->records.data(), n * sizeof(PatchRecord));
    return;
  }
  TextWriter w(&r->files[kPatchesCsv], r->textBuffer);
  w.Printf("id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b\n");
  for (Environment* env : r->envPtrs)
    for (size_t i = 0; i < env->patches().size(); ++i) WriteRecord(&w, RecordOf(*r, *env, i));
  for (int src = 1; src < t->size(); ++src) {
    t->Recv(src, &count, sizeof count);
    while (count > 0) {
      size_t n = count < kPatchChunk ? static_cast<size_t>(count) : kPatchChunk;
      t->Recv(src, r->records.data(), n * sizeof(PatchRecord));
      for (size_t i = 0; i < n; ++i) WriteRecord(&w, r->records[i]);
      count -= n;
    }
  }
  w.Flush();
}

// One character of a JSON string as it is written inside the quotes: into
// out (at least 7 bytes); returns the length.
size_t JsonChar(char c, char* out) {
  unsigned char ch = static_cast<unsigned char>(c);
  if (ch == '"' || ch == '\\') {
    out[0] = '\\';
    out[1] = c;
    return 2;
  }
  if (ch < 0x20) return static_cast<size_t>(std::snprintf(out, 7, "\\u%04x", ch));
  out[0] = c;
  return 1;
}

void JsonString(TextWriter* w, const char* s) {
  w->Write("\"", 1);
  char esc[8];
  for (; *s; ++s) w->Write(esc, JsonChar(*s, esc));
  w->Write("\"", 1);
}

// The same, for init-time text on the heap (footprint --json).
std::string JsonQuoted(const std::string& s) {
  std::string q = "\"";
  char esc[8];
  for (char c : s) q.append(esc, JsonChar(c, esc));
  return q + "\"";
}

void JsonTriple(TextWriter* w, const char* name, const double v[3], bool comma) {
  w->Printf("    \"%s\": [%.17g, %.17g, %.17g]%s\n", name, v[0], v[1], v[2], comma ? "," : "");
}

void WriteRunJson(Render* r, const SolveResult& res, float exposure, double outputSeconds) {
  const Options& o = r->options;
  TextWriter w(&r->files[kRunJson], r->textBuffer);
  w.Printf("{\n  \"vismask_version\": 1,\n  \"command\": \"render\",\n  \"scene\": ");
  JsonString(&w, o.scene.c_str());
  w.Printf(",\n  \"out\": ");
  JsonString(&w, o.outDir.c_str());
  w.Printf(",\n  \"options\": {\n");
  w.Printf("    \"patch_size\": %.9g,\n    \"rays\": %u,\n    \"seed\": %llu,\n", r->patchSize,
           RayCap(o), static_cast<unsigned long long>(o.seed));
  w.Printf("    \"ray_alloc\": \"%s\",\n    \"emitted_rays\": %llu,\n    \"min_rays\": %u,\n"
           "    \"max_rays\": %u,\n    \"sampler\": \"%s\",\n    \"ray_budget\": %llu,\n",
           o.rayAlloc == Options::RayAlloc::kPower ? "power" : "fixed",
           static_cast<unsigned long long>(o.emittedRays), o.minRays, o.maxRays,
           o.sobol ? "sobol" : "random", static_cast<unsigned long long>(o.rayBudget));
  w.Printf("    \"stop_unshot\": %.17g,\n    \"max_shots\": %llu,\n    \"max_seconds\": %.17g,\n",
           o.stopUnshot, static_cast<unsigned long long>(o.maxShots), o.maxSeconds);
  w.Printf("    \"width\": %d,\n    \"height\": %d,\n    \"exposure\": %.9g,\n", o.width, o.height,
           exposure);
  w.Printf("    \"exposure_auto\": %s,\n", o.hasExposure ? "false" : "true");
  const Camera& c = r->camera;  // as --camera takes it: eye, target, up, fovy
  w.Printf("    \"camera\": [%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g],\n", c.eye.x,
           c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z, c.fovyDeg);
  // The side the camera frames (null with --camera), and whether it was chosen (no --view).
  if (r->hasSide) w.Printf("    \"view\": \"%s\",\n", ViewSideName(r->side));
  else w.Printf("    \"view\": null,\n");
  w.Printf("    \"view_auto\": %s,\n", r->sideChosen ? "true" : "false");
  w.Printf("    \"envs\": [%d, %d, %d],\n    \"mask_method\": \"%s\",\n", o.envs[0], o.envs[1],
           o.envs[2], MaskMethodName(o.maskMethod));
  w.Printf("    \"mask_res\": %u,\n    \"round_shots\": %u,\n    \"queue\": %u,\n",
           o.maskRes, o.roundShots, o.queue);
  w.Printf("    \"rank_timeout\": %.17g,\n", o.rankTimeout);
  w.Printf("    \"reference\": ");
  if (o.reference.empty()) w.Printf("null");
  else JsonString(&w, o.reference.c_str());
  w.Printf(",\n    \"exclude\": ");
  if (o.exclude.empty()) w.Printf("null");
  else JsonString(&w, o.exclude.c_str());
  w.Printf(",\n    \"error_every\": %llu,\n", static_cast<unsigned long long>(o.errorEvery));
  w.Printf("    \"correct_unshot\": %s,\n", o.correctUnshot ? "true" : "false");
  w.Printf("    \"aa\": %s,\n", o.aa ? "true" : "false");
  w.Printf("    \"smooth\": %s,\n    \"crease\": %.9g,\n", o.smooth ? "true" : "false", o.creaseDeg);
  // Only when on, so that a one-sided run.json is what it was before them.
  if (o.twoSided || o.twoSidedEmitters)
    w.Printf("    \"two_sided\": %s,\n    \"two_sided_emitters\": %s,\n",
             o.twoSided ? "true" : "false", o.twoSidedEmitters ? "true" : "false");
  w.Printf("    \"stop_error\": %.17g\n  },\n", o.stopError);
  size_t patches = 0, vertices = 0, cells = 0, refs = 0;
  for (const EnvSummary& e : r->summary) {
    patches += e.patches;
    vertices += e.vertices;
    cells += e.gridCells;
    refs += e.gridRefs;
  }
  w.Printf("  \"counts\": {\n    \"polygons\": %zu,\n    \"patches\": %zu,\n", r->numPolygons,
           patches);
  if (o.twoSided || o.twoSidedEmitters)  // of `patches`, the reversed copies
    w.Printf("    \"twin_patches\": %llu,\n", static_cast<unsigned long long>(r->numTwins));
  w.Printf("    \"vertices\": %zu,\n    \"environments\": %zu,\n", vertices, r->summary.size());
  w.Printf("    \"ranks\": %d,\n    \"transport\": \"%s\",\n", r->transport->size(),
           r->transport->name());
  w.Printf("    \"grid_cells\": %zu,\n    \"grid_refs\": %zu\n  },\n", cells, refs);
  EnvStats st;
  for (const EnvSummary& e : r->summary) {
    st.shots += e.stats.shots;
    st.foreignShots += e.stats.foreignShots;
    st.rays += e.stats.rays;
    st.maskRays += e.stats.maskRays;
    st.hits += e.stats.hits;
    st.packetsSent += e.stats.packetsSent;
  }
  uint32_t packetBytes = r->exchange.packetBytes;  // 0 with one environment
  w.Printf("  \"result\": {\n    \"stop_reason\": \"%s\",\n    \"rounds\": %llu,\n",
           StopReasonName(res.reason), static_cast<unsigned long long>(res.rounds));
  w.Printf("    \"shots\": %llu,\n    \"local_shots\": %llu,\n    \"foreign_shots\": %llu,\n",
           static_cast<unsigned long long>(res.shots), static_cast<unsigned long long>(st.shots),
           static_cast<unsigned long long>(st.foreignShots));
  w.Printf("    \"rays\": %llu,\n    \"mask_rays\": %llu,\n    \"hits\": %llu,\n",
           static_cast<unsigned long long>(st.rays), static_cast<unsigned long long>(st.maskRays),
           static_cast<unsigned long long>(st.hits));
  w.Printf("    \"packets\": %llu,\n    \"packet_bytes\": %u,\n    \"bytes_sent\": %llu,\n",
           static_cast<unsigned long long>(st.packetsSent), packetBytes,
           static_cast<unsigned long long>(st.packetsSent * packetBytes));
  w.Printf("    \"wait_seconds\": %.6f,\n    \"wait_seconds_max_rank\": %.6f,\n"
           "    \"compute_cpu_seconds\": %.6f,\n    \"critical_cpu_seconds\": %.6f,\n",
           res.waitSeconds, res.waitSecondsMax, res.computeSeconds, res.criticalSeconds);
  w.Printf("    \"unshot_fraction\": %.17g,\n", res.unshotFraction);
  // Sub-patch elements: the pool (roots included), what was used, the
  // leaves drawn, and whether refinement stopped for want of elements.
  uint64_t used = 0, capacity = 0, leaves = 0, depth = 0, splits = 0, refused = 0;
  for (const EnvSummary& e : r->summary) {
    used += e.elementsUsed;
    capacity += e.elementCapacity;
    leaves += e.leaves;
    depth = e.elementDepth > depth ? e.elementDepth : depth;
    splits += e.stats.splits;
    refused += e.stats.refusedSplits;
  }
  w.Printf("    \"elements\": {\"capacity\": %llu, \"used\": %llu, \"leaves\": %llu, "
           "\"splits\": %llu, \"deepest\": %llu, \"refused_splits\": %llu, "
           "\"refinement_stopped\": %s},\n",
           (unsigned long long)capacity, (unsigned long long)used, (unsigned long long)leaves,
           (unsigned long long)splits, (unsigned long long)depth, (unsigned long long)refused,
           refused > 0 ? "true" : "false");
  // Against --reference (null without one): the final image's relative RMSE.
  if (o.reference.empty()) w.Printf("    \"relative_rmse\": null,\n");
  else w.Printf("    \"relative_rmse\": %.17g,\n", res.relativeRmse);
  w.Printf("    \"excluded_pixels\": %zu,\n", r->excludedPixels);  // by --exclude
  w.Printf("    \"error_measurements\": %llu,\n",
           static_cast<unsigned long long>(res.errorMeasurements));
  // The stated error of patches.csv's b: the Monte Carlo standard error
  // relative to b (area-weighted RMS over patches and channels), and the
  // ambient term's share of the total radiosity (what the still-unshot power
  // adds: added to b with --correct-unshot on, missing from it otherwise).
  double relVarArea = 0.0, weight = 0.0, bArea = 0.0, ambientArea = 0.0;
  for (const EnvSummary& e : r->summary) {
    relVarArea += e.relVarArea;
    weight += e.weight;
    for (int c = 0; c < 3; ++c) {
      bArea += e.bArea[c];
      ambientArea += e.ambientArea[c];
    }
  }
  double radiosity = o.correctUnshot ? bArea : bArea + ambientArea;
  w.Printf("    \"ambient\": [%.17g, %.17g, %.17g],\n", r->ambientB[0], r->ambientB[1],
           r->ambientB[2]);
  w.Printf("    \"ambient_share\": %.17g,\n", radiosity > 0.0 ? ambientArea / radiosity : 0.0);
  double mc = weight > 0.0 ? std::sqrt(relVarArea / weight) : 0.0;
  w.Printf("    \"mc_relative_error\": %.17g,\n", mc);
  // The stated error: the Monte Carlo error, the bias estimate of the
  // power not yet shot (BiasEstimate) and that of the power the masks lost
  // (LossEstimate), combined in quadrature.
  w.Printf("    \"bias_estimate\": %.17g,\n", res.biasEstimate);
  w.Printf("    \"loss_estimate\": %.17g,\n", res.lossEstimate);
  w.Printf("    \"stated_error\": %.17g\n  },\n",
           std::sqrt(mc * mc + res.biasEstimate * res.biasEstimate +
                     res.lossEstimate * res.lossEstimate));
  EnergyLedger total;
  for (const EnvSummary& e : r->summary) {
    for (int c = 0; c < 3; ++c) {
      total.emitted[c] += e.ledger.emitted[c];
      total.absorbed[c] += e.ledger.absorbed[c];
      total.escaped[c] += e.ledger.escaped[c];
      total.unshot[c] += e.ledger.unshot[c];
      total.inFlight[c] += e.ledger.inFlight[c];
    }
  }
  w.Printf("  \"energy\": {\n");
  JsonTriple(&w, "emitted", total.emitted, true);
  JsonTriple(&w, "absorbed", total.absorbed, true);
  JsonTriple(&w, "escaped", total.escaped, true);
  JsonTriple(&w, "unshot", total.unshot, true);
  JsonTriple(&w, "in_flight", total.inFlight, true);
  // What the ledger cannot place: power in flight between environments
  // (except Method R's, booked in in_flight), and what masks lost (negative:
  // leaked). Zero up to rounding for one environment and for Method R.
  double residual[3];
  for (int c = 0; c < 3; ++c)
    residual[c] = total.emitted[c] - total.absorbed[c] - total.escaped[c] - total.unshot[c] -
                  total.inFlight[c];
  JsonTriple(&w, "residual", residual, false);
  w.Printf("  },\n  \"timings\": {\n    \"init_seconds\": %.6f,\n", r->initSeconds);
  w.Printf("    \"solve_seconds\": %.6f,\n    \"error_seconds\": %.6f,\n", res.seconds,
           res.errorSeconds);
  w.Printf("    \"output_seconds\": %.6f\n  },\n", outputSeconds);
  w.Printf("  \"memory\": {\n    \"environment_arena_bytes\": [");
  for (size_t i = 0; i < r->summary.size(); ++i)
    w.Printf("%s%llu", i ? ", " : "", static_cast<unsigned long long>(r->summary[i].arenaBytes));
  uint64_t highWater = ArenaRoundUp(r->rankArena.used()), arenas = r->rankArena.capacity();
  for (Environment* e : r->envPtrs) {
    highWater += ArenaRoundUp(e->arenaUsed());
    arenas += e->arenaCapacity();
  }
  uint64_t peak = os::PeakRssBytes(), files = os::FileRssBytes();
  w.Printf("],\n    \"rank0_arena_bytes\": %zu,\n", r->rankArena.capacity());
  // map_Kd textures: rank 0's texels (part of its arena), and every texture
  // of the scene with the 3 bytes a texel each rank showing it holds.
  w.Printf("    \"rank0_texture_bytes\": %llu,\n    \"textures\": [",
           static_cast<unsigned long long>(r->rankTextureBytes));
  for (size_t i = 0; i < r->textureInfo.size(); ++i) {
    const Render::TextureInfo& t = r->textureInfo[i];
    w.Printf("%s{\"path\": ", i ? ", " : "");
    JsonString(&w, t.path.c_str());
    w.Printf(", \"width\": %u, \"height\": %u, \"texel_bytes\": %llu}", t.width, t.height,
             static_cast<unsigned long long>(t.width) * t.height * 3);
  }
  w.Printf("],\n");
  w.Printf("    \"predicted_bytes\": %llu,\n    \"arena_high_water_bytes\": %llu,\n",
           static_cast<unsigned long long>(r->predictedBytes), static_cast<unsigned long long>(highWater));
  w.Printf("    \"file_rss_bytes\": %llu,\n", static_cast<unsigned long long>(files));
  w.Printf("    \"peak_rss_explained\": %.4f,\n",
           peak > 0 ? static_cast<double>(arenas + files) / static_cast<double>(peak) : 0.0);
  w.Printf("    \"peak_rss_bytes\": %llu\n  }\n}\n", static_cast<unsigned long long>(peak));
  w.Flush();
}

// Draws the current solution into rank 0's framebuffer: the ambient term
// from every environment (summed in environment order), each rank's patches
// drawn by that rank, and rank 0 depth-compositing the others'. Collective.
void RenderImage(Render* r) {
  Transport* t = r->transport.get();
  for (uint32_t i = 0; i < r->layout.perRank; ++i) r->ambientMine[i] = AmbientReport{};
  for (size_t i = 0; i < r->envPtrs.size(); ++i) r->ambientMine[i] = AmbientOf(*r->envPtrs[i]);
  GatherByEnv(r, r->ambientMine, r->ambientAll, r->ambient);
  double* ambient = r->ambientB;
  AmbientTerm(r->ambient, ambient);
  r->fb.Clear();
  for (Environment* env : r->envPtrs) env->ComputeVertexRadiosity(ambient);
  if (r->sharedCapacity > 0) {
    Span<Environment* const> envs(r->envPtrs.data(), r->envPtrs.size());
    CollectShared(envs, r->sharedMine);
    t->AllGather(r->sharedMine.data(), r->sharedMine.bytes(), r->sharedAll.data());
    ShareVertices(envs, r->sharedAll, r->sharedScratch, r->shareRule);
  }
  for (Environment* env : r->envPtrs) DrawEnvironment(r->view, *env, ambient, &r->fb, r->textures.textures);
  // The other ranks' framebuffers, a band of rows at a time (rank 0 holds
  // one band), composited in rank order; then the fragments are resolved.
  const Framebuffer& mine = r->fb;
  const size_t w = static_cast<size_t>(mine.width);
  for (int src = 1; src < t->size(); ++src) {
    if (!r->isRoot() && t->rank() != src) continue;
    for (int y = 0; y < mine.height; y += kBandRows) {
      int rows = std::min(kBandRows, mine.height - y);
      size_t first = static_cast<size_t>(y) * w, n = static_cast<size_t>(rows) * w;
      if (r->isRoot()) {
        Framebuffer& in = r->incoming;
        if (mine.aa) {
          t->Recv(src, in.frags.data(), in.frags.subspan(0, n * kFragments).bytes());
          t->Recv(src, in.dropped.data(), in.dropped.subspan(0, n).bytes());
        } else {
          t->Recv(src, in.color.data(), in.color.subspan(0, n).bytes());
          t->Recv(src, in.depth.data(), in.depth.subspan(0, n).bytes());
          t->Recv(src, in.id.data(), in.id.subspan(0, n).bytes());
        }
        CompositeRows(in, y, rows, &r->fb);
      } else if (mine.aa) {
        auto f = mine.frags.subspan(first * kFragments, n * kFragments);
        auto d = mine.dropped.subspan(first, n);
        t->Send(0, f.data(), f.bytes());
        t->Send(0, d.data(), d.bytes());
      } else {
        auto c = mine.color.subspan(first, n);
        auto d = mine.depth.subspan(first, n);
        auto i = mine.id.subspan(first, n);
        t->Send(0, c.data(), c.bytes());
        t->Send(0, d.data(), d.bytes());
        t->Send(0, i.data(), i.bytes());
      }
    }
  }
  if (r->isRoot()) Resolve(&r->fb);
}

// --reference: the image of the solution so far against the reference, on
// rank 0 (the other ranks only help draw it).
class ReferenceProbe : public ErrorProbe {
 public:
  explicit ReferenceProbe(Render* r) : r_(r) {}
  double Measure() override {
    RenderImage(r_);
    if (!r_->isRoot()) return 0.0;
    static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "colour is packed RGB floats");
    Span<const float> image(reinterpret_cast<const float*>(r_->fb.color.data()),
                            r_->fb.color.size() * 3);
    return CompareImages(image, r_->reference, r_->exclude).relativeRmse;
  }

 private:
  Render* r_;
};

// A camera that sees nothing but background, or only the unlit backs of
// one-sided polygons (an open box seen from a closed side), gives a black
// image that looks like a failed solve: say so. Rank 0, output phase: reads
// the resolved framebuffer and allocates nothing.
void WarnIfEmpty(const Framebuffer& fb, bool hasCamera) {
  ImageContent content = InspectImage(fb);
  if (content.litFront) return;
  const char* fix = hasCamera ? "try another --camera, or --view front|back|left|right|top|bottom"
                              : "try --view front|back|left|right|top|bottom, or --camera";
  if (!content.surface)
    os::PrintErr("vismask: warning: the image is all background: the camera sees no surface (%s)\n", fix);
  else
    os::PrintErr("vismask: warning: the image is black: the camera sees no lit front-facing "
                 "surface, only background and the backs of one-sided polygons (%s)\n", fix);
}

int WriteOutputs(Render* r, const SolveResult& res) {
  double start = os::Seconds();
  RenderImage(r);
  WritePatchesCsv(r);
  for (uint32_t i = 0; i < r->layout.perRank; ++i) r->summaryMine[i] = EnvSummary{};
  for (size_t i = 0; i < r->envPtrs.size(); ++i) {
    const Environment& e = *r->envPtrs[i];
    EnvSummary& s = r->summaryMine[i];
    s = EnvSummary{};
    s.ledger = e.ledger();
    s.stats = e.stats();
    ErrorSums(*r, e, &s);
    s.arenaBytes = e.arenaCapacity();
    s.patches = e.patches().size();
    s.vertices = e.vertices().size();
    s.gridCells = e.grid().cellCount();
    s.gridRefs = e.grid().plan().refs;
    s.elementsUsed = e.elementsUsed();
    s.elementCapacity = e.elements().size();
    for (const Element& el : e.elements().subspan(0, e.elementsUsed())) {
      s.leaves += el.child == kNoElement;
      if (el.depth > s.elementDepth) s.elementDepth = el.depth;
    }
  }
  GatherByEnv(r, r->summaryMine, r->summaryAll, r->summary);
  if (!r->isRoot()) return kExitOk;

  WarnIfEmpty(r->fb, r->options.hasCamera);
  float exposure = r->options.hasExposure ? r->options.exposure
                                          : AutoExposure(r->fb.color, r->fb.id, kNoPatch);
  ToneMap(r->fb.color, exposure, r->rgb8);
  char why[os::kWhyBytes] = "";
  // A failed write is remembered by its file and reported by CommitAll with
  // the file's name and the reason; only the PNG encoder fails on its own.
  bool ok = WritePng(&r->files[kPng], r->options.width, r->options.height, r->rgb8, r->pngScratch, why);
  WritePfm(&r->files[kPfm], r->options.width, r->options.height, r->fb.color);
  r->convergence.Flush();
  WriteRunJson(r, res, exposure, os::Seconds() - start);
  // Commit only when every file was written: all outputs are this run's, or
  // none is replaced (run.json, last, marks a complete run).
  if (ok) ok = os::CommitAll(r->files, kNumOutputs, why);
  if (!ok) {
    for (auto& f : r->files) f.Discard();
    os::PrintErr("vismask: cannot write the outputs in '%s': %s\n", r->options.outDir.c_str(), why);
    return kExitOutput;
  }
  return kExitOk;
}

// vismask footprint: every environment's and every rank's arena bytes, by
// part, from the same measuring layout a render uses, without solving.
// The figures `footprint` reports for one way of meshing the scene.
struct FootprintFigures {
  std::vector<std::unique_ptr<Environment>> envs;
  std::vector<Render> probes;  // per rank: its own buffers' layout
  std::vector<uint64_t> rankTotal, rankEnvBytes, rankOwn;
  uint64_t patches = 0, twins = 0, envBytes = 0, total = 0;
};

Status MeasureFootprint(const Options& o, const Prepared& p, FootprintFigures* f) {
  uint32_t total = static_cast<uint32_t>(p.grid.count());
  Status s = PrepareEnvs(p, 0, total, &f->envs);
  if (!s.ok()) return s;
  int ranks = o.ranks;
  f->rankTotal.assign(ranks, 0);
  f->rankEnvBytes.assign(ranks, 0);
  f->rankOwn.assign(ranks, 0);
  f->probes = std::vector<Render>(ranks);
  auto& envs = f->envs;
  for (int k = 0; k < ranks; ++k) {
    Render& r = f->probes[k];
    r.options = o;
    r.layout = EnvsOfRank(total, ranks, k);
    for (int q = 0; q < ranks; ++q) {
      RankEnvs re = EnvsOfRank(total, ranks, q);
      uint64_t shared = 0;
      for (uint32_t e = re.first; e < re.first + re.count; ++e) {
        shared += envs[e]->numSharedVertices();
        r.anySmooth |= !envs[e]->smoothVertices().empty();
      }
      r.sharedCapacity = std::max(r.sharedCapacity, shared);
    }
    Arena measure = Arena::Measure();
    r.LayoutRank(measure, p.packetBytes, ranks, k == 0, p.textures,
                 TexturesUsed(p, r.layout.first, r.layout.count));
    f->rankOwn[k] = ArenaRoundUp(measure.used());
    for (uint32_t e = r.layout.first; e < r.layout.first + r.layout.count; ++e)
      f->rankEnvBytes[k] += envs[e]->footprint().total;
    f->rankTotal[k] = f->rankEnvBytes[k] + f->rankOwn[k];
    f->total += f->rankTotal[k];
  }
  for (const auto& e : envs) {
    f->patches += e->footprint().numPatches;
    f->twins += e->numTwins();
    f->envBytes += e->footprint().total;
  }
  return Status::Ok();
}

int Footprint(const Options& o) {
  Prepared p;
  Status s = PrepareScene(o, &p);
  if (!s.ok()) return Fail(s);
  PrintWarnings(p.textures);
  uint32_t total = static_cast<uint32_t>(p.grid.count());
  FootprintFigures fig;
  s = MeasureFootprint(o, p, &fig);
  if (!s.ok()) return Fail(s);
  // What two-sidedness costs: the same scene measured one-sided.
  FootprintFigures one;
  if (p.twins.any()) {
    Prepared q = p;
    q.twins = TwinOptions{};
    s = MeasureFootprint(o, q, &one);
    if (!s.ok()) return Fail(s);
  }
  const auto& envs = fig.envs;
  const auto& probes = fig.probes;
  const auto& rankTotal = fig.rankTotal;
  const auto& rankEnvBytes = fig.rankEnvBytes;
  const auto& rankOwn = fig.rankOwn;
  int ranks = o.ranks;
  std::string out;
  char line[512];
  auto add = [&](const char* fmt, auto... args) {
    std::snprintf(line, sizeof line, fmt, args...);
    out += line;
  };
  using ull = unsigned long long;
  // One-sided figures: the same as these when nothing is two-sided.
  const FootprintFigures& base = p.twins.any() ? one : fig;
  if (o.json) {
    out += "{\n  \"scene\": " + JsonQuoted(o.scene) + ",\n";
    add("  \"mask_method\": \"%s\",\n  \"packet_size_bytes\": %u,\n", MaskMethodName(o.maskMethod),
        p.packetBytes);
    // What --two-sided / --two-sided-emitters cost against the one-sided
    // mesh (all patches, all ranks; total_bytes: every rank's arenas).
    add("  \"two_sided\": {\"two_sided\": %s, \"two_sided_emitters\": %s, \"patches\": %llu, "
        "\"twin_patches\": %llu, \"one_sided_patches\": %llu, \"environment_arena_bytes\": %llu, "
        "\"one_sided_environment_arena_bytes\": %llu, \"total_bytes\": %llu, "
        "\"one_sided_total_bytes\": %llu, \"extra_bytes\": %lld},\n",
        o.twoSided ? "true" : "false", o.twoSidedEmitters ? "true" : "false", (ull)fig.patches,
        (ull)fig.twins, (ull)base.patches, (ull)fig.envBytes, (ull)base.envBytes, (ull)fig.total,
        (ull)base.total, (long long)fig.total - (long long)base.total);
    out += "  \"environments\": [\n";
    for (uint32_t e = 0; e < total; ++e) {
      const EnvFootprint& f = envs[e]->footprint();
      add("    {\"env\": %u, \"rank\": %d, \"patches\": %llu, \"twin_patches\": %llu, \"grid_cells\": %llu, "
          "\"patch_bytes\": %llu, \"element_bytes\": %llu, \"vertex_bytes\": %llu, \"grid_bytes\": %llu, "
          "\"queue_bytes\": %llu, \"packet_bytes\": %llu, \"texcoord_bytes\": %llu, \"arena_bytes\": %llu}%s\n",
          e, RankOfEnv(e, total, ranks),
          (ull)f.numPatches, (ull)envs[e]->numTwins(), (ull)f.gridCells, (ull)f.patches, (ull)f.elements, (ull)f.vertices,
          (ull)f.grid, (ull)f.queue, (ull)f.packets, (ull)f.textures, (ull)f.total, e + 1 < total ? "," : "");
    }
    out += "  ],\n  \"ranks\": [\n";
    for (int k = 0; k < ranks; ++k) {
      const Render& r = probes[k];
      add("    {\"rank\": %d, \"environments\": %u, \"environment_arena_bytes\": %llu, "
          "\"exchange_bytes\": %llu, \"image_bytes\": %llu, \"output_bytes\": %llu, "
          "\"texture_bytes\": %llu, \"rank_arena_bytes\": %llu, \"total_bytes\": %llu}%s\n",
          k, r.layout.count, (ull)rankEnvBytes[k], (ull)r.rankExchangeBytes, (ull)r.rankImageBytes,
          (ull)r.rankOutputBytes, (ull)r.rankTextureBytes, (ull)rankOwn[k], (ull)rankTotal[k],
          k + 1 < ranks ? "," : "");
    }
    out += "  ]\n}\n";
  } else {
    add("vismask footprint: %s, %u environment%s, %d rank%s, mask %s %s=%u (%u-byte packets), "
        "%dx%d image\n\n",
        o.scene.c_str(), total, total == 1 ? "" : "s", ranks, ranks == 1 ? "" : "s",
        MaskMethodName(o.maskMethod), o.maskMethod == MaskMethod::kR ? "N" : "R",
        o.maskMethod == MaskMethod::kR ? RayCap(o) : o.maskRes, p.packetBytes, o.width, o.height);
    add("%4s %4s %9s %10s %12s %12s %12s %12s %12s %12s %12s %13s\n", "env", "rank", "patches",
        "grid_cells", "patches_B", "elements_B", "vertices_B", "grid_B", "queue_B", "packets_B",
        "texcoord_B", "arena_B");
    for (uint32_t e = 0; e < total; ++e) {
      const EnvFootprint& f = envs[e]->footprint();
      int k = RankOfEnv(e, total, ranks);
      add("%4u %4d %9llu %10llu %12llu %12llu %12llu %12llu %12llu %12llu %12llu %13llu\n", e, k,
          (ull)f.numPatches, (ull)f.gridCells, (ull)f.patches, (ull)f.elements, (ull)f.vertices,
          (ull)f.grid, (ull)f.queue, (ull)f.packets, (ull)f.textures, (ull)f.total);
    }
    add("\n%4s %4s %14s %12s %12s %12s %12s %13s\n", "rank", "envs", "env_arenas_B", "exchange_B",
        "image_B", "output_B", "texture_B", "total_B");
    for (int k = 0; k < ranks; ++k) {
      const Render& r = probes[k];
      add("%4d %4u %14llu %12llu %12llu %12llu %12llu %13llu\n", k, r.layout.count, (ull)rankEnvBytes[k],
          (ull)r.rankExchangeBytes, (ull)r.rankImageBytes, (ull)r.rankOutputBytes,
          (ull)r.rankTextureBytes, (ull)rankTotal[k]);
    }
    if (p.twins.any())
      add("\n%s: %llu patches, %llu of them twins (one-sided: %llu); %llu bytes in all ranks' "
          "arenas, %+lld (%+.1f%%) against one-sided\n",
          o.twoSided ? "--two-sided" : "--two-sided-emitters", (ull)fig.patches, (ull)fig.twins,
          (ull)base.patches, (ull)fig.total, (long long)fig.total - (long long)base.total,
          100.0 * (static_cast<double>(fig.total) / static_cast<double>(base.total) - 1.0));
    add("\nbytes are arena reservations (the whole of a solve's memory after init); a rank's\n"
        "process also holds its binary and libraries (see run.json's memory section)\n");
  }
  os::WriteOut(out.data(), out.size());
  return kExitOk;
}

// vismask compare A.pfm B.pfm: the relative RMSE of A against B over all
// pixels and channels, sqrt(sum (a - b)^2 / sum b^2), and the largest
// absolute difference.
int Compare(const Options& o) {
  PfmImage a, b;
  Status s = ReadPfm(o.compareA, &a);
  if (s.ok()) s = ReadPfm(o.compareB, &b);
  if (!s.ok()) return Fail(s);
  if (a.width != b.width || a.height != b.height)
    return Fail(Status::Error("vismask: compare: the images differ in size (" +
                              std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
                              std::to_string(b.width) + "x" + std::to_string(b.height) + ")"));
  PgmImage mask;  // --exclude: its nonzero pixels are left out
  if (!o.exclude.empty()) {
    s = ReadPgm(o.exclude, &mask);
    if (!s.ok()) return Fail(Status::Error("vismask: --exclude: " + s.ToString()));
    if (mask.width != a.width || mask.height != a.height)
      return Fail(Status::Error("vismask: --exclude: " + o.exclude + ": is " +
                                std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                                ", the images are " + std::to_string(a.width) + "x" +
                                std::to_string(a.height)));
  }
  ImageError e = CompareImages(Span<const float>(a.pixels.data(), a.pixels.size()),
                               Span<const float>(b.pixels.data(), b.pixels.size()),
                               Span<const uint8_t>(mask.pixels.data(), mask.pixels.size()));
  char line[256];
  int n = std::snprintf(line, sizeof line, "relative_rmse %.9g\nmax_abs_error %.9g\n", e.relativeRmse,
                        e.maxAbs);
  if (!o.exclude.empty())
    n += std::snprintf(line + n, sizeof line - size_t(n), "excluded_pixels %zu\n", e.excludedPixels);
  os::WriteOut(line, static_cast<size_t>(n));
  return kExitOk;
}

}  // namespace

int Main(int argc, const char* const* argv) {
  SetPhase(Phase::kInit);
  double start = os::Seconds();
  auto r = std::make_unique<Render>();
  Status s = ParseArgs(argc, argv, &r->options);
  if (!s.ok()) return Fail(s);
  if (r->options.help) {
    const char* text = HelpText();
    os::WriteOut(text, std::strlen(text));
    return kExitOk;
  }
  if (r->options.command == "compare") return Compare(r->options);
  if (r->options.command == "footprint") return Footprint(r->options);
  // The pipe transport forks here: every rank carries on from this point.
  r->transport = MakeTransport(
      TransportRequest{r->options.transport, r->options.ranks, r->options.rankTimeout}, &s);
  // An error with no text: another rank (rank 0) reports it.
  if (!r->transport) return s.message().empty() ? kExitUsage : Fail(s);
  int rc = kExitUsage;
  try {
    rc = Init(r.get());
  } catch (const std::bad_alloc&) {
    // Init's heap (the scene, the mesh) is not in the budget: a scene too
    // big to load is refused here, with what this process had reached.
    os::PrintErr("vismask: rank %d: out of memory at init, loading and meshing the scene (peak "
                 "resident %llu bytes); a larger --patch-size, fewer ranks on this host or more "
                 "memory\n",
                 r->transport->rank(), static_cast<unsigned long long>(os::PeakRssBytes()));
  }
  // Every rank learns whether every rank's init succeeded (rank 0 alone
  // opens the outputs) before anyone starts the solve's collectives.
  int32_t mine = rc, all[kMaxRanks] = {};
  CHECK_LE(r->transport->size(), kMaxRanks);  // MakeTransport refuses more
  r->transport->AllGather(&mine, sizeof mine, all);
  for (int k = 0; k < r->transport->size(); ++k) rc = std::max(rc, static_cast<int>(all[k]));
  if (rc != kExitOk) return r->transport->Finish(rc);
  r->initSeconds = os::Seconds() - start;

  SetPhase(Phase::kSolve);
  SolveOptions so;
  so.roundShots = r->options.roundShots;
  so.queueCapacity = r->options.queue;
  so.order = Span<const uint32_t>(r->options.envOrder.data(), r->options.envOrder.size());
  so.stopUnshot = r->options.stopUnshot;
  so.maxShots = r->options.maxShots;
  so.rayBudget = r->options.rayBudget;
  so.maxSeconds = r->options.maxSeconds;
  so.stopError = r->options.stopError;
  so.correctUnshot = r->options.correctUnshot;
  so.quiet = r->options.quiet;
  ReferenceProbe probe(r.get());
  if (!r->options.reference.empty()) so.probe = &probe;
  so.errorEvery = r->options.errorEvery;
  SolveResult res = Solve(Span<Environment* const>(r->envPtrs.data(), r->envPtrs.size()),
                          r->layout, r->transport.get(), &r->exchange, so,
                          r->isRoot() ? &r->convergence : nullptr);
  if (res.reason == StopReason::kStalled) {  // no outputs: the solve did not finish
    if (r->isRoot()) {
      for (auto& f : r->files) f.Discard();
      os::PrintErr("vismask: the solve stalled after %llu shots: %llu rounds without a shot "
                   "while %.3g of the emitted power was unshot or in flight (the admission of "
                   "new records let no environment shoot; try a larger --queue)\n",
                   static_cast<unsigned long long>(res.shots),
                   static_cast<unsigned long long>(r->layout.total), res.unshotFraction);
    }
    return r->transport->Finish(kExitStalled);
  }

  SetPhase(Phase::kOutput);
  rc = WriteOutputs(r.get(), res);
  SetPhase(Phase::kDone);
  rc = r->transport->Finish(rc);
  if (rc == kExitOk && !r->options.quiet && r->isRoot()) {
    char view[64] = "--camera";
    if (r->hasSide)
      std::snprintf(view, sizeof view, "view %s%s", ViewSideName(r->side), r->sideChosen ? " (chosen)" : "");
    os::PrintErr("vismask: %llu shots, %.2f s solve, %s; wrote %s/image.png\n",
                 static_cast<unsigned long long>(res.shots), res.seconds, view, r->options.outDir.c_str());
  }
  return rc;
}

}  // namespace vismask
