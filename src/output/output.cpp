// The outputs: the image drawn from every rank, patches.csv, the files
// committed as one (run.h).
#include "../app/run.h"

namespace vismask::run {

// The radiosity patches.csv holds for patch i: the solved b, plus kd times
// the ambient term with --correct-unshot on.
double OutputB(const RunState& r, const Environment& env, size_t i, int c) {
  double b = env.energy()[i].b[c];
  if (r.options.correctUnshot) b += static_cast<double>(env.patches()[i].kd[c]) * r.ambientB[c];
  return b;
}

// The stated error's sums over one environment's patches: the Monte Carlo
// variance of each b relative to b (area-weighted), b * area, and the
// ambient term's share.
void ErrorSums(const RunState& r, const Environment& env, EnvSummary* s) {
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

PatchRecord RecordOf(const RunState& r, const Environment& env, size_t i) {
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
  w->Printf(
      "%u,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.17g,%.17g,%.17g\n",
      p.id, p.env, p.c[0], p.c[1], p.c[2], p.n[0], p.n[1], p.n[2], p.area, p.kd[0], p.kd[1],
      p.kd[2], p.ke[0], p.ke[1], p.ke[2], p.b[0], p.b[1], p.b[2]);
}

// patches.csv in id order: rank 0's environments, then every other rank's,
// sent to rank 0 in chunks (ids rise with environment and rank).
void WritePatchesCsv(RunState* r) {
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

namespace {

// Point sampled: each rank draws its environments into its framebuffer, and
// rank 0 depth-composites the others', a band of rows at a time, in rank
// order. The nearest (depth, id) wins and ties keep the first drawn, so the
// image is the same whichever rank holds which environment.
void DrawPointSampled(RunState* r, const double* ambient) {
  Transport* t = r->transport.get();
  for (Environment* env : r->envPtrs)
    DrawEnvironment(r->view, *env, ambient, &r->fb, r->textures.textures, &r->foreign);
  const Framebuffer& mine = r->fb;
  const size_t w = static_cast<size_t>(mine.width);
  for (int src = 1; src < t->size(); ++src) {
    if (!r->isRoot() && t->rank() != src) continue;
    for (int y = 0; y < mine.height; y += kBandRows) {
      int rows = std::min(kBandRows, mine.height - y);
      size_t first = static_cast<size_t>(y) * w, n = static_cast<size_t>(rows) * w;
      if (r->isRoot()) {
        Framebuffer& in = r->incoming;
        t->Recv(src, in.color.data(), in.color.subspan(0, n).bytes());
        t->Recv(src, in.depth.data(), in.depth.subspan(0, n).bytes());
        t->Recv(src, in.id.data(), in.id.subspan(0, n).bytes());
        CompositeRows(in, y, rows, &r->fb);
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
}

// Antialiased: a pixel's fragments sum the pieces of one polygon (its id),
// which may lie in several environments, and keep the kFragments nearest.
// Float sums and a bounded list depend on the order things arrive in, so
// each environment is drawn alone (into an empty framebuffer) and merged
// into rank 0's image in environment order, whichever rank holds it: rank
// 0's own through r->envFb, the others' sent one environment at a time,
// only the rows it drew, a band of rows at a time.
void DrawAntialiased(RunState* r, const double* ambient) {
  Transport* t = r->transport.get();
  Framebuffer& mine = r->fb;
  const size_t w = static_cast<size_t>(mine.width);
  if (r->isRoot()) {
    for (size_t k = 0; k < r->envPtrs.size(); ++k) {
      // The first is drawn straight into the empty image: the same as
      // merging it into one.
      Framebuffer* target = k == 0 ? &mine : &r->envFb;
      DrawEnvironment(r->view, *r->envPtrs[k], ambient, target, r->textures.textures, &r->foreign);
      if (k == 0) continue;
      CompositeDirty(r->envFb, &mine);
      r->envFb.ClearDirty();
    }
    for (int src = 1; src < t->size(); ++src) {
      RankEnvs theirs = EnvsOfRank(r->rankEnvs.total, t->size(), src);
      for (uint32_t k = 0; k < theirs.count; ++k) {
        int32_t rowsDrawn[2];
        t->Recv(src, rowsDrawn, sizeof rowsDrawn);
        CHECK(rowsDrawn[0] >= 0 && rowsDrawn[1] < mine.height);
        for (int y = rowsDrawn[0]; y <= rowsDrawn[1]; y += kBandRows) {
          int rows = std::min(kBandRows, rowsDrawn[1] + 1 - y);
          size_t n = static_cast<size_t>(rows) * w;
          Framebuffer& in = r->incoming;
          t->Recv(src, in.frags.data(), in.frags.subspan(0, n * kFragments).bytes());
          t->Recv(src, in.dropped.data(), in.dropped.subspan(0, n).bytes());
          CompositeRows(in, y, rows, &mine);
        }
      }
    }
    return;
  }
  for (Environment* env : r->envPtrs) {
    mine.ClearDirty();
    DrawEnvironment(r->view, *env, ambient, &mine, r->textures.textures, &r->foreign);
    // An environment that drew nothing sends the empty range [0, -1].
    int32_t rowsDrawn[2] = {mine.dirtyLo, mine.dirtyHi};
    t->Send(0, rowsDrawn, sizeof rowsDrawn);
    for (int y = mine.dirtyLo; y <= mine.dirtyHi; y += kBandRows) {
      int rows = std::min(kBandRows, mine.dirtyHi + 1 - y);
      size_t first = static_cast<size_t>(y) * w, n = static_cast<size_t>(rows) * w;
      auto f = mine.frags.subspan(first * kFragments, n * kFragments);
      auto d = mine.dropped.subspan(first, n);
      t->Send(0, f.data(), f.bytes());
      t->Send(0, d.data(), d.bytes());
    }
  }
}

}  // namespace

// Every environment's vertex radiosity from `ambient`, shared across cuts
// and smoothed polygons. Collective.
void ShareDisplayValues(RunState* r, const double* ambient) {
  for (Environment* env : r->envPtrs) env->ComputeVertexRadiosity(ambient);
  if (r->sharedCapacity > 0) {
    Span<Environment* const> envs(r->envPtrs.data(), r->envPtrs.size());
    CollectShared(envs, r->sharedMine);
    r->transport->AllGather(r->sharedMine.data(), r->sharedMine.bytes(), r->sharedAll.data());
    ShareVertices(envs, r->sharedAll, r->sharedScratch, r->shareRule);
  }
}

// Draws the current solution into rank 0's framebuffer: the ambient term
// from every environment (summed in environment order), each rank's patches
// drawn by that rank, and rank 0 depth-compositing the others'. Collective.
void RenderImage(RunState* r) {
  ++r->imagesDrawn;
  for (uint32_t i = 0; i < r->rankEnvs.perRank; ++i) r->ambientMine[i] = AmbientReport{};
  for (size_t i = 0; i < r->envPtrs.size(); ++i) r->ambientMine[i] = AmbientOf(*r->envPtrs[i]);
  GatherByEnv(r, r->ambientMine, r->ambientAll, r->ambient);
  AmbientTerm(r->ambient, r->ambientB);
  // Per-pixel direct light shows the first bounce of the emission not yet
  // shot; the image's ambient term leaves it out (patches.csv's and
  // run.json's, r->ambientB, keep it).
  double display[3];
  bool direct = !r->envPtrs.empty() && r->envPtrs[0]->directPerPixel();
  AmbientTerm(r->ambient, display, direct);
  const double* ambient = display;
  r->fb.Clear();
  for (Environment* env : r->envPtrs) env->SetDisplayIndirect(direct);
  ShareDisplayValues(r, ambient);
  if (r->fb.aa)
    DrawAntialiased(r, ambient);
  else
    DrawPointSampled(r, ambient);
  if (r->isRoot()) Resolve(&r->fb);
}

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
    os::PrintErr("vismask: warning: the image is all background: the camera sees no surface (%s)\n",
                 fix);
  else
    os::PrintErr(
        "vismask: warning: the image is black: the camera sees no lit front-facing "
        "surface, only background and the backs of one-sided polygons (%s)\n",
        fix);
}

int WriteOutputs(RunState* r, const SolveResult& res) {
  double start = os::Seconds();
  // A final --reference measurement drew this very image (the same state,
  // the same drawing): the same bytes, so it is not drawn again.
  if (!r->imageCurrent) RenderImage(r);
  WritePatchesCsv(r);
  // The export is the view-independent solution: with per-pixel direct
  // light the image's vertex values were the indirect part alone, so the
  // whole is worked out again (with Cohen's ambient term, as without it).
  if (!r->options.exportPath.empty() && !r->envPtrs.empty() && r->envPtrs[0]->directPerPixel()) {
    for (Environment* env : r->envPtrs) env->SetDisplayIndirect(false);
    ShareDisplayValues(r, r->ambientB);
  }
  WriteExport(r);
  for (uint32_t i = 0; i < r->rankEnvs.perRank; ++i) r->summaryMine[i] = EnvSummary{};
  for (size_t i = 0; i < r->envPtrs.size(); ++i) {
    const Environment& e = *r->envPtrs[i];
    EnvSummary& s = r->summaryMine[i];
    s = EnvSummary{};
    s.ledger = e.ledger();
    s.stats = e.stats();
    ErrorSums(*r, e, &s);
    s.arenaBytes = e.arenaCapacity();
    s.work = e.workSteps();
    s.patches = e.patches().size();
    s.vertices = e.lattice().vertices().size();
    s.gridCells = e.grid().cellCount();
    s.gridRefs = e.grid().plan().refs;
    s.gridSubGrids = e.grid().plan().subGrids;
    s.elementsUsed = e.elementsUsed();
    s.elementCapacity = e.elements().size();
    s.filterSteps = e.filterSteps();
    for (const Element& el : e.elements().subspan(0, e.elementsUsed())) {
      s.leaves += el.child == kNoElement;
      if (el.depth > s.elementDepth) s.elementDepth = el.depth;
    }
  }
  GatherByEnv(r, r->summaryMine, r->summaryAll, r->summary);
  // Every rank's memory for run.json: predicted and measured.
  RunState::RankMemory mine{r->predictedBytes, r->initPeakBytes, os::PeakRssBytes(),
                            os::FileRssBytes(), 0};
  for (Environment* e : r->envPtrs)
    mine.bytesSent += e->stats().packetsSent * r->exchange.packetBytes;
  r->transport->AllGather(&mine, sizeof mine, r->rankMemory);
  if (!r->isRoot()) return kExitOk;

  WarnIfEmpty(r->fb, r->options.hasCamera);
  float exposure =
      r->options.hasExposure ? r->options.exposure : AutoExposure(r->fb.color, r->fb.id, kNoPatch);
  ToneMap(r->fb.color, exposure, r->rgb8);
  char why[os::kWhyBytes] = "";
  // A failed write is remembered by its file and reported by CommitAll with
  // the file's name and the reason; only the PNG encoder fails on its own.
  bool ok =
      WritePng(&r->files[kPng], r->options.width, r->options.height, r->rgb8, r->pngScratch, why);
  WritePfm(&r->files[kPfm], r->options.width, r->options.height, r->fb.color);
  r->convergence.Flush();
  WriteRunJson(r, res, exposure, os::Seconds() - start);
  // Commit only when every file was written: all outputs are this run's, or
  // none is replaced (run.json, last, marks a complete run).
  // The .glb (with --export) is committed with them, before run.json.
  os::OutFile* commit[kNumOutputs + 1];
  int n = 0;
  for (int f = 0; f < kNumOutputs; ++f) {
    if (f == kRunJson && r->exportFile.isOpen()) commit[n++] = &r->exportFile;
    commit[n++] = &r->files[f];
  }
  if (ok) ok = os::CommitAll(commit, n, why, r->options.outDir.c_str());
  if (!ok) {
    for (auto& f : r->files) f.Discard();
    r->exportFile.Discard();
    os::PrintErr("vismask: cannot write the outputs in '%s': %s\n", r->options.outDir.c_str(), why);
    return kExitOutput;
  }
  return kExitOk;
}

}  // namespace vismask::run
