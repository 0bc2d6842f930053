// The option table's rows for the scene and its light, the environments,
// the ranks and the checkpoints (options_rows.h).
#include "options_rows.h"

namespace vismask::option_rows {

// The scene as read, its light, and the error measured against a reference.
std::vector<Row> SceneRows() {
  return {
      Flag("--strict", ParseStrict).Help(nullptr, R"(
refuse degenerate, non-planar and self-intersecting
faces (exit 2, file:line) instead of mending them:
by default a non-planar face is triangulated, a
repeated or collinear corner removed, and a face with
no area or crossing edges dropped, each kind counted
in one warning line; and refuse faces before any
usemtl, undefined materials, a missing MTL file and
a texture not found as written (by default grey
Kd 0.5, or the texture found in another letter case
or dropped, each with one warning line))"),
      Custom("--emit", ParseEmit)
          .Help("NAME=R,G,B", R"(
make material NAME an emitter of exitance Ke =
(R, G, B), each >= 0, replacing the MTL's Ke (said
in a warning when that was not 0); NAME=ka takes the
material's Ka (scenes that give the light's strength
there); repeatable; a NAME no MTL defines exits 2)")
          .Usage(),
      Custom("--sky", ParseSkyOption)
          .Help("R,G,B", R"(
light from a uniform sky of radiance (R, G, B), each
>= 0 (W/m^2/sr of scene units), in every direction
the scene does not block, as a path tracer's constant
world colour; the scene then need not emit)")
          .More("--sky FILE.hdr", R"(
light from a sky map: an equirectangular Radiance HDR
image of the radiance in each direction, oriented as
Blender's default equirectangular world on a Y-up
scene (the centre looks along +X, the top is +Y,
three quarters across looks along +Z); a path tracer's
world environment texture. A path ending in .hdr or
.pic, or holding a '/', is a file)")
          .Usage()
          .Json("sky"),
      Custom("--sun", ParseSunOption)
          .Help("X,Y,Z,R,G,B[,DEG]", R"(
light from a sun in direction (X, Y, Z) (towards
it), of irradiance (R, G, B) on a surface facing it,
DEG degrees across (0 to 90; 0.53). Sky and sun shoot
into the scene from its box's faces: the box and the
patch size stay the scene's)")
          .Usage()
          .Json("sun"),
      Flag("--two-sided", &O::twoSided)
          .Help(nullptr, R"(
both sides of every polygon receive, reflect and show
(for scenes wound inconsistently): each polygon is
meshed twice, the copy reversed; patches double.
An emitter's copy reflects but does not emit unless
--two-sided-emitters is given too)")
          .Json("two_sided"),
      Flag("--two-sided-emitters", &O::twoSidedEmitters)
          .Help(nullptr, R"(
emitters emit from both sides, Ke from each: twice
the emitted power of the one-sided emitter (their
back sides also reflect))")
          .Json("two_sided_emitters"),
      Text("--reference", &O::reference, "a PFM file")
          .Help("REF.pfm", R"(
measure the image's relative RMSE against REF.pfm
(same size) when the solve ends, in convergence.csv
and run.json; the time it takes is not solve time)")
          .Json("reference"),
      Count("--error-every", &O::errorEvery, 1, kNoLimit, "a positive number of shots")
          .Help("K", "with --reference: also every K shots during the solve")
          .Json("error_every"),
      Text("--exclude", &O::exclude, "a PGM file")
          .Help("MASK.pgm", R"(
with --reference: leave out of the relative RMSE the
pixels where MASK.pgm (8-bit PGM, same size) is
nonzero, e.g. visible emitters (tools/reference))")
          .Json("exclude"),
      Choice("--correct-unshot", &O::correctUnshot, "on|off")
          .Help("on|off", R"(
on: patches.csv's b includes kd * the ambient term
(Cohen's estimate of what the still-unshot power will
add, which the image always shows); default off)")
          .Json("correct_unshot"),
      Number("--stop-error", &O::stopError, 0.0, 1.0, "a number in (0, 1)")
          .Open(true, true)
          .Help("E", R"(
also stop when the estimated relative bias of b from
the power not yet shot is below E, 0 < E < 1: the
share rho*U/(1-rho) of the radiosity power still to
come (times 1-rho with --correct-unshot on), which
unlike --stop-unshot counts the 1/(1-rho)
amplification of stiff scenes (default: off))")
          .Json("stop_error"),
      Flag("--json", ParseJson).Help(nullptr, "footprint only: the report as JSON on stdout"),
  };
}

