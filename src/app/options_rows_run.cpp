// The option table's rows for where a run writes, how big a solve is,
// when it stops, and the image (options_rows.h).
#include "options_rows.h"

namespace vismask::option_rows {

namespace {

// The seed and when the solve stops (SolveRows' last rows).
std::vector<Row> StopRows() {
  return {
      Count("--seed", &O::seed, 0, kNoLimit, "an unsigned 64-bit integer")
          .Help("S", "random seed, unsigned 64-bit (default 1)")
          .Json("seed"),
      Number("--stop-unshot", &O::stopUnshot, 0.0, 1.0, "a number in [0, 1)")
          .Open(false, true)
          .Help("F", R"(
stop when unshot power < F * emitted power, 0 <= F < 1
(default 1e-3); 0 needs another stop as well)")
          .Json("stop_unshot"),
      Count("--max-shots", &O::maxShots, 1, kNoLimit, "a positive integer")
          .Help("N", "stop after N shots (default: no limit)")
          .Json("max_shots"),
      Number("--max-seconds", &O::maxSeconds, 0.0, kNoLimit, "a number of seconds > 0")
          .Open(true, false)
          .Help("T", R"(
stop after T seconds of solving (default: no limit;
a time limit makes the result depend on speed).
Without --emitted-rays (one rank, power allocation)
it plans them from the rays per second timed at
init (run.json: emitted_rays_planned), and in one
environment paces the solve to end near T, its
rays per unit power re-planned as it goes (run.json:
emitted_rays_paced); without --patch-size, larger
patches where T is too short for the automatic
ones (run.json: patch_size_planned))")
          .Usage()
          .Json("max_seconds"),
  };
}

}  // namespace

// Where the run writes, how big a solve is and when it stops.
std::vector<Row> SolveRows() {
  std::vector<Row> rows = {
      Text("--out", &O::outDir, "a directory")
          .Help("DIR", "output directory (default out/); created if missing")
          .Usage()
          .MayDiffer(),
      Custom("--export", ParseExport)
          .Help("FILE.glb", R"(
also write the solved mesh as binary glTF 2.0 to
FILE.glb (a path from the current directory, not
under --out; its directory must exist): every
patch's lattice vertices and triangles, COLOR_0 the
linear display radiance image.pfm shows there
(emission included, unclamped), an unlit material;
scene units and the OBJ's axes)")
          .Usage()
          .MayDiffer()
          .Json("export"),
      Number("--patch-size", &O::patchSize, 0.0, 3.4e38, "a length > 0")
          .Open(true, false)
          .Tiny("a length float can hold (>= 1.2e-38; smaller is 0)")
          .Help("L", R"(
longest patch edge, scene units (default: largest
scene extent / 28))")
          .Usage()
          .Json("patch_size"),
      Choice("--ray-alloc", &O::rayAlloc, "power|fixed")
          .Given(&O::hasRayAlloc)
          .Help("power|fixed", R"(
how many Monte Carlo rays a shot traces. power (the
default): in proportion to the shot's unshot power,
--emitted-rays for the whole emitted power, at least
--min-rays; a shot worth more than --max-rays shoots
that share of its power and keeps the rest for later
shots. fixed: --rays every shot (the old default))")
          .Json("ray_alloc"),
      Count("--rays", &O::rays, 1, 1e8, "an integer in [1, 1e8]")
          .Given(&O::hasRays)
          .Help("N", R"(
fixed: Monte Carlo rays per shot (4096); given alone it
selects --ray-alloc fixed)")
          .Json("rays"),
      Count("--emitted-rays", &O::emittedRays, 1, 1e12, "an integer in [1, 1e12]")
          .Given(&O::hasEmittedRays)
          .Help("M", R"(
power: the rays the emitted power is worth (4000000);
a shot of power P traces M * P / emitted power rays,
rounded up or down at random from the shot's stream)")
          .Json("emitted_rays"),
      Count("--min-rays", &O::minRays, 1, 1e8, "an integer in [1, 1e8]")
          .Help("F", "power: the fewest rays a shot traces (default 16)")
          .Json("min_rays"),
      Count("--max-rays", &O::maxRays, 1, 1e8, "an integer in [1, 1e8]")
          .Help("C", R"(
power: the most rays a shot traces (default 8192);
also Method R's packet bits)")
          .Json("max_rays"),
      Choice("--sampler", &O::sobol, "sobol|random")
          .Help("S", R"(
sobol (default): scrambled Sobol' points over a
shot's origin x direction; random: independent draws)")
          .Json("sampler"),
      Choice("--origins", &O::originsByPower, "power|uniform")
          .Help("O", R"(
where a patch's rays leave from: power (default): its
elements (or, unsplit, its quarters) by the light each
received (one environment), or its cells not buried
in a solid (several), none from a part under a block
or behind a lamp; uniform: anywhere on the patch alike)")
          .Json("origins"),
      Choice("--sequence", &O::patchSequence, "patch|shot")
          .Help("Q", R"(
with Sobol' points in one environment: patch
(default): a patch's shots continue one sequence, so
its rays over all its shots are one stratified set
(an emitter's excepted); shot: each shot its own, as
several environments draw them)")
          .Json("sequence"),
      Count("--ray-budget", &O::rayBudget, 1, kNoLimit, "a positive integer")
          .Help("N", "stop once N form-factor rays have been traced")
          .Json("ray_budget"),
      Count("--sub-grids", &O::subGrids, 0, 1e6, "an integer in [0, 1e6]")
          .Help("N", R"(
a cell of an environment's ray-casting grid that
holds N or more patch references (not all on one
plane) gets a grid of its own (default 32); 0: one
uniform grid. The same image and patches either way
in one environment; only the speed and the grid's
bytes change (and, with several environments, the
rounds, which count grid steps))")
          .Json("sub_grids"),
      Count("--elements", &O::elementsPerPatch, 0, 1024, "an integer in [0, 1024]").Help("K", R"(
receivers finer than shooters: each patch is a
quadtree of elements that split where the radiosity
received changes fast (shadow edges, contact shadows,
corners); the pool holds K elements per patch beyond
the patches themselves (default 8; 0: no refinement).
When it is used up refinement stops (run.json says so))"),
      Count("--element-depth", &O::elementDepth, 0, 16, "an integer in [0, 16]").Help("D", R"(
the deepest an element splits, 0-16 (default 4: 1/16
of the patch's edge))"),
      Number("--element-spread", &O::elementSpread, 0.0, 100.0, "a number in [0, 100]")
          .Help("S", R"(
an element splits only where its quarters' radiosity
differs by more than S (relative RMS, default 0.1) and
more than its Monte Carlo noise explains)"),
      Number("--element-chi2", &O::elementChi2, 0.0, 1e6, "a number in [0, 1e6]").Help("X", R"(
... explains: chi-square (3 dof) of its quarters
against an even spread above X (default 20))"),
  };
  for (Row& r : StopRows()) rows.push_back(r);
  return rows;
}

// The image: its size, camera, exposure and filtering.
std::vector<Row> ImageRows() {
  return {
      Count("--width", &O::width, 1, 16384, "an integer in [1, 16384]")
          .Help("W", "image width in pixels (default 512)")
          .Usage()
          .Json("width"),
      Count("--height", &O::height, 1, 16384, "an integer in [1, 16384]")
          .Help("H", "image height in pixels (default 512)")
          .Usage()
          .Json("height"),
      Custom("--camera", ParseCamera)
          .Given(&O::hasCamera)
          .Help("ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg", R"(
eye, target, up and vertical field of view (default:
the --view side that shows the most front-facing
surface, front on a tie))")
          .Usage()
          .Json("camera"),
      Choice("--view", &O::view, "front|back|left|right|top|bottom")
          .Given(&O::hasView)
          .Help("SIDE", R"(
front | back | left | right | top | bottom: frame the
scene's bounding box from that side, its larger extent
filling the view: front from -z looking +z, back from
+z, left from +x and right from -x (as they appear in
the front view), top from +y, bottom from -y. Without
--view or --camera, the side is chosen by rays from
each side's eye: the most image showing the front of
a polygon, occlusion included. Not with --camera)")
          .Usage()
          .Json("view"),
      Number("--exposure", &O::exposure, 0.0, 3.4e38, "a number > 0")
          .Open(true, false)
          .Tiny("a number float can hold (>= 1.2e-38; smaller is 0)")
          .Given(&O::hasExposure)
          .Help("E", "linear exposure for image.png (default: automatic)")
          .Usage()
          .Json("exposure"),
      Choice("--aa", &O::aa, "on|off")
          .Help("on|off", R"(
on: each pixel is the exact area-weighted mean of what
it sees (a 1-pixel box filter: every piece's coverage
of the pixel square, computed analytically); off: the
pixel centre only, quads as two Gouraud triangles
(the images before --aa existed); default on)")
          .Json("aa"),
      Count("--direct-samples", &O::directSamples, 0, 1024, "an integer in [0, 1024]")
          .Help("N", R"(
direct light gathered per pixel, 0..1024: the image's
direct part is each emitter's exact unoccluded
irradiance times the share of its shadow rays that
reach it, N rays spread over the emitters by what
each brings there (rays to the emitters' corners and
4 first; all N only where those disagree; a piece
covering part of a pixel its share of N); the solve
supplies the rest; 0: the solved radiosity alone
(the images before it). With several environments
each gathers every environment's emitters
(--foreign-mask-res); the sun's light is the
solve's. Default 128)")
          .Json("direct_samples"),
      Number("--emission-rays", &O::emissionRays, 0.0, 1.0, "a number in (0, 1]")
          .Open(true, false)
          .Given(&O::hasEmissionRays)
          .Help("F", R"(
power allocation: an emission the pixels gather
(an emitter's own, the sun's, with --direct-samples)
traces F times the rays its power is worth; the
solve's direct part then only feeds later shots.
Default 0.125 with --direct-samples (in several
environments, unless --foreign-mask-res 0), else 1)")
          .Json("emission_rays"),
      Count("--indirect-filter", &O::indirectFilter, 0, 64, "an integer in [0, 64]").Help("K", R"(
with direct light per pixel, the indirect part is
smoothed over each polygon's display lattice, K steps
(each vertex half its own value, half its edge
neighbours' mean, those nothing sees left out; the
outline is extrapolated from inside, as without).
Not given: from the rays a patch received (more steps
the fewer: its noise), 0 once converged; 0: off.
run.json: indirect_filter_steps)"),
      Choice("--smooth", &O::smooth, "on|off")
          .Help("on|off", R"(
on: where polygons with a smoothing group ('s N') or
vertex normals ('vn') meet, the image shades across
them smoothly, within the crease angle; default on)")
          .Json("smooth"),
      Number("--crease", &O::creaseDeg, 0.0, 180.0, "an angle in [0, 180] degrees")
          .Help("DEG", R"(
smoothing's crease angle, 0..180: the most two vertex
normals, or two faces of one smoothing group, may
differ by and be shaded as one surface (default 30))")
          .Json("crease"),
      Flag("--quiet", &O::quiet).Help(nullptr, "no progress line on stderr").Usage().MayDiffer(),
  };
}

}  // namespace vismask::option_rows
