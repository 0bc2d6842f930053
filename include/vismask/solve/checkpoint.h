// Checkpoint and resume (--checkpoint DIR, --resume DIR).
//
// At a round's end, every --checkpoint-every seconds of solve (rank 0's
// clock, which every rank has from the round's reports, so every rank
// decides alike) and at the first round's end after a rank caught SIGINT,
// SIGTERM or SIGHUP, each rank writes each of its environments to
// DIR/env-NNNNN.S, S a or b in turn: the files of the last complete
// checkpoint stay whole while the next is written. Each file is written
// atomically (os::WriteFileAtomic: a temporary name, synced, renamed, the
// directory synced). Once every rank has written its files, rank 0 writes
// DIR/manifest, atomically too: which generation (and so which letter) is
// complete, and what a resumed run must agree with (the scene's bytes, the
// environments, the result-changing options). A kill at any moment leaves
// the manifest naming a complete checkpoint, or no manifest.
//
// An environment's file is a head, its EnvState, the solver's SolveState
// (solver.h) and its arena's bytes, with the CRC-32 of all but the head.
// Per environment, so it does not matter which rank held which: a run
// resumes on any number of ranks, and since the solve does not depend on
// how environments are grouped onto ranks, it ends with the same bytes as a
// run never stopped. Nothing is allocated while checkpointing: the files
// are written from the arenas, and the paths and the manifest's buffer are
// made at init.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/core/os.h"
#include "vismask/core/status.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/solver.h"

namespace vismask {

// The bytes of an environment's checkpoint file whose arena holds
// `arenaBytes` (`vismask footprint`, run.json).
uint64_t CheckpointFileBytes(uint64_t arenaBytes);

// What a resumed run must agree with: "scene BYTES CRC32", "environments
// SPEC" and "options ARGS" lines (the manifest holds them as written).
std::string CheckpointIdentity(uint64_t sceneBytes, uint32_t sceneCrc, const std::string& envSpec,
                               const std::vector<std::string>& resultArgs);

// The value of `key` in DIR/manifest ("environments" -> "auto:16"), or
// empty if there is none or it cannot be read. For the environments a
// resumed run without --envs adopts.
std::string ManifestValue(const std::string& dir, const char* key);

class Checkpoints final : public RoundHook {
 public:
  // Init, on every rank: makes DIR and the paths of this rank's
  // environments' files; rank 0 keeps `identity` for the manifest. A user
  // error (DIR cannot be made) on any rank is every rank's.
  Status Setup(const std::string& dir, double every, Span<Environment* const> envs,
               uint32_t numEnvs, Transport* transport, const std::string& identity);
  // Init, on every rank, after Setup: the solve's state from DIR's newest
  // complete checkpoint into the environments and *state. Refused (on every
  // rank alike) when there is none, when it is of another scene, other
  // environments or other result-changing options (the message names each
  // difference), or when a file is damaged or missing. The message is on
  // the rank that found it (rank 0's for the manifest); others get an
  // empty one.
  Status Resume(SolveState* state);

  bool AtRoundEnd(const SolveState& state) override;
  bool haveCheckpoint() const override { return generation_ > 0; }
  uint64_t checkpointRounds() const override { return lastRounds_; }
  double checkpointElapsed() const override { return lastElapsed_; }

  uint64_t written() const { return written_; }  // by this run
  uint64_t failed() const { return failed_; }    // checkpoints not written (a warning each)
  uint64_t resumedRounds() const { return resumedRounds_; }  // 0: not resumed
  bool resumed() const { return resumed_; }
  uint64_t rankBytes() const { return rankBytes_; }      // this rank's files, one checkpoint
  double writeSeconds() const { return writeSeconds_; }  // spent writing, all checkpoints
  int interrupt() const { return interrupt_; }           // the signal that ended the solve, or 0

 private:
  bool Write(const SolveState& state);
  std::string dir_;
  double every_ = 0.0;
  Span<Environment* const> envs_;
  uint32_t numEnvs_ = 0;
  Transport* transport_ = nullptr;
  std::string identity_;
  std::vector<std::string> paths_;  // [2 * i + slot]: this rank's environment i's files
  std::string manifestPath_;
  std::vector<char> manifest_;  // rank 0: the manifest's text, made at each checkpoint
  uint64_t generation_ = 0;     // the last complete checkpoint's (0: none)
  uint64_t lastRounds_ = 0;
  double lastElapsed_ = 0.0;
  uint64_t triedRounds_ = 0;  // the last checkpoint tried, written or not
  double triedElapsed_ = 0.0;
  uint64_t written_ = 0, failed_ = 0, resumedRounds_ = 0, rankBytes_ = 0;
  bool resumed_ = false;
  double writeSeconds_ = 0.0;
  int interrupt_ = 0;
};

}  // namespace vismask