// How the scene is split into environments and what travels between them.
std::vector<Row> EnvironmentRows() {
  return {
      Custom("--envs", ParseEnvs)
          .Given(&O::hasEnvs)
          .Help("NX[xNY[xNZ]]", R"(
split the scene's box into a grid of environments
(default 1); each owns only its own patches and grid)")
          .More("--envs auto[:N]", R"(
N environments (default: --ranks, or under mpirun the
world size), the grid's shape and its split planes
chosen from the scene: each axis cut where the
patches (estimated from the polygons' areas) divide
evenly, so every slab holds about as many; still a
grid. The default when --envs is not given and the
run has more than one rank)")
          .Envs()
          .Usage()
          .Resume(ResumeRule::kByMeaning)
          .Json("envs"),
      Choice("--mask-method", &O::maskMethod, "none|A|B|C|R")
          .Given(&O::hasMaskMethod)
          .Help("M", R"(
R | B | C | A | none (default R): what a shooter
sends on to its neighbours. R: one bit per ray of
the shot (--rays or --max-rays bits), each ray routed
to the neighbour it leaves for and absorbed in exactly
one environment; a neighbour no ray reaches never
hears of the shot. B: a hemisphere mask with one ray
from the shooter's centre per open pixel (exact at its
resolution; the paper's Method B); C: pixels the rays
only hit close, only passed stay open, B's ray for the
rest; A: from the form-factor rays that hit (cheap,
leaks light where no ray hit); none: no mask (light
passes occluders))")
          .Envs()
          .Json("mask_method"),
      Count("--mask-res", &O::maskRes, 1, 4096, "an integer in [1, 4096]")
          .Given(&O::hasMaskRes)
          .Help("R", R"(
hemisphere mask resolution (A, B, C): R rows (theta) x
4R columns (phi), 1 <= R <= 4096 (default 50); given
without --mask-method it selects B)")
          .Envs()
          .Json("mask_res"),
      Count("--foreign-mask-res", &O::foreignMaskRes, 0, 256, "an integer in [0, 256]")
          .Help("R", R"(
several environments, with --direct-samples: the
pixels gather every environment's emitters, the part
of a shadow ray in another environment read from that
environment's transit mask for the emitter patch, R x
4R directions from its centre (docs/design/direct-
light.md); 0: each gathers only its own emitters, the
others' light shown from the solve. Default 32)")
          .Envs()
          .Json("foreign_mask_res"),
      Count("--round-shots", &O::roundShots, 1, 1e6, "an integer in [1, 1e6]")
          .Given(&O::hasRoundShots)
          .Help("K", R"(
at most K shots per environment per round (default
with several environments or with --round-work: 256,
fewer when 6 packets a shot would fill more than
512 KiB; otherwise 1).
Given alone (no --round-work), the rounds of before:
K shots, no work limit)")
          .Envs()
          .Json("round_shots"),
      Count("--round-work", &O::roundWork, 0, 1e15, "an integer in [0, 1e15] (0: no limit)")
          .Given(&O::hasRoundWork)
          .Help("N", R"(
a round ends for an environment once its shots have
done N units of work: grid steps (cells entered plus
patches tested), plus, with Method R, 10 a ray, 9 a
hit and 41 a shot (with A, B, C and none: 32, 40 and
12288); a count that tracks CPU time but never
depends on it, so rounds are the same whatever the
machine, ranks or transport. Default with several
environments: about 32 full shots' worth (32 x
(--max-rays, or --rays, x (the cube root of an
environment's grid cells + a ray's and a hit's work)
+ a shot's)); 0: no limit)")
          .Envs()
          .Json("round_work"),
      Choice("--centre-rays", &O::centreRays, "all|read|auto")
          .Help("W", R"(
all | read | auto (default auto): which open pixels
Method B casts a centre ray through. all: every one
that leads to a neighbour, each packet's priority and
power in flight from its whole mask; read: only those
the shot's rays will read downstream (each
environment's rays are known from the shot's key), the
priority and power in flight from the receiver's rays
that pass; auto: read for a shot whose rays x
(environments - 1) are at most a quarter of the 4R^2
pixels, else all. The same light lands at the
pixels read; the shots' order may differ)")
          .Envs()
          .Json("centre_rays"),
      Count("--mask-cache", &O::maskCacheKiB, 0, 67108864, "an integer in [0, 2^26] (KiB)")
          .Help("K", R"(
KiB per environment for Methods B and C's centre masks
of local shooters, kept for their later shots (the
mask depends only on the shooter); same output,
fewer centre rays; 0: none (default 8192))")
          .Envs(),
      Count("--queue", &O::queue, 1, 1e6, "an integer in [1, 1e6]")
          .Given(&O::hasQueue)
          .Help("Q", R"(
foreign shooters an environment holds at once; a
full queue holds back new ones (default: the
environments x the round's shots, so that every
environment can make a whole round, but at most 64
an environment and 1 MiB of slots; at least 64))")
          .Envs()
          .Json("queue"),
  };
}

// Where the ranks run, how they are checked on, and the checkpoints.
std::vector<Row> RunRows() {
  return {
      Count("--ranks", &O::ranks, 1, 256, "an integer in [1, 256]")
          .Help("N", R"(
run on N processes on this host, connected by POSIX
pipes (default 1); environments are dealt to ranks in
contiguous blocks; N <= the number of environments)")
          .Envs()
          .Usage()
          .MayDiffer(),
      Choice("--transport", &O::transport, "loop|pipe|mpi")
          .Help("T", R"(
loop | pipe | mpi: loop keeps every environment in
one process; pipe is the default for --ranks > 1; mpi
is what build/vismask-mpi uses (under mpirun))")
          .Envs()
          .MayDiffer(),
      Number("--rank-timeout", &O::rankTimeout, 0.0, 1e9, "seconds in [0, 1e9] (0: none)")
          .Help("S", R"(
a rank that waits for a peer and hears nothing from
it for S seconds ends the run (exit 3, naming the
silent rank; a stopped or hung rank). The limit is
S or 10 times the longest wait of the run so far,
whichever is longer, so S must exceed how much
longer one rank's round or init takes than another's
and rank 0's output writing (default 60; 0: wait
forever))")
          .Envs()
          .MayDiffer()
          .Json("rank_timeout"),
      Text("--checkpoint", &O::checkpointDir, "a directory")
          .Help("DIR", R"(
write the solve's state to DIR at a round's end every
--checkpoint-every seconds of solve, and when the run
gets SIGINT, SIGTERM or SIGHUP (it then ends with
128 + the signal, no outputs): one file per
environment on the rank holding it, written
atomically, and DIR/manifest on rank 0 naming the
newest complete checkpoint (a second signal ends the
run at once))")
          .Envs()
          .MayDiffer(),
      Number("--checkpoint-every", &O::checkpointEvery, 0.0, 1e9,
             "seconds in [0, 1e9] (0: every round)")
          .Help("S", R"(
seconds of solve between checkpoints (default 300;
0: every round))")
          .Envs()
          .MayDiffer(),
      // The options listed as free to differ are the table's (HelpText).
      Text("--resume", &O::resumeDir, "a directory")
          .Help("DIR",
                "go on from DIR's newest complete checkpoint (and keep checkpointing there): the "
                "outputs are the bytes a run never stopped gives. Give the same scene and "
                "options; %may-differ% may differ (without --envs, the checkpoint's "
                "environments); another scene or option is refused (exit 2, naming the "
                "difference). Each rank needs the files of the environments it now holds in DIR")
          .Envs()
          .MayDiffer(),
      Custom("--mem-budget", ParseMemBudget)
          .Help("BYTES", R"(
refuse at init (exit 2, with the numbers) when a rank
would reserve more than BYTES (suffix K, M or G for
KiB, MiB, GiB); a run that starts never runs out)")
          .Envs()
          .MayDiffer(),
      Custom("--env-order", ParseEnvOrder)
          .Help("I,J,...", R"(
run the environments in this order within each round
(a permutation of 0..N-1); a check of determinism:
the results must not change)")
          .Envs(),
  };
}

}  // namespace vismask::option_rows
