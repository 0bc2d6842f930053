#include "vismask/app.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "vismask/environment.h"
#include "vismask/image_io.h"
#include "vismask/mesh.h"
#include "vismask/options.h"
#include "vismask/partition.h"
#include "vismask/os.h"
#include "vismask/phase.h"
#include "vismask/raster.h"
#include "vismask/scene.h"
#include "vismask/solver.h"
#include "vismask/text_writer.h"

namespace vismask {

namespace {

constexpr int kExitOk = 0;
constexpr int kExitOutput = 1;
constexpr int kExitUsage = 2;
constexpr uint64_t kMaxPatches = 50000000;
constexpr size_t kTextBufferBytes = 64 * 1024;

enum OutputFile { kPng, kPfm, kPatchesCsv, kConvergenceCsv, kRunJson, kNumOutputs };
const char* const kOutputNames[kNumOutputs] = {"image.png", "image.pfm", "patches.csv",
                                               "convergence.csv", "run.json"};

// Everything a render needs after init, carved from arenas at init.
struct Render {
  Options options;
  size_t numPolygons = 0;
  float patchSize = 0.0f;
  std::vector<std::unique_ptr<Environment>> envs;  // made at init, never resized
  std::vector<Environment*> envPtrs;
  View view;
  Arena outputArena = Arena::Measure();
  Framebuffer fb;
  Span<uint8_t> rgb8;
  Span<uint8_t> pngScratch;
  Span<char> convBuffer;
  Span<char> textBuffer;
  os::OutFile files[kNumOutputs];
  TextWriter convergence;
  double initSeconds = 0.0;

