// Options: the command line. `vismask render SCENE.obj [flags]` and
// `vismask --help`. Parsing is strict: an unknown flag, a missing value or a
// value that does not parse completely, is not finite or is out of range is
// an error (never clamped). Each option's name, syntax, range, help and
// run.json key are one row of the option table (options_table.h).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/core/status.h"
#include "vismask/display/camera.h"
#include "vismask/parallel/transport.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/mask.h"
#include "vismask/solve/outside.h"

namespace vismask {

struct Options {
  std::string command;  // "render", "footprint", "scene-dump", "compare", "verify" or "view"; empty
                        // with --help
  bool help = false;
  bool helpAll = false;  // --help all: every option (HelpText); --help alone: UsageText
  std::string scene;
  LoadOptions load;      // --strict, --emit NAME=R,G,B|ka (repeatable)
  OutsideLight outside;  // --sky R,G,B, --sun X,Y,Z,R,G,B[,DEG] (outside.h)
  std::string outDir = "out";
  // --export FILE.glb: the solved mesh as binary glTF (gltf.h); empty: none.
  std::string exportPath;
  float patchSize = 0.0f;  // 0: automatic (largest scene extent / kAutoPatchDivisions)
  // Ray allocation: kPower (the default) gives a shot rays in proportion
  // to its power; kFixed (chosen by --rays N alone) gives every shot N.
  enum class RayAlloc { kPower, kFixed };
  RayAlloc rayAlloc = RayAlloc::kPower;  // --ray-alloc power|fixed
  bool hasRayAlloc = false;              // --ray-alloc given (else --rays alone picks fixed)
  uint32_t rays = 4096;                  // --rays: per shot (fixed)
  bool hasRays = false;
  bool hasEmittedRays = false;      // --emitted-rays given (else --max-seconds may plan it)
  bool hasEmissionRays = false;     // --emission-rays given (else ResolveEmissionRays)
  bool emittedRaysPlanned = false;  // --max-seconds chose emittedRays (app.cpp, PlanBudget)
  uint64_t emittedRaysPaced = 0;    // the emitted rays the paced solve's last quantum came to
  bool patchSizePlanned = false;    // --max-seconds chose patchSize (app.cpp, PlanPatchSize)
  bool initAgain = false;           // init made again (the planned patch size): warnings said once
  uint64_t emittedRays = 4000000;   // --emitted-rays: the rays the emitted power is worth (power)
  uint32_t minRays = 16;            // --min-rays: the fewest a shot traces (power)
  // --max-rays: the most a shot traces (power); a shot worth more shoots a
  // part of its power and keeps the rest.
  uint32_t maxRays = 8192;
  bool sobol = true;              // --sampler sobol|random
  bool originsByPower = true;     // --origins power|uniform
  bool patchSequence = true;      // --sequence patch|shot
  uint32_t elementsPerPatch = 8;  // --elements K: the element pool, K per patch beyond the roots
  uint32_t elementDepth = 4;      // --element-depth D: the deepest an element splits
  float elementSpread = 0.1f;     // --element-spread S: the least relative spread that splits
  float elementChi2 = 20.0f;      // --element-chi2 X: the significance a split needs
  uint64_t rayBudget = 0;         // --ray-budget N: stop once N rays are traced; 0: none
  uint64_t seed = 1;              // --seed: every random stream derives from it
  double stopUnshot = 1e-3;       // --stop-unshot F: stop once unshot < F * emitted power
  uint64_t maxShots = 0;          // --max-shots; 0: none
  double maxSeconds = 0.0;        // --max-seconds; 0: none
  int width = 512;                // --width, --height: the image in pixels
  int height = 512;
  bool hasCamera = false;  // --camera given: `camera` as given (else init chooses one)
  Camera camera;
  bool hasView = false;  // --view SIDE: that side's camera instead of the chosen one
  ViewSide view = ViewSide::kFront;
  bool hasExposure = false;  // --exposure given (else automatic)
  float exposure = 1.0f;
  bool quiet = false;       // --quiet: no progress line
  int envs[3] = {1, 1, 1};  // --envs NX[xNY[xNZ]] (or the grid --envs auto:N chose, at init)
  bool hasEnvs = false;     // --envs given (else --ranks N > 1 or an MPI world > 1 means auto:N)
  // --envs auto[:N]: N environments (default: --ranks), the grid's shape and
  // its split planes chosen at init from the scene (partition.h, WorkSplitter).
  bool envsAuto = false;
  int envsAutoCount = 0;
  // R by default: every ray absorbed in exactly one environment, and its
  // packets go only where its rays go. --mask-res alone selects B.
  MaskMethod maskMethod = MaskMethod::kR;
  bool hasMaskMethod = false;
  bool hasMaskRes = false;
  uint32_t maskRes = 50;
  // --sub-grids N: a top grid cell with at least N references gets a grid
  // of its own (Grid::Nest's minRefs, the same default); 0: one uniform grid.
  uint32_t subGrids = 32;
  // --foreign-mask-res R: several environments gather every environment's
  // emitters per pixel, through R x 4R transit masks (foreign_light.h); 0: off.
  uint32_t foreignMaskRes = 32;
  // Round size (ResolveRounds). --round-shots K: at most K shots per
  // environment per round. --round-work N: a round ends for an environment
  // once its work reaches N, work being a count of its rays' grid steps
  // (cells entered plus patches tested: Grid::steps) plus a ray's, a hit's
  // and a shot's charge (WorkCostsOf the mask method, work.h): a count, so
  // rounds never depend on the machine's speed; 0: no limit. With several
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
  uint32_t maskCacheKiB = 8192;    // --mask-cache: B/C centre masks kept per environment
  std::vector<uint32_t> envOrder;  // --env-order: a permutation of the environments
  std::string transport;           // --transport loop|pipe|mpi; empty: the binary's default
  int ranks = 1;                   // --ranks N (pipe)
  // --rank-timeout S: a peer silent that long ends the run; 0: never.
  double rankTimeout = kDefaultRankTimeout;
  uint64_t memBudget = 0;  // --mem-budget BYTES per rank; 0: none
  // --checkpoint DIR: the solve's state written there at round ends, every
  // --checkpoint-every S seconds of solve (0: every round) and on SIGINT,
  // SIGTERM or SIGHUP; --resume DIR: the solve continued from DIR's newest
  // checkpoint (and checkpointed there, unless --checkpoint names another).
  std::string checkpointDir;
  double checkpointEvery = 300.0;
  std::string resumeDir;
  // The arguments a checkpoint must agree with (checkpoint.h): every option
  // given whose table row says it changes the result (ResumeRule::kMustMatch)
  // with its value as given; the scene is compared by its bytes and --envs
  // as EnvSpec.
  std::vector<std::string> resultArgs;
  bool json = false;        // footprint --json
  std::string reference;    // --reference REF.pfm: the error of the image against it
  uint64_t errorEvery = 0;  // --error-every K shots (with --reference); 0: at the end only
  // --exclude MASK.pgm (render with --reference, compare): pixels left out
  // of the error.
  std::string exclude;
  bool correctUnshot = false;  // --correct-unshot on: patches.csv's b gets kd * ambient
  // --two-sided: every polygon gets a second, reversed copy (its twin), so
  // both sides receive, reflect and show. --two-sided-emitters: emitting
  // polygons get one too (with --two-sided, their twins already exist),
  // and emitters' twins emit Ke as well: twice the emitted power.
  bool twoSided = false;
  bool twoSidedEmitters = false;
  // --direct-samples N: shadow rays per shaded point toward the emitters
  // (direct light gathered per pixel, direct.h); 0: the image shows the
  // solved radiosity alone. -1 (not given): kDefaultDirectSamples
  // (ResolveEnvironments); each of several environments gathers its own
  // emitters.
  int directSamples = -1;
  // --emission-rays F: the share of the rays its power is worth that an
  // emission the pixels gather traces (power allocation). Not given:
  // ResolveEmissionRays.
  double emissionRays = 1.0;
  // --indirect-filter K: smoothing steps of the indirect part on the
  // display lattice (with per-pixel direct light); -1 (not given): from the
  // hits a patch received (Environment::IndirectFilterSteps).
  int indirectFilter = -1;
  bool aa = true;  // --aa on|off: exact pixel coverage (a 1-pixel box filter), or centre samples
  // --smooth on|off: share display values across smoothed polygons (smoothing.h).
  bool smooth = true;
  float creaseDeg = 30.0f;  // --crease DEG: the most two normals may differ by and be smoothed
  double stopError = 0.0;   // --stop-error E: stop when the estimated bias < E; 0: off
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

// The automatic patch size divides the scene's largest extent by this: the
// division that keeps the error against the ground truth smallest at the
// default rays (docs/RESULTS.md compares them).
constexpr float kAutoPatchDivisions = 28.0f;

// The most rays one shot traces (--max-rays under power allocation, --rays
// when fixed): Method R's packet bits, and what sizes a round.
inline uint32_t RayCap(const Options& o) {
  return o.rayAlloc == Options::RayAlloc::kPower ? o.maxRays : o.rays;
}

// The environments a run has, as a checkpoint records them: "auto:N" or
// "NXxNYxNZ" (after SetWorldSize under mpirun).
std::string EnvSpec(const Options& o);

// The default --direct-samples with one environment.
constexpr int kDefaultDirectSamples = 128;
// The default --emission-rays with per-pixel direct light in one environment.
constexpr double kDefaultEmissionRays = 0.125;

// Parses argv (argv[0] is the program). On error returns a Status whose
// message names the flag and the offending value.
Status ParseArgs(int argc, const char* const* argv, Options* options);

// The round size the options give for `numEnvs` environments: fills
// roundShots and roundWork (or roundWorkAuto) when they were not given
// (see Options). Called once the environment count is known.
void ResolveRounds(int numEnvs, Options* options);

// --emission-rays not given: kDefaultEmissionRays with per-pixel direct
// light in one environment; else 1 (with several, the others' pixels show
// an emitter's light from the solve, whose foreign shots trace the rays its
// shots did). Called once the environment count is known, after
// --direct-samples' default.
void ResolveEmissionRays(int numEnvs, Options* options);

// Whether several environments' pixels gather every environment's
// emitters (foreign_light.h): per-pixel direct light and --foreign-mask-res.
inline bool GathersForeign(const Options& o) {
  return o.directSamples > 0 && o.foreignMaskRes > 0;
}

// The --emission-rays a solve uses: 1 without per-pixel direct light,
// whatever was given (the solve is then the image).
inline double SolveEmissionRays(const Options& o) {
  return o.directSamples > 0 ? o.emissionRays : 1.0;
}

// The default --queue: numEnvs x roundShots slots (admission shares the
// free slots among the environments, so that is what lets each make a
// whole round), but at most kAutoQueueShots an environment and
// kAutoQueueBytes of `packetBytes` slots, and at least kMinAutoQueue. Why
// both bounds: too few slots make a split solve take many rounds (each
// environment waits for room to admit foreign shooters); too many an
// environment let it shoot its weak local patches while strong foreign
// power waits in the queue, which costs shots on stiff scenes (docs/DESIGN.md,
// "Packets, queues, rounds").
constexpr uint64_t kAutoQueueBytes = 1u << 20;
constexpr uint32_t kMinAutoQueue = 64;
constexpr uint32_t kAutoQueueShots = 64;
uint32_t AutoQueue(int numEnvs, uint32_t roundShots, uint64_t packetBytes);

// The one rule for --envs from the rank count: a run of `ranks` > 1 ranks
// without --envs has --envs auto, one environment a rank (at most
// kMaxAutoEnvs). Sets envsAuto and envsAutoCount; true when it changed
// them (no --envs, more than one rank, not already auto). ParseArgs applies
// it for --ranks, SetWorldSize for the MPI world.
bool AutoEnvsForRanks(int ranks, Options* options);

// A run of `ranks` ranks (the MPI world): AutoEnvsForRanks, and when that
// changed the options, the grid's placeholder shape and the rounds resolved
// again. True when it changed the options.
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
