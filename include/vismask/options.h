// Options: the command line. `vismask render SCENE.obj [flags]` and
// `vismask --help`. Parsing is strict: an unknown flag, a missing value or a
// value that does not parse completely, is not finite or is out of range is
// an error (never clamped).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/camera.h"
#include "vismask/mask.h"
#include "vismask/outside.h"
#include "vismask/scene.h"
#include "vismask/status.h"
#include "vismask/transport.h"

namespace vismask {

struct Options {
  std::string command;  // "render", "footprint", "compare", "verify" or "view"; empty with --help
  bool help = false;
  bool helpAll = false;  // --help all: every option (HelpText); --help alone: UsageText
  std::string scene;
  LoadOptions load;      // --strict, --emit NAME=R,G,B|ka (repeatable)
  OutsideLight outside;  // --sky R,G,B, --sun X,Y,Z,R,G,B[,DEG] (outside.h)
  std::string outDir = "out";
  std::string
      exportPath;  // --export FILE.glb: the solved mesh as binary glTF (gltf.h); empty: none
  float patchSize = 0.0f;  // 0: automatic (largest scene extent / kAutoPatchDivisions)
  // Ray allocation: kPower (the default) gives a shot rays in proportion
  // to its power; kFixed (chosen by --rays N alone) gives every shot N.
  enum class RayAlloc { kPower, kFixed };
  RayAlloc rayAlloc = RayAlloc::kPower;
  bool hasRayAlloc = false;
  uint32_t rays = 4096;  // --rays: per shot (fixed)
  bool hasRays = false;
  uint64_t emittedRays = 4000000;  // --emitted-rays: the rays the emitted power is worth (power)
  uint32_t minRays = 16;           // --min-rays: the fewest a shot traces (power)
  uint32_t maxRays =
      8192;           // --max-rays: the most a shot traces (power); more power -> partial shots
  bool sobol = true;  // --sampler sobol|random
  uint32_t elementsPerPatch = 8;  // --elements K: the element pool, K per patch beyond the roots
  uint32_t elementDepth = 4;      // --element-depth D: the deepest an element splits
  float elementSpread = 0.1f;     // --element-spread S: the least relative spread that splits
  float elementChi2 = 20.0f;      // --element-chi2 X: the significance a split needs
  uint64_t rayBudget = 0;         // --ray-budget N: stop once N rays are traced; 0: none
  uint64_t seed = 1;
  double stopUnshot = 1e-3;
  uint64_t maxShots = 0;    // 0: none
  double maxSeconds = 0.0;  // 0: none
  int width = 512;
  int height = 512;
  bool hasCamera = false;
  Camera camera;
  bool hasView = false;  // --view SIDE: that side's camera instead of the chosen one
  ViewSide view = ViewSide::kFront;
  bool hasExposure = false;
  float exposure = 1.0f;
  bool quiet = false;
  int envs[3] = {1, 1, 1};  // --envs NX[xNY[xNZ]] (or the grid --envs auto:N chose, at init)
  // --envs auto[:N]: N environments (default: --ranks), the grid's shape and
  // its split planes chosen at init from the scene (partition.h, WorkSplitter).
  bool hasEnvs = false;  // --envs given (else --ranks N > 1 or an MPI world > 1 means auto:N)
  bool envsAuto = false;
  int envsAutoCount = 0;
  // R by default: every ray absorbed in exactly one environment, and its
  // packets go only where its rays go. --mask-res alone selects B.
  MaskMethod maskMethod = MaskMethod::kR;
  bool hasMaskMethod = false;
  bool hasMaskRes = false;
  uint32_t maskRes = 50;
  // Round size (ResolveRounds). --round-shots K: at most K shots per
  // environment per round; --round-work N: a round ends for an environment
  // once its rays' grid walks have done N steps (cells entered plus patches
  // tested: Grid::steps, a count, never a time), 0: never. With several
  // environments and neither given, both are automatic: roundWorkAuto, and
  // init sets roundWork from the scene (AutoRoundWork); with one
  // environment and neither given, one shot a round (nothing to exchange).
  uint32_t roundShots = 1;
  bool hasRoundShots = false;
  uint64_t roundWork = 0;
  bool hasRoundWork = false;
  bool roundWorkAuto = false;
  uint32_t queue = 64;  // --queue Q; without it, AutoQueue (ResolveRounds)
  bool hasQueue = false;
  // --centre-rays: which open pixels Method B casts a centre ray through.
  CentreChoice centreRays = CentreChoice::kAuto;
  uint32_t maskCacheKiB = 8192;  // --mask-cache: B/C centre masks kept per environment
  std::vector<uint32_t> envOrder;
  std::string transport;  // --transport loop|pipe|mpi; empty: the binary's default
  int ranks = 1;          // --ranks N (pipe)
  double rankTimeout =
      kDefaultRankTimeout;  // --rank-timeout S: a silent peer ends the run; 0: never
  uint64_t memBudget = 0;   // --mem-budget BYTES per rank; 0: none
  bool json = false;        // footprint --json
  std::string reference;    // --reference REF.pfm: the error of the image against it
  uint64_t errorEvery = 0;  // --error-every K shots (with --reference); 0: at the end only
  std::string exclude;  // --exclude MASK.pgm (render with --reference, compare): pixels left out of
                        // the error
  bool correctUnshot = false;
  // --two-sided: every polygon gets a second, reversed copy (its twin), so
  // both sides receive, reflect and show. --two-sided-emitters: emitting
  // polygons get one too (with --two-sided, their twins already exist),
  // and emitters' twins emit Ke as well: twice the emitted power.
  bool twoSided = false;
  bool twoSidedEmitters = false;
  bool aa = true;  // --aa on|off: exact pixel coverage (a 1-pixel box filter), or centre samples
  bool smooth =
      true;  // --smooth on|off: share display values across smoothed polygons (smoothing.h)
  float creaseDeg = 30.0f;  // --crease DEG: the most two normals may differ by and be smoothed
  double stopError = 0.0;   // --stop-error E: stop when the estimated bias < E; 0: off  //
                            // --correct-unshot on: patches.csv's b gets kd * ambient
  // vismask compare A.pfm B.pfm
  std::string compareA, compareB;
  // vismask view OUT_DIR [--glb NAME.glb] [--port P] (viewer.h)
  std::string viewDir;
  std::string verifyDir;  // vismask verify OUT_DIR
  std::string viewGlb;    // empty: the one .glb in viewDir
  int viewPort = 0;       // 0: any free port
};

// Rounds by work (ResolveRounds, AutoRoundWork): the full shots' worth of
// work an automatic round holds, the most shots it holds, and the outbox
// bytes an automatic round may fill (fewer shots with large packets).
constexpr uint32_t kAutoRoundWorkShots = 32;
constexpr uint32_t kAutoRoundShots = 256;
constexpr uint64_t kAutoRoundOutboxBytes = 512 * 1024;

constexpr float kAutoPatchDivisions =
    28.0f;  // issue 15: 16 measured 2.9% against the ground truth, 28 2.4% (docs/RESULTS.md)

// Parses argv (argv[0] is the program). On error returns a Status whose
// message names the flag and the offending value.
Status ParseArgs(int argc, const char* const* argv, Options* options);

// The round size the options give for `numEnvs` environments: fills
// roundShots and roundWork (or roundWorkAuto) when they were not given
// (see Options). Called once the environment count is known.
void ResolveRounds(int numEnvs, Options* options);

// The default --queue: numEnvs x roundShots slots (admission shares the
// free slots among the environments, so that is what lets each make a
// whole round), but at most kAutoQueueShots an environment and
// kAutoQueueBytes of `packetBytes` slots, and at least kMinAutoQueue. The
// fixed 64 of before held the building's solve in 16 environments to 123
// rounds; 1024 slots take 19 (issue 20). More than 64 an environment made
// the stiff box in 2x2x2 (Method R, --stop-error 8e-3) take more shots:
// 44 757 with 512 slots, over 100 000 with 2 048 (admission lets every
// environment shoot its weak local patches while the strong power waits
// in the queues).
constexpr uint64_t kAutoQueueBytes = 1u << 20;
constexpr uint32_t kMinAutoQueue = 64;
constexpr uint32_t kAutoQueueShots = 64;
uint32_t AutoQueue(int numEnvs, uint32_t roundShots, uint64_t packetBytes);

// A run of `ranks` ranks (the MPI world) without --envs: --envs auto with
// one environment a rank, its rounds resolved again. True when it changed
// the options (no --envs, more than one rank, not already auto).
bool SetWorldSize(int ranks, Options* options);

// The automatic --round-work: kAutoRoundWorkShots full shots, each the
// most rays a shot traces, every one landing here, times (the grid steps a
// ray takes in an environment of the scene's estimated `patches` / `numEnvs`
// patches, about the cube root of kStepCellsPerPatch cells a patch, plus
// a ray's and a hit's work), plus a shot's (WorkCostsOf the mask method, work.h).
// From the scene and the options alone, so every rank computes the same.
uint64_t AutoRoundWork(const Options& options, double patches, int numEnvs);

// `vismask --help`: a short usage, the input formats read and five
// examples, pointing to `--help all`.
const char* UsageText();
// The --help all text: every command and option.
const char* HelpText();

}  // namespace vismask