  void LayoutOutput(Arena& arena) {
    fb.Layout(arena, options.width, options.height);
    rgb8 = arena.Alloc<uint8_t>(size_t(options.width) * size_t(options.height) * 3);
    pngScratch = arena.Alloc<uint8_t>(PngScratchBytes(options.width, options.height));
    convBuffer = arena.Alloc<char>(kTextBufferBytes);
    textBuffer = arena.Alloc<char>(kTextBufferBytes);
  }
};

int Fail(const Status& s) {
  std::string text = s.ToString() + "\n";
  os::WriteErr(text.data(), text.size());
  return kExitUsage;
}

// Init: load, mesh, build the environment and the output stage, open the
// output files under temporary names. Heap allocation is allowed here only.
int Init(Render* r) {
  const Options& o = r->options;
  Scene scene;
  Status s = LoadScene(o.scene, &scene);
  if (!s.ok()) return Fail(s);
  r->numPolygons = scene.polygons.size();
  glm::vec3 extent = scene.bounds.hi - scene.bounds.lo;
  float maxExtent = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  r->patchSize = o.patchSize > 0.0f ? o.patchSize : maxExtent / kAutoPatchDivisions;

  EnvGrid grid;
  for (int a = 0; a < 3; ++a) grid.n[a] = o.envs[a];
  grid.box = scene.bounds;
  Partition part;
  s = PartitionScene(scene, grid, &part);
  if (!s.ok()) return Fail(s);

  Mesh mesh;
  std::vector<uint32_t> all(part.scene.polygons.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  s = MeshScene(part.scene, all, r->patchSize, kMaxPatches, &mesh);
  if (!s.ok()) return Fail(Status::Error("vismask: --patch-size: " + s.message()));

  EnvOptions envOptions;
  envOptions.rayEpsilon = 1e-6f * glm::length(extent);
  envOptions.rays = o.rays;
  envOptions.seed = o.seed;
  envOptions.maskMethod = o.maskMethod;
  envOptions.maskRes = o.maskRes;
  envOptions.roundShots = o.roundShots;
  envOptions.queueCapacity = o.queue;
  std::vector<std::vector<uint32_t>> ids(grid.count());
  for (uint32_t i = 0; i < mesh.patches.size(); ++i)
    ids[part.env[mesh.patches[i].surface]].push_back(i);
  for (int e = 0; e < grid.count(); ++e) {
    r->envs.push_back(std::make_unique<Environment>());
    r->envs.back()->Init(grid, static_cast<uint32_t>(e), mesh, ids[e], envOptions);
  }
  for (auto& e : r->envs) r->envPtrs.push_back(e.get());

  Camera camera = o.hasCamera ? o.camera : DefaultCamera(scene.bounds);
  if (!MakeView(camera, o.width, o.height, &r->view))
    return Fail(Status::Error("vismask: --camera: degenerate camera"));

  Arena measure = Arena::Measure();
  r->LayoutOutput(measure);
  r->outputArena = Arena(measure.used());
  r->LayoutOutput(r->outputArena);

  char why[os::kWhyBytes];
  if (!os::MakeDirs(o.outDir.c_str(), why)) {
    os::PrintErr("vismask: --out: %s\n", why);
    return kExitOutput;
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

void WritePatchesCsv(Render* r) {
  TextWriter w(&r->files[kPatchesCsv], r->textBuffer);
  w.Printf("id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b\n");
  for (Environment* env : r->envPtrs) {
    Span<const Patch> patches = env->patches();
    Span<const PatchEnergy> energy = env->energy();
    for (size_t i = 0; i < patches.size(); ++i) {
      const Patch& p = patches[i];
      glm::vec3 c(0.0f);
      for (uint32_t k = 0; k < p.numCorners; ++k) c += p.corner[k];
      c /= static_cast<float>(p.numCorners);
      w.Printf("%u,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.17g,%.17g,%.17g\n",
               p.globalId, env->index(), c.x, c.y, c.z, p.normal.x, p.normal.y, p.normal.z, p.area,
               p.kd.x, p.kd.y, p.kd.z, p.ke.x, p.ke.y, p.ke.z, energy[i].b[0], energy[i].b[1],
               energy[i].b[2]);
    }
  }
  w.Flush();
}

void JsonString(TextWriter* w, const char* s) {
  w->Write("\"", 1);
  for (; *s; ++s) {
    unsigned char ch = static_cast<unsigned char>(*s);
    if (ch == '"' || ch == '\\') {
      char esc[2] = {'\\', static_cast<char>(ch)};
      w->Write(esc, 2);
    } else if (ch < 0x20) {
      w->Printf("\\u%04x", ch);
    } else {
      w->Write(s, 1);
    }
  }
  w->Write("\"", 1);
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
           o.rays, static_cast<unsigned long long>(o.seed));
  w.Printf("    \"stop_unshot\": %.17g,\n    \"max_shots\": %llu,\n    \"max_seconds\": %.17g,\n",
           o.stopUnshot, static_cast<unsigned long long>(o.maxShots), o.maxSeconds);
  w.Printf("    \"width\": %d,\n    \"height\": %d,\n    \"exposure\": %.9g,\n", o.width, o.height,
           exposure);
  w.Printf("    \"exposure_auto\": %s,\n", o.hasExposure ? "false" : "true");
  w.Printf("    \"envs\": [%d, %d, %d],\n    \"mask_method\": \"%s\",\n", o.envs[0], o.envs[1],
           o.envs[2], MaskMethodName(o.maskMethod));
  w.Printf("    \"mask_res\": %u,\n    \"round_shots\": %u,\n    \"queue\": %u\n  },\n",
           o.maskRes, o.roundShots, o.queue);
  size_t patches = 0, vertices = 0, cells = 0, refs = 0;
  for (Environment* e : r->envPtrs) {
    patches += e->patches().size();
    vertices += e->vertices().size();
    cells += e->grid().cellCount();
    refs += e->grid().plan().refs;
  }
  w.Printf("  \"counts\": {\n    \"polygons\": %zu,\n    \"patches\": %zu,\n", r->numPolygons,
           patches);
  w.Printf("    \"vertices\": %zu,\n    \"environments\": %zu,\n", vertices, r->envPtrs.size());
  w.Printf("    \"grid_cells\": %zu,\n    \"grid_refs\": %zu\n  },\n", cells, refs);
  EnvStats st;
  for (Environment* e : r->envPtrs) {
    st.shots += e->stats().shots;
    st.foreignShots += e->stats().foreignShots;
    st.rays += e->stats().rays;
    st.maskRays += e->stats().maskRays;
    st.hits += e->stats().hits;
    st.packetsSent += e->stats().packetsSent;
  }
  uint32_t packetBytes = r->envPtrs.empty() ? 0 : r->envPtrs[0]->packetBytes();
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
  w.Printf("    \"unshot_fraction\": %.17g\n  },\n", res.unshotFraction);
  EnergyLedger total;
  for (Environment* e : r->envPtrs) {
    for (int c = 0; c < 3; ++c) {
      total.emitted[c] += e->ledger().emitted[c];
      total.absorbed[c] += e->ledger().absorbed[c];
      total.escaped[c] += e->ledger().escaped[c];
      total.unshot[c] += e->ledger().unshot[c];
    }
  }
  w.Printf("  \"energy\": {\n");
  JsonTriple(&w, "emitted", total.emitted, true);
  JsonTriple(&w, "absorbed", total.absorbed, true);
  JsonTriple(&w, "escaped", total.escaped, true);
  JsonTriple(&w, "unshot", total.unshot, true);
  // What the ledger cannot place: power in flight between environments, and
  // what masks lost (negative: leaked). Zero up to rounding for one environment.
  double residual[3];
  for (int c = 0; c < 3; ++c)
    residual[c] = total.emitted[c] - total.absorbed[c] - total.escaped[c] - total.unshot[c];
  JsonTriple(&w, "residual", residual, false);
  w.Printf("  },\n  \"timings\": {\n    \"init_seconds\": %.6f,\n", r->initSeconds);
  w.Printf("    \"solve_seconds\": %.6f,\n    \"output_seconds\": %.6f\n  },\n", res.seconds,
           outputSeconds);
  w.Printf("  \"memory\": {\n    \"environment_arena_bytes\": [");
  for (size_t i = 0; i < r->envPtrs.size(); ++i)
    w.Printf("%s%zu", i ? ", " : "", r->envPtrs[i]->arenaCapacity());
  w.Printf("],\n    \"output_arena_bytes\": %zu,\n", r->outputArena.capacity());
  w.Printf("    \"peak_rss_bytes\": %llu\n  }\n}\n",
           static_cast<unsigned long long>(os::PeakRssBytes()));
  w.Flush();
}

int WriteOutputs(Render* r, const SolveResult& res) {
  double start = os::Seconds();
  double ambient[3];
  AmbientTerm(Span<Environment* const>(r->envPtrs.data(), r->envPtrs.size()), ambient);
  r->fb.Clear();
  for (Environment* env : r->envPtrs) {
    env->ComputeVertexRadiosity(ambient);
    RasterPatches(r->view, env->patches(), env->vertices(), env->vertexRadiosity(), &r->fb);
  }
  float exposure = r->options.hasExposure ? r->options.exposure
                                          : AutoExposure(r->fb.color, r->fb.id, kNoPatch);
  ToneMap(r->fb.color, exposure, r->rgb8);

  char why[os::kWhyBytes] = "write failed";
  bool ok = WritePng(&r->files[kPng], r->options.width, r->options.height, r->rgb8, r->pngScratch, why);
  ok = ok && WritePfm(&r->files[kPfm], r->options.width, r->options.height, r->fb.color);
  WritePatchesCsv(r);
  ok = ok && r->convergence.Flush();
  WriteRunJson(r, res, exposure, os::Seconds() - start);
  // Commit only when every file was written: all outputs appear, or none.
  for (int f = 0; f < kNumOutputs && ok; ++f) ok = r->files[f].Commit(why);
  if (!ok) {
    for (auto& f : r->files) f.Discard();
    os::PrintErr("vismask: cannot write the outputs in '%s': %s\n", r->options.outDir.c_str(), why);
    return kExitOutput;
  }
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
  double num = 0.0, den = 0.0, maxAbs = 0.0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    double d = static_cast<double>(a.pixels[i]) - b.pixels[i];
    num += d * d;
    den += static_cast<double>(b.pixels[i]) * b.pixels[i];
    maxAbs = std::fmax(maxAbs, std::fabs(d));
  }
  double rel = den > 0.0 ? std::sqrt(num / den) : (num > 0.0 ? INFINITY : 0.0);
  char line[256];
  int n = std::snprintf(line, sizeof line, "relative_rmse %.9g\nmax_abs_error %.9g\n", rel, maxAbs);
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
  int rc = Init(r.get());
  if (rc != kExitOk) return rc;
  r->initSeconds = os::Seconds() - start;

  SetPhase(Phase::kSolve);
  SolveOptions so;
  so.roundShots = r->options.roundShots;
  so.queueCapacity = r->options.queue;
  so.order = Span<const uint32_t>(r->options.envOrder.data(), r->options.envOrder.size());
  so.stopUnshot = r->options.stopUnshot;
  so.maxShots = r->options.maxShots;
  so.maxSeconds = r->options.maxSeconds;
  so.quiet = r->options.quiet;
  SolveResult res = Solve(Span<Environment* const>(r->envPtrs.data(), r->envPtrs.size()), so,
                          &r->convergence);

  SetPhase(Phase::kOutput);
  rc = WriteOutputs(r.get(), res);
  SetPhase(Phase::kDone);
  if (rc == kExitOk && !r->options.quiet)
    os::PrintErr("vismask: %llu shots, %.2f s solve; wrote %s/image.png\n",
                 static_cast<unsigned long long>(res.shots), res.seconds, r->options.outDir.c_str());
  return rc;
}

}  // namespace vismask
