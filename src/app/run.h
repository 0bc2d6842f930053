// The render pipeline's shared pieces (internal to src/): the run's state on
// one rank (RunState), what init prepares (Prepared), and the stages that
// src/app/app.cpp (dispatch, compare, Main), src/app/render_init.cpp (init;
// src/app/prepare.cpp and src/app/prepare_envs.cpp its scene work),
// src/output/output.cpp (the image and the outputs), src/output/run_json.cpp (run.json)
// and src/output/footprint.cpp (`vismask footprint`) define.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "vismask/app/options.h"
#include "vismask/core/os.h"
#include "vismask/core/phase.h"
#include "vismask/display/display.h"
#include "vismask/display/raster.h"
#include "vismask/display/smoothing.h"
#include "vismask/output/gltf.h"
#include "vismask/output/image_io.h"
#include "vismask/output/text_writer.h"
#include "vismask/parallel/transport.h"
#include "vismask/scene/emitter_check.h"
#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"
#include "vismask/scene/scene_stream.h"
#include "vismask/scene/texture.h"
#include "vismask/solve/checkpoint.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/partition.h"
#include "vismask/solve/solver.h"

namespace vismask::run {

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
  double relVarArea;      // sum over patches and channels with b > 0 of area * var / b^2
  double weight;          // sum of the areas counted there
  double bArea[3];        // sum of b * area, as written (with the correction when on)
  double ambientArea[3];  // sum of kd * ambient * area
  uint64_t arenaBytes;
  uint64_t work;  // Environment::workSteps at the end
  uint64_t patches;
  uint64_t vertices;
  uint64_t gridCells;
  uint64_t gridRefs;
  uint64_t gridSubGrids;  // top cells with a grid of their own (--sub-grids)
  uint64_t elementsUsed;  // roots included
  uint64_t elementCapacity;
  uint64_t leaves;
  uint64_t elementDepth;  // the deepest leaf
  uint64_t filterSteps;   // the last image's indirect smoothing (Environment::filterSteps)
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
// --export: the chunk each rank streams the .glb's vertices and triangles
// through (a whole number of either: 2048 vertices, 4096 triangles).
constexpr size_t kExportChunkBytes = 2048 * kGlbVertexBytes;
static_assert(kExportChunkBytes % kGlbTriangleBytes == 0, "whole triangles per chunk");

// The camera a render uses, and where it comes from (ChooseCamera).
struct CameraChoice {
  Camera camera;
  bool hasSide = false;     // a side's: --view or chosen (not --camera)
  bool sideChosen = false;  // the side is chosen by ChooseViewSide (not --view)
  bool fromScene = false;   // the scene file's camera (glTF), no --camera or --view
  ViewSide side = ViewSide::kFront;
  bool inside = false;      // an inside candidate's (InsideCamera)
  bool viewProbed = false;  // the sides were probed and no --view given: viewChoice
  ViewChoice viewChoice;
};

// Everything a run needs after init, carved from arenas at init.
struct RunState {
  Options options;
  std::unique_ptr<Transport> transport;
  RankEnvs rankEnvs;
  size_t numPolygons = 0;
  EnvGrid envGrid;        // the environments' grid and its planes (run.json)
  uint64_t numTwins = 0;  // twin patches, all ranks (--two-sided, --two-sided-emitters)
  float patchSize = 0.0f;
  std::vector<std::unique_ptr<Environment>> envs;  // this rank's, made at init
  std::vector<Environment*> envPtrs;
  CameraChoice cam;  // the camera used, and where it came from
  std::vector<std::pair<std::string, double>> initStages;  // InitClock's, for run.json
  View view;
  Arena rankArena = Arena::Measure();  // exchange and output buffers of this rank
  ExchangeBuffers exchange;
  Framebuffer fb;
  Framebuffer incoming;   // rank 0 with several ranks: kBandRows rows of another rank's image
  Framebuffer envFb;      // rank 0, antialiased, holding several environments: one drawn alone
  Span<float> reference;  // rank 0 with --reference: the reference image, RGB floats
  Span<uint8_t> exclude;  // rank 0 with --exclude: nonzero where a pixel is left out of the error
  size_t excludedPixels = 0;
  // Images drawn (RenderImage), for run.json; whether the framebuffer holds
  // the final solution's image already (a --reference measurement after the
  // last round), so that the outputs do not draw it again.
  uint32_t imagesDrawn = 0;
  bool imageCurrent = false;
  Span<uint8_t> rgb8;
  Span<uint8_t> pngScratch;
  Span<char> convBuffer;
  Span<char> textBuffer;
  Span<PatchRecord> records;
  Span<EnvSummary> summaryMine, summaryAll, summary;  // summary: by environment
  Span<AmbientReport> ambientMine, ambientAll, ambient;
  os::DirLock outLock;  // rank 0: --out is ours until the process ends
  os::OutFile files[kNumOutputs];
  // --export FILE.glb (export.cpp): every environment's counts and bounds,
  // the chunk the vertices and triangles stream through, and on rank 0 the
  // file's head; the file itself is committed with the outputs.
  Span<GlbMesh> exportMine, exportAll, exportByEnv;
  Span<uint8_t> exportChunk, exportHead;
  os::OutFile exportFile;
  GlbMesh exportWhole;       // the whole mesh, after the export (rank 0: for run.json)
  uint64_t exportBytes = 0;  // the file's size (rank 0)
  TextWriter convergence;
  // --checkpoint, --resume (checkpoint.h): the writer, and the state resumed from.
  Checkpoints checkpoints;
  SolveState resumeState;
  double initSeconds = 0.0;
  double ambientB[3] = {0, 0, 0};  // the ambient term of the last image drawn
  // Display values shared across cuts and smoothed polygons (display.h).
  Span<VertexRecord> sharedMine, sharedAll;
  Span<uint32_t>
      sharedScratch;            // ShareVertices' sort of the smooth records, and those at one point
  uint64_t sharedCapacity = 0;  // the most shared vertices any rank's environments hold
  bool anySmooth = false;       // some rank has smooth vertices
  ShareRule shareRule;
  // Several environments gathering every environment's emitters
  // (foreign_light.h): the light and the transit masks, their counts, and
  // the emitter records gathered at init (freed once built).
  ForeignLight foreign;
  ForeignLight::Counts foreignCounts;
  std::vector<EmitterRecord> foreignStaged;
  TextureSet textures;  // the textures this rank's patches show (texture.h)
  // Every scene texture, for run.json (read-only after init).
  struct TextureInfo {
    std::string path;
    uint32_t width, height;
  };
  std::vector<TextureInfo> textureInfo;
  uint64_t predictedBytes = 0;  // this rank's arenas, as measured before they were made
  uint64_t initPeakBytes = 0;   // this rank's init at its peak, predicted (heap and arenas)
  // Every rank's memory, gathered at output for run.json.
  struct RankMemory {
    uint64_t predicted, initPeak, peakRss, fileRss, bytesSent;
  };
  RankMemory rankMemory[kMaxRanks] = {};

