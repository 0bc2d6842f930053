// The option table's rows for the scene and its light, the environments,
// the ranks and the checkpoints (options_rows.h).
#include "options_rows.h"

namespace vismask {
namespace option_rows {

using O = Options;

// The scene as read, its light, and the error measured against a reference.
void AddSceneRows(std::vector<Row>* t) {
  t->insert(
      t->end(),
      {
          Flag("--strict", ParseStrict)
              .Help(nullptr,
                    "refuse degenerate, non-planar and self-intersecting\n"
                    "faces (exit 2, file:line) instead of mending them:\n"
                    "by default a non-planar face is triangulated, a\n"
                    "repeated or collinear corner removed, and a face with\n"
                    "no area or crossing edges dropped, each kind counted\n"
                    "in one warning line; and refuse faces before any\n"
                    "usemtl, undefined materials, a missing MTL file and\n"
                    "a texture not found as written (by default grey\n"
                    "Kd 0.5, or the texture found in another letter case\n"
                    "or dropped, each with one warning line)"),
          Custom("--emit", ParseEmit)
              .Help("NAME=R,G,B",
                    "make material NAME an emitter of exitance Ke =\n"
                    "(R, G, B), each >= 0, replacing the MTL's Ke (said\n"
                    "in a warning when that was not 0); NAME=ka takes the\n"
                    "material's Ka (scenes that give the light's strength\n"
                    "there); repeatable; a NAME no MTL defines exits 2")
              .Usage(),
          Custom("--sky", ParseSkyOption)
              .Help("R,G,B",
                    "light from a uniform sky of radiance (R, G, B), each\n"
                    ">= 0 (W/m^2/sr of scene units), in every direction\n"
                    "the scene does not block, as a path tracer's constant\n"
                    "world colour; the scene then need not emit")
              .More("--sky FILE.hdr",
                    "light from a sky map: an equirectangular Radiance HDR\n"
                    "image of the radiance in each direction, oriented as\n"
                    "Blender's default equirectangular world on a Y-up\n"
                    "scene (the centre looks along +X, the top is +Y,\n"
                    "three quarters across looks along +Z); a path tracer's\n"
                    "world environment texture. A path ending in .hdr or\n"
                    ".pic, or holding a '/', is a file")
              .Usage()
              .Json("sky"),
          Custom("--sun", ParseSunOption)
              .Help("X,Y,Z,R,G,B[,DEG]",
                    "light from a sun in direction (X, Y, Z) (towards\n"
                    "it), of irradiance (R, G, B) on a surface facing it,\n"
                    "DEG degrees across (0 to 90; 0.53). Sky and sun shoot\n"
                    "into the scene from its box's faces: the box and the\n"
                    "patch size stay the scene's")
              .Usage()
              .Json("sun"),
          Flag("--two-sided", &O::twoSided)
              .Help(nullptr,
                    "both sides of every polygon receive, reflect and show\n"
                    "(for scenes wound inconsistently): each polygon is\n"
                    "meshed twice, the copy reversed; patches double.\n"
                    "An emitter's copy reflects but does not emit unless\n"
                    "--two-sided-emitters is given too")
              .Json("two_sided"),
          Flag("--two-sided-emitters", &O::twoSidedEmitters)
              .Help(nullptr,
                    "emitters emit from both sides, Ke from each: twice\n"
                    "the emitted power of the one-sided emitter (their\n"
                    "back sides also reflect)")
              .Json("two_sided_emitters"),
          Text("--reference", &O::reference, "a PFM file")
              .Help("REF.pfm",
                    "measure the image's relative RMSE against REF.pfm\n"
                    "(same size) when the solve ends, in convergence.csv\n"
                    "and run.json; the time it takes is not solve time")
              .Json("reference"),
          Count("--error-every", &O::errorEvery, 1, kNoLimit, "a positive number of shots")
              .Help("K", "with --reference: also every K shots during the solve")
              .Json("error_every"),
          Text("--exclude", &O::exclude, "a PGM file")
              .Help("MASK.pgm",
                    "with --reference: leave out of the relative RMSE the\n"
                    "pixels where MASK.pgm (8-bit PGM, same size) is\n"
                    "nonzero, e.g. visible emitters (tools/reference)")
              .Json("exclude"),
          Choice("--correct-unshot", &O::correctUnshot, "on|off")
              .Help("on|off",
                    "on: patches.csv's b includes kd * the ambient term\n"
                    "(Cohen's estimate of what the still-unshot power will\n"
                    "add, which the image always shows); default off")
              .Json("correct_unshot"),
          Number("--stop-error", &O::stopError, 0.0, 1.0, "a number in (0, 1)")
              .Open(true, true)
              .Help("E",
                    "also stop when the estimated relative bias of b from\n"
                    "the power not yet shot is below E, 0 < E < 1: the\n"
                    "share rho*U/(1-rho) of the radiosity power still to\n"
                    "come (times 1-rho with --correct-unshot on), which\n"
                    "unlike --stop-unshot counts the 1/(1-rho)\n"
                    "amplification of stiff scenes (default: off)")
              .Json("stop_error"),
          Flag("--json", ParseJson).Help(nullptr, "footprint only: the report as JSON on stdout"),
      });
}

// How the scene is split into environments and what travels between them.
void AddEnvironmentRows(std::vector<Row>* t) {
  t->insert(
      t->end(),
      {
          Custom("--envs", ParseEnvs)
              .Given(&O::hasEnvs)
              .Help("NX[xNY[xNZ]]",
                    "split the scene's box into a grid of environments\n"
                    "(default 1); each owns only its own patches and grid")
              .More("--envs auto[:N]",
                    "N environments (default: --ranks, or under mpirun the\n"
                    "world size), the grid's shape and its split planes\n"
                    "chosen from the scene: each axis cut where the\n"
                    "patches (estimated from the polygons' areas) divide\n"
                    "evenly, so every slab holds about as many; still a\n"
                    "grid. The default when --envs is not given and the\n"
                    "run has more than one rank")
              .Envs()
              .Usage()
              .Resume(ResumeRule::kByMeaning)
              .Json("envs"),
          Choice("--mask-method", &O::maskMethod, "none|A|B|C|R")
              .Given(&O::hasMaskMethod)
              .Help("M",
                    "R | B | C | A | none (default R): what a shooter\n"
                    "sends on to its neighbours. R: one bit per ray of\n"
                    "the shot (--rays or --max-rays bits), each ray routed\n"
                    "to the neighbour it leaves for and absorbed in exactly\n"
                    "one environment; a neighbour no ray reaches never\n"
                    "hears of the shot. B: a hemisphere mask with one ray\n"
                    "from the shooter's centre per open pixel (exact at its\n"
                    "resolution; the paper's Method B); C: pixels the rays\n"
                    "only hit close, only passed stay open, B's ray for the\n"
                    "rest; A: from the form-factor rays that hit (cheap,\n"
                    "leaks light where no ray hit); none: no mask (light\n"
                    "passes occluders)")
              .Envs()
              .Json("mask_method"),
          Count("--mask-res", &O::maskRes, 1, 4096, "an integer in [1, 4096]")
              .Given(&O::hasMaskRes)
              .Help("R",
                    "hemisphere mask resolution (A, B, C): R rows (theta) x\n"
                    "4R columns (phi), 1 <= R <= 4096 (default 50); given\n"
                    "without --mask-method it selects B")
              .Envs()
              .Json("mask_res"),
          Count("--round-shots", &O::roundShots, 1, 1e6, "an integer in [1, 1e6]")
              .Given(&O::hasRoundShots)
              .Help("K",
                    "at most K shots per environment per round (default\n"
                    "with several environments or with --round-work: 256,\n"
                    "fewer when 6 packets a shot would fill more than\n"
                    "512 KiB; otherwise 1).\n"
                    "Given alone (no --round-work), the rounds of before:\n"
                    "K shots, no work limit")
              .Envs()
              .Json("round_shots"),
          Count("--round-work", &O::roundWork, 0, 1e15, "an integer in [0, 1e15] (0: no limit)")
              .Given(&O::hasRoundWork)
              .Help("N",
                    "a round ends for an environment once its shots have\n"
                    "done N units of work: grid steps (cells entered plus\n"
                    "patches tested), plus, with Method R, 10 a ray, 9 a\n"
                    "hit and 41 a shot (with A, B, C and none: 32, 40 and\n"
                    "12288); a count that tracks CPU time but never\n"
                    "depends on it, so rounds are the same whatever the\n"
                    "machine, ranks or transport. Default with several\n"
                    "environments: about 32 full shots' worth (32 x\n"
                    "(--max-rays, or --rays, x (the cube root of an\n"
                    "environment's grid cells + a ray's and a hit's work)\n"
                    "+ a shot's)); 0: no limit")
              .Envs()
              .Json("round_work"),
          Choice("--centre-rays", &O::centreRays, "all|read|auto")
              .Help("W",
                    "all | read | auto (default auto): which open pixels\n"
                    "Method B casts a centre ray through. all: every one\n"
                    "that leads to a neighbour, each packet's priority and\n"
                    "power in flight from its whole mask; read: only those\n"
                    "the shot's rays will read downstream (each\n"
                    "environment's rays are known from the shot's key), the\n"
                    "priority and power in flight from the receiver's rays\n"
                    "that pass; auto: read for a shot whose rays x\n"
                    "(environments - 1) are at most a quarter of the 4R^2\n"
                    "pixels, else all. The same light lands at the\n"
                    "pixels read; the shots' order may differ")
              .Envs()
              .Json("centre_rays"),
          Count("--mask-cache", &O::maskCacheKiB, 0, 67108864, "an integer in [0, 2^26] (KiB)")
              .Help("K",
                    "KiB per environment for Methods B and C's centre masks\n"
                    "of local shooters, kept for their later shots (the\n"
                    "mask depends only on the shooter); same output,\n"
                    "fewer centre rays; 0: none (default 8192)")
              .Envs(),
          Count("--queue", &O::queue, 1, 1e6, "an integer in [1, 1e6]")
              .Given(&O::hasQueue)
              .Help("Q",
                    "foreign shooters an environment holds at once; a\n"
                    "full queue holds back new ones (default: the\n"
                    "environments x the round's shots, so that every\n"
                    "environment can make a whole round, but at most 64\n"
                    "an environment and 1 MiB of slots; at least 64)")
              .Envs()
              .Json("queue"),
      });
}

// Where the ranks run, how they are checked on, and the checkpoints.
void AddRunRows(std::vector<Row>* t) {
  t->insert(
      t->end(),
      {
          Count("--ranks", &O::ranks, 1, 256, "an integer in [1, 256]")
              .Help("N",
                    "run on N processes on this host, connected by POSIX\n"
                    "pipes (default 1); environments are dealt to ranks in\n"
                    "contiguous blocks; N <= the number of environments")
              .Envs()
              .Usage()
              .MayDiffer(),
          Choice("--transport", &O::transport, "loop|pipe|mpi")
              .Help("T",
                    "loop | pipe | mpi: loop keeps every environment in\n"
                    "one process; pipe is the default for --ranks > 1; mpi\n"
                    "is what build/vismask-mpi uses (under mpirun)")
              .Envs()
              .MayDiffer(),
          Number("--rank-timeout", &O::rankTimeout, 0.0, 1e9, "seconds in [0, 1e9] (0: none)")
              .Help("S",
                    "a rank that waits for a peer and hears nothing from\n"
                    "it for S seconds ends the run (exit 3, naming the\n"
                    "silent rank; a stopped or hung rank). The limit is\n"
                    "S or 10 times the longest wait of the run so far,\n"
                    "whichever is longer, so S must exceed how much\n"
                    "longer one rank's round or init takes than another's\n"
                    "and rank 0's output writing (default 60; 0: wait\n"
                    "forever)")
              .Envs()
              .MayDiffer()
              .Json("rank_timeout"),
          Text("--checkpoint", &O::checkpointDir, "a directory")
              .Help("DIR",
                    "write the solve's state to DIR at a round's end every\n"
                    "--checkpoint-every seconds of solve, and when the run\n"
                    "gets SIGINT, SIGTERM or SIGHUP (it then ends with\n"
                    "128 + the signal, no outputs): one file per\n"
                    "environment on the rank holding it, written\n"
                    "atomically, and DIR/manifest on rank 0 naming the\n"
                    "newest complete checkpoint (a second signal ends the\n"
                    "run at once)")
              .Envs()
              .MayDiffer(),
          Number("--checkpoint-every", &O::checkpointEvery, 0.0, 1e9,
                 "seconds in [0, 1e9] (0: every round)")
              .Help("S",
                    "seconds of solve between checkpoints (default 300;\n"
                    "0: every round)")
              .Envs()
              .MayDiffer(),
          // The options listed as free to differ are the table's (HelpText).
          Text("--resume", &O::resumeDir, "a directory")
              .Help(
                  "DIR",
                  "go on from DIR's newest complete checkpoint (and keep checkpointing there): the "
                  "outputs are the bytes a run never stopped gives. Give the same scene and "
                  "options; "
                  "%may-differ% may differ (without --envs, the checkpoint's environments); "
                  "another "
                  "scene or option is refused (exit 2, naming the difference). Each rank needs the "
                  "files of the environments it now holds in DIR")
              .Envs()
              .MayDiffer(),
          Custom("--mem-budget", ParseMemBudget)
              .Help("BYTES",
                    "refuse at init (exit 2, with the numbers) when a rank\n"
                    "would reserve more than BYTES (suffix K, M or G for\n"
                    "KiB, MiB, GiB); a run that starts never runs out")
              .Envs()
              .MayDiffer(),
          Custom("--env-order", ParseEnvOrder)
              .Help("I,J,...",
                    "run the environments in this order within each round\n"
                    "(a permutation of 0..N-1); a check of determinism:\n"
                    "the results must not change")
              .Envs(),
      });
}

}  // namespace option_rows
}  // namespace vismask
