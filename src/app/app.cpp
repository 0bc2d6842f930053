#include "vismask/app/app.h"

#include "run.h"
#include "vismask/app/viewer.h"

namespace vismask {
namespace run {
namespace {

// --reference: the image of the solution so far against the reference, on
// rank 0 (the other ranks only help draw it).
class ReferenceProbe : public ErrorProbe {
 public:
  explicit ReferenceProbe(RunState* r) : r_(r) {}
  double Measure() override {
    RenderImage(r_);
    current_ = true;
    if (!r_->isRoot()) return 0.0;
    static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "colour is packed RGB floats");
    Span<const float> image(reinterpret_cast<const float*>(r_->fb.color.data()),
                            r_->fb.color.size() * 3);
    return CompareImages(image, r_->reference, r_->exclude).relativeRmse;
  }

  void Moved() override { current_ = false; }
  // The framebuffer holds the image of the solution as it is (the last
  // Measure came after the last round): the outputs need not draw it again.
  bool current() const { return current_; }

 private:
  RunState* r_;
  bool current_ = false;
};

}  // namespace

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
  if (!mask.pixels.empty() &&
      std::all_of(mask.pixels.begin(), mask.pixels.end(), [](uint8_t m) { return m != 0; }))
    return Fail(Status::Error("vismask: --exclude: " + o.exclude +
                              ": every pixel is excluded: nothing is left to compare"));
  ImageError e = CompareImages(Span<const float>(a.pixels.data(), a.pixels.size()),
                               Span<const float>(b.pixels.data(), b.pixels.size()),
                               Span<const uint8_t>(mask.pixels.data(), mask.pixels.size()));
  char line[256];
  int n = std::snprintf(line, sizeof line, "relative_rmse %.9g\nmax_abs_error %.9g\n",
                        e.relativeRmse, e.maxAbs);
  if (!o.exclude.empty())
    n +=
        std::snprintf(line + n, sizeof line - size_t(n), "excluded_pixels %zu\n", e.excludedPixels);
  return WriteStdout(line, static_cast<size_t>(n)) ? kExitOk : kExitOutput;
}

}  // namespace run

using namespace run;