  bool isRoot() const { return transport->rank() == 0; }

  // The rank's own arena: exchange buffers, framebuffer, gathered reports;
  // on rank 0 also the second framebuffer, the 8-bit image, the PNG scratch
  // and the writers' buffers.
  // The textures: a display resource like the framebuffer, so the rank's, and
  // one copy serves all its environments (the solve read them at init only,
  // into each patch's kd); only those its environments use (`used`).
  uint64_t rankExchangeBytes = 0, rankImageBytes = 0, rankOutputBytes = 0, rankTextureBytes = 0,
           rankExportBytes = 0;
  // --sky FILE.hdr: the rank's copy of the map's texels (none without).
  static Span<float> LayoutSkyMap(Arena& arena, const OutsideLight& lit) {
    return lit.skyMap ? arena.Alloc<float>(size_t{lit.skyMap->width} * lit.skyMap->height * 3)
                      : Span<float>();
  }
  void LayoutRank(Arena& arena, uint32_t packetBytes, int ranks, bool root,
                  const SceneTextures& sceneTextures, const std::vector<uint8_t>& used) {
    size_t mark = arena.used();
    auto part = [&](uint64_t* bytes) {
      *bytes += arena.used() - mark;
      mark = arena.used();
    };
    rankExchangeBytes = rankImageBytes = rankOutputBytes = rankTextureBytes = rankExportBytes = 0;
    // A shot sends at most one packet to each neighbour: an environment
    // sends another rank at most --round-shots packets a round for each of
    // that rank's environments it neighbours (at most 6 and perRank).
    exchange.Layout(arena, rankEnvs, ranks, packetBytes,
                    ranks > 1 ? std::min<uint32_t>(6, rankEnvs.perRank) * options.roundShots : 0,
                    packetBytes > 0 ? 6 * options.roundShots : 0);
    part(&rankExchangeBytes);
    fb.Layout(arena, options.width, options.height, options.aa);
    part(&rankImageBytes);
    records = arena.Alloc<PatchRecord>(kPatchChunk);
    summaryMine = arena.Alloc<EnvSummary>(rankEnvs.perRank);
    summaryAll = arena.Alloc<EnvSummary>(size_t(ranks) * rankEnvs.perRank);
    summary = arena.Alloc<EnvSummary>(rankEnvs.total);
    ambientMine = arena.Alloc<AmbientReport>(rankEnvs.perRank);
    ambientAll = arena.Alloc<AmbientReport>(size_t(ranks) * rankEnvs.perRank);
    ambient = arena.Alloc<AmbientReport>(rankEnvs.total);
    part(&rankOutputBytes);
    // Shared vertices: every rank's block holds sharedCapacity records.
    sharedMine = arena.Alloc<VertexRecord>(sharedCapacity);
    sharedAll = arena.Alloc<VertexRecord>(size_t(ranks) * sharedCapacity);
    sharedScratch = arena.Alloc<uint32_t>(anySmooth ? 2 * size_t(ranks) * sharedCapacity : 0);
    if (!foreignCounts.empty()) foreign.Layout(arena, foreignCounts);
    part(&rankImageBytes);
    textures.Layout(arena, sceneTextures, used);
    part(&rankTextureBytes);
    if (!options.exportPath.empty()) {
      exportMine = arena.Alloc<GlbMesh>(rankEnvs.perRank);
      exportAll = arena.Alloc<GlbMesh>(size_t(ranks) * rankEnvs.perRank);
      exportByEnv = arena.Alloc<GlbMesh>(rankEnvs.total);
      exportChunk = arena.Alloc<uint8_t>(kExportChunkBytes);
      if (root) exportHead = arena.Alloc<uint8_t>(kGlbHeadBytes);
    }
    part(&rankExportBytes);
    if (!root) return;
    if (ranks > 1)
      incoming.Layout(arena, options.width, std::min(options.height, kBandRows), options.aa);
    if (options.aa && rankEnvs.count > 1) envFb.Layout(arena, options.width, options.height, true);
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
void GatherByEnv(RunState* r, Span<T> mine, Span<T> all, Span<T> byEnv) {
  r->transport->AllGather(mine.data(), mine.bytes(), all.data());
  int ranks = r->transport->size();
  for (int k = 0; k < ranks; ++k) {
    RankEnvs re = EnvsOfRank(r->rankEnvs.total, ranks, k);
    for (uint32_t i = 0; i < re.count; ++i)
      byEnv[re.first + i] = all[size_t(k) * r->rankEnvs.perRank + i];
  }
}

// Several environments gathering every environment's emitters
// (foreign_light.h): the emitter patches of `envs` (prepared or built)
// appended to *out, with their environments and local indices.
template <class Envs>
void AppendEmitters(const Envs& envs, std::vector<EmitterRecord>* out) {
  for (const auto& e : envs) {
    Span<const Patch> patches = e->preparedPatches();
    for (uint32_t i = 0; i < patches.size(); ++i)
      if (Emits(patches[i])) out->push_back(EmitterRecord{patches[i], e->index(), i});
  }
}
// *all in global id order, and the counts the light and masks need.
inline ForeignLight::Counts ForeignCountsOf(const Options& o, uint32_t envs, int ranks,
                                            uint32_t perRank, std::vector<EmitterRecord>* all) {
  std::sort(all->begin(), all->end(), [](const EmitterRecord& a, const EmitterRecord& b) {
    return a.patch.globalId < b.patch.globalId;
  });
  const bool sun = o.outside.HasSun();
  if (envs <= 1 || !GathersForeign(o) || (all->empty() && !sun)) return ForeignLight::Counts{};
  return ForeignLight::Count(*all, envs, static_cast<uint32_t>(ranks), perRank, o.foreignMaskRes,
                             sun);
}

inline int Fail(const Status& s) {
  std::string text = s.ToString() + "\n";
  os::WriteErr(text.data(), text.size());
  return kExitUsage;
}

// A user error found at init: every rank finds it, rank 0 reports it.
inline int FailInit(const RunState* r, const Status& s) {
  if (r->isRoot()) return Fail(s);
  return kExitUsage;
}

// The init work `render` and `footprint` share: the scene read in passes
// (scene_stream.h) and cut into environments, of which this rank keeps its
// own pieces and counts every environment's patches. Heap; dropped at the
// end of init.
// Init's stages and their seconds: each that takes over a second
// says so on stderr when `report` (rank 0 without --quiet); run.json lists
// them all (init_stages).
struct InitClock {
  bool report = false;
  std::vector<std::pair<std::string, double>> stages;  // in order, each name once
  // Adds `seconds` to stage `what` (`detail` says what it did).
  void Done(const char* what, double seconds, const std::string& detail = "");
};
// The progress line for a stage: "vismask: init: WHAT took S s (DETAIL)",
// or "" when it took a second or less.
std::string InitStageLine(const char* what, double seconds, const std::string& detail);

struct Prepared {
  mutable InitClock clock;  // PrepareEnvs (const) times its meshing too
  SceneInfo info;           // materials, bounds, statement counts, the loader's warnings
  // objPath, materials and bounds; polygons: the source polygons of this
  // rank's pieces only (for smoothing), sourceIds their indices in the file.
  Scene scene;
  std::vector<uint32_t> sourceIds;
  SceneTextures textures;  // decoded map_Kd images
  OutsideLight outside;    // --sky, --sun, with --sky FILE.hdr's map read
  EnvGrid grid;
  Partition part;               // this rank's pieces (part.source indexes scene.polygons)
  uint32_t first = 0, end = 0;  // the environments this rank holds
  // Every environment: patches (twins included) and lattice vertices, counted.
  std::vector<double> envPatches, envTwins, envVertices;
  std::vector<uint64_t> envPieceBytes;       // held environments: their pieces' heap
  uint32_t idBase = 0;                       // the global id of this rank's first patch
  uint32_t pieceBase = 0;                    // the index of its first piece in the whole partition
  ViewSide side = ViewSide::kFront;          // chosen (without --camera or --view)
  ViewChoice view;                           // the probe's choice, inside or a side
  bool viewProbed = false;                   // whether the probe ran
  std::vector<std::string> emitterWarnings;  // rank 0
  float patchSize = 0.0f;
  float tolerance = 0.0f;                     // points this close are one: cut and smooth vertices
  bool smooth = true;                         // --smooth
  std::vector<std::vector<uint32_t>> pieces;  // polygon pieces of each environment
  TwinOptions twins;                          // --two-sided, --two-sided-emitters
  EnvOptions envOptions;
  uint32_t packetBytes = 0;
  // The budget the passes are held to (0: none), what init holds besides
  // (the reference image), and how a rank says it is over: the passes
  // judge their own arrays, probe and check after pass 1, and their pieces
  // as pass 2 takes them, before holding more than the budget.
  uint64_t budget = 0;
  uint64_t held = 0;
  std::function<void(uint64_t need, const char* what)> overBudget;
  uint64_t textureBytes = 0;  // the decoded textures' heap
  uint64_t checkBytes = 0;    // rank 0: the emitter check's heap (a bound)

  // Bounds, from environment e's counted patches and vertices, on the heap
  // its staged copy (Environment::Prepare, until Build) and its mesh (until
  // staged) take.
  uint64_t StagedBound(uint32_t e) const;
  uint64_t MeshBound(uint32_t e) const;
  // A bound on the heap init holds at its peak on a rank holding
  // environments [first, end), whose arenas take envArenas and rankArena
  // bytes; `held`: what init keeps all along besides (the reference image).
  // The stages: pass 1 and 2 (the parser's arrays, the pieces, the camera's
  // probe, the emitter check), meshing (the pieces, the staged copies, one
  // mesh), building (the pieces' heap, the staged copies and the arenas).
  uint64_t InitPeak(uint32_t first, uint32_t end, bool root, uint64_t envArenas, uint64_t rankArena,
                    uint64_t held) const;
  uint64_t roundWork = 0;  // the automatic --round-work (Options::roundWorkAuto)
};

// What init holds besides the scene and the arenas (the process's strings,
// tables, the transport's and iostream's buffers), a bound.
constexpr uint64_t kInitBaseBytes = uint64_t{4} << 20;

// Environment by environment, the patch limit as meshing each would
// refuse it (with its twins).
Status CheckEnvSizes(const Prepared& p, uint32_t total);

// Pass 0 (scene_stream.h): the statements counted, nothing parsed.
Status CountScene(const Options& o, Prepared* p);
// Passes 1 and 2: the scene parsed and checked, then cut into environments;
// `p` keeps the pieces of environments [first, end). `root`: also the
// emitter check (its warnings in p->emitterWarnings).
Status PrepareScene(const Options& o, Prepared* p, uint32_t first, uint32_t end, bool root);
Status PrepareEnvs(const Prepared& p, uint32_t first, uint32_t end,
                   std::vector<std::unique_ptr<Environment>>* envs);
// The patches (twins included) of the environments p holds.
uint64_t OwnPatches(const Prepared& p);
std::vector<uint8_t> TexturesUsed(const Prepared& p, uint32_t first, uint32_t count);
// --camera, the scene file's own, a side of the box (chosen, or --view),
// or a view from inside where the sides see little: the camera of render
// and of scene-dump.
CameraChoice ChooseCamera(const Options& o, const Prepared& p);
int Init(RunState* r);
void PrintWarnings(const SceneTextures& t);
void WritePatchesCsv(RunState* r);
GlbMesh ExportMeshOf(const Environment& env);
void WriteExport(RunState* r);
void JsonString(TextWriter* w, const char* s);
std::string JsonQuoted(const std::string& s);
void WriteRunJson(RunState* r, const SolveResult& res, float exposure, double outputSeconds);
// run.json's "options" section, from the option table (run_json_options.cpp).
void WriteRunJsonOptions(TextWriter* w, const RunState& r, float exposure);
void RenderImage(RunState* r);
int WriteOutputs(RunState* r, const SolveResult& res);
int Footprint(const Options& o);
// `vismask scene-dump` (scene_dump.cpp): the loaded scene as JSON, and its --help.
int SceneDump(const Options& o);
const char* SceneDumpHelpText();
int Compare(const Options& o);
// --max-seconds's plan and pace (plan_run.cpp). PlanRate: the rays per
// second this machine traces through the scene's grids now, the mean kd
// (at most 0.95) and the patches, over this rank's environments.
struct PlanRate {
  double rate = 0.0, rho = 0.0, patches = 0.0;
};
float PlanPatchSize(const RunState& r, PlanRate* measured);
PlanRate PlanBudget(RunState* r, const PlanRate& known);
bool Paces(const RunState& r);
PaceInput PaceInputOf(const Options& o, const PlanRate& planned, size_t environments);
int Verify(const Options& o);
// The size and CRC-32 of a file; false (with *why) if it cannot be read.
bool SizeAndCrc(const std::string& path, uint64_t* bytes, uint32_t* crc, std::string* why);

// Writes a command's result to standard output; false, having said why on
// stderr ("vismask: cannot write to standard output: ..."), if it did not
// get there: the command then exits with kExitOutput.
inline bool WriteStdout(const char* s, size_t n) {
  char why[os::kWhyBytes];
  if (os::WriteOut(s, n, why)) return true;
  os::PrintErr("vismask: %s\n", why);
  return false;
}

}  // namespace vismask::run