namespace {

// Init on every rank, and every rank told whether every rank's init
// succeeded (rank 0 alone opens the outputs) before anyone starts the
// solve's collectives: the largest exit code.
int InitAllRanks(RunState* r) {
  int rc = kExitUsage;
  try {
    rc = Init(r);
  } catch (const std::bad_alloc&) {
    // Init's peak is in the budget, but the system may still refuse it
    // (ulimit -v, overcommit off): refused here, with what this process
    // had reached.
    os::PrintErr(
        "vismask: rank %d: out of memory at init, loading and meshing the scene (peak "
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
  return rc;
}

// --checkpoint, --resume: the directory, and the state resumed from; false
// (said) on an error.
bool SetupCheckpoints(RunState* r) {
  Status s;
  std::string identity;
  if (r->isRoot()) {
    uint64_t bytes = 0;
    uint32_t crc = 0;
    std::string why;
    if (!SizeAndCrc(r->options.scene, &bytes, &crc, &why)) {
      os::PrintErr("vismask: %s: %s\n", r->options.scene.c_str(), why.c_str());
      bytes = crc = 0;  // the scene was read at init: seen only if it went since
    }
    identity = CheckpointIdentity(bytes, crc, EnvSpec(r->options), r->options.resultArgs);
    // --sky FILE.hdr: the map's bytes change the result as the scene's do.
    const std::string& sky = r->options.outside.skyFile;
    if (!sky.empty()) {
      if (!SizeAndCrc(sky, &bytes, &crc, &why)) bytes = crc = 0;
      char line[64];
      std::snprintf(line, sizeof line, "sky_map %llu %08x\n",
                    static_cast<unsigned long long>(bytes), crc);
      identity += line;
    }
  }
  Span<Environment* const> envs(r->envPtrs.data(), r->envPtrs.size());
  s = r->checkpoints.Setup(r->options.checkpointDir, r->options.checkpointEvery, envs,
                           r->rankEnvs.total, r->transport.get(), identity);
  if (s.ok() && !r->options.resumeDir.empty()) s = r->checkpoints.Resume(&r->resumeState);
  if (!s.ok()) {
    if (!s.message().empty()) Fail(s);
    return false;
  }
  return true;
}

// The solve's options from the command line.
SolveOptions SolveOptionsOf(const Options& o) {
  SolveOptions so;
  so.roundShots = o.roundShots;
  so.roundWork = o.roundWork;
  so.queueCapacity = o.queue;
  so.routed = o.maskMethod == MaskMethod::kR;
  so.order = Span<const uint32_t>(o.envOrder.data(), o.envOrder.size());
  so.stopUnshot = o.stopUnshot;
  so.maxShots = o.maxShots;
  so.rayBudget = o.rayBudget;
  so.maxSeconds = o.maxSeconds;
  so.stopError = o.stopError;
  so.correctUnshot = o.correctUnshot;
  so.quiet = o.quiet;
  return so;
}

// A solve that ended without outputs (a signal, a stall): its message on
// rank 0 and the run's exit status; -1 when the solve finished.
int EndedEarly(RunState* r, const SolveResult& res) {
  if (res.reason == StopReason::kInterrupted) {  // a signal: the checkpoint holds the solve
    const int sig = r->checkpoints.interrupt();
    if (r->isRoot()) {
      for (auto& f : r->files) f.Discard();
      r->exportFile.Discard();
      if (r->checkpoints.written() > 0 || r->checkpoints.resumed())
        os::PrintErr(
            "vismask: ended by signal %d after %llu shots; the checkpoint in %s holds round %llu: "
            "the same command with --resume %s instead of --checkpoint goes on from there\n",
            sig, static_cast<unsigned long long>(res.shots), r->options.checkpointDir.c_str(),
            static_cast<unsigned long long>(r->checkpoints.checkpointRounds()),
            r->options.checkpointDir.c_str());
      else
        os::PrintErr("vismask: ended by signal %d after %llu shots; no checkpoint was written\n",
                     sig, static_cast<unsigned long long>(res.shots));
    }
    return r->transport->Finish(128 + sig);
  }
  // No outputs: the solve did not finish (kStalled), or would never (kNoLoss).
  if (res.reason == StopReason::kStalled || res.reason == StopReason::kNoLoss) {
    if (r->isRoot()) {
      for (auto& f : r->files) f.Discard();
      if (res.reason == StopReason::kStalled)
        os::PrintErr(
            "vismask: the solve stalled after %llu shots: %llu rounds without a shot "
            "while %.3g of the emitted power was unshot or in flight (the admission of "
            "new records let no environment shoot; try a larger --queue)\n",
            static_cast<unsigned long long>(res.shots),
            static_cast<unsigned long long>(r->rankEnvs.total), res.unshotFraction);
      else
        os::PrintErr(
            "vismask: the solve stalled after %llu shots: the unshot power went from %.4g%% to "
            "%.4g%% of the emitted, not down by %g%% of itself, while %g times as much power was "
            "shot: power goes round where nothing absorbs it (faces of Kd 1 closing a cavity? "
            "give them a Kd below 1, or stop sooner with --max-shots or --max-seconds)\n",
            static_cast<unsigned long long>(res.shots), 100.0 * res.stallFrom, 100.0 * res.stallTo,
            100.0 * kStallFall, kStallShot);
    }
    return r->transport->Finish(kExitStalled);
  }

  return -1;
}

// Rank 0's last line: shots, solve time, the view, where the image went.
void PrintDone(const RunState* r, const SolveResult& res) {
  char view[128] = "--camera";
  if (r->cam.hasSide)
    std::snprintf(view, sizeof view, "view %s%s", ViewSideName(r->cam.side),
                  r->cam.sideChosen ? " (chosen)" : "");
  else if (r->cam.inside)
    std::snprintf(view, sizeof view, "view from inside (chosen: the %s side sees %s)",
                  ViewSideName(r->cam.viewChoice.side),
                  r->cam.viewChoice.sideBack > r->cam.viewChoice.sideFront ? "mostly back faces"
                                                                           : "one wall");
  os::PrintErr("vismask: %llu shots, %.2f s solve, %s; wrote %s/image.png\n",
               static_cast<unsigned long long>(res.shots), res.seconds, view,
               r->options.outDir.c_str());
}

}  // namespace

int Main(int argc, const char* const* argv) {
  SetPhase(Phase::kInit);
  double start = os::Seconds();
  auto r = std::make_unique<RunState>();
  Status s = ParseArgs(argc, argv, &r->options);
  if (!s.ok()) return Fail(s);
  if (r->options.help) {
    const char* text = r->options.command == "view"         ? ViewHelpText()
                       : r->options.command == "scene-dump" ? SceneDumpHelpText()
                       : r->options.helpAll                 ? HelpText()
                                                            : UsageText();
    return WriteStdout(text, std::strlen(text)) ? kExitOk : kExitOutput;
  }
  if (r->options.command == "compare") return Compare(r->options);
  if (r->options.command == "verify") return Verify(r->options);
  if (r->options.command == "footprint") return Footprint(r->options);
  if (r->options.command == "view") return View(r->options);
  if (r->options.command == "scene-dump") return SceneDump(r->options);
  // --resume without --envs: the checkpoint's environments (a run of 16
  // ranks, resumed on 15, keeps its 16 environments).
  if (!r->options.resumeDir.empty() && !r->options.hasEnvs) {
    const std::string spec = ManifestValue(r->options.resumeDir, "environments");
    if (!spec.empty()) {
      std::vector<const char*> args(argv, argv + argc);
      args.push_back("--envs");
      args.push_back(spec.c_str());
      s = ParseArgs(static_cast<int>(args.size()), args.data(), &r->options);
      if (!s.ok()) return Fail(s);
    }
  }
  // The pipe transport forks here: every rank carries on from this point.
  r->transport = MakeTransport(
      TransportRequest{r->options.transport, r->options.ranks, r->options.rankTimeout}, &s);
  // An error with no text: another rank (rank 0) reports it.
  if (!r->transport) return s.message().empty() ? kExitUsage : Fail(s);
  // Under mpirun without --envs: one balanced environment a rank.
  SetWorldSize(r->transport->size(), &r->options);
  int rc = InitAllRanks(r.get());
  if (rc != kExitOk) return r->transport->Finish(rc);
  // --max-seconds without --patch-size: init again at the planned patch
  // size (the first init's state and its output lock let go first).
  PlanRate rate;
  if (const float size = PlanPatchSize(*r, &rate); size > 0.0f) {
    rate = PlanRate{};  // timed on the mesh let go
    auto again = std::make_unique<RunState>();
    again->options = r->options;
    again->options.patchSize = size;
    again->options.patchSizePlanned = true;
    again->options.initAgain = true;
    again->transport = std::move(r->transport);
    r.reset();
    r = std::move(again);
    rc = InitAllRanks(r.get());
    if (rc != kExitOk) return r->transport->Finish(rc);
  }
  // --checkpoint, --resume: the directory, and the state resumed from.
  const bool checkpointing = !r->options.checkpointDir.empty();
  if (checkpointing) {
    if (!SetupCheckpoints(r.get())) return r->transport->Finish(kExitUsage);
    os::DeferInterrupts(true);
  }
  r->initSeconds = os::Seconds() - start;

  const PlanRate planned = PlanBudget(r.get(), rate);

  SetPhase(Phase::kSolve);
  SolveOptions so = SolveOptionsOf(r->options);
  ReferenceProbe probe(r.get());
  if (!r->options.reference.empty()) so.probe = &probe;
  so.errorEvery = r->options.errorEvery;
  if (checkpointing) so.hook = &r->checkpoints;
  Pacer pacer(PaceInputOf(r->options, planned, r->envPtrs.size()));
  if (Paces(*r)) so.pacer = &pacer;
  if (r->checkpoints.resumed()) so.resume = &r->resumeState;
  SolveResult res =
      Solve(Span<Environment* const>(r->envPtrs.data(), r->envPtrs.size()), r->rankEnvs,
            r->transport.get(), &r->exchange, so, r->isRoot() ? &r->convergence : nullptr);
  // Past the solve a signal ends the run at once again (the outputs' commit defers it).
  if (checkpointing) os::DeferInterrupts(false);
  // The emitted rays the paced quantum came to (run.json).
  if (so.pacer && pacer.updates() > 0)
    r->options.emittedRaysPaced =
        static_cast<uint64_t>(static_cast<double>(r->options.emittedRays) / pacer.scale());
  const int early = EndedEarly(r.get(), res);
  if (early >= 0) return early;
  SetPhase(Phase::kOutput);
  r->imageCurrent = probe.current();
  rc = WriteOutputs(r.get(), res);
  SetPhase(Phase::kDone);
  rc = r->transport->Finish(rc);
  if (rc == kExitOk && !r->options.quiet && r->isRoot()) PrintDone(r.get(), res);
  return rc;
}

}  // namespace vismask
