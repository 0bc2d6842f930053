#include "vismask/options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vismask/packet.h"
#include "vismask/partition.h"

namespace vismask {

const char* HelpText() {
  return R"(vismask - fixed-memory progressive-refinement radiosity

usage:
  vismask render SCENE.obj [options]     solve and render a scene
  vismask footprint SCENE.obj [options]  the memory each environment and rank
                                         would reserve, without solving
                                         (render's options; --json for JSON)
  vismask compare A.pfm B.pfm [--exclude MASK.pgm]
                                         relative RMSE and max abs error of A
                                         against B (pixels where MASK.pgm is
                                         nonzero left out)
  vismask view OUT_DIR [--glb NAME.glb] [--port P]
                                         serve the solved mesh (render
                                         --export) in the viewer page on
                                         localhost and print its URL
                                         ('vismask view --help')
  vismask --help                         this text

render options:
  --out DIR            output directory (default out/); created if missing
  --export FILE.glb    also write the solved mesh as binary glTF 2.0 to
                       FILE.glb (a path from the current directory, not
                       under --out; its directory must exist): every
                       patch's lattice vertices and triangles, COLOR_0 the
                       linear display radiance image.pfm shows there
                       (emission included, unclamped), an unlit material;
                       scene units and the OBJ's axes
  --patch-size L       longest patch edge, scene units (default: largest
                       scene extent / 28)
  --ray-alloc power|fixed
                       how many Monte Carlo rays a shot traces. power (the
                       default): in proportion to the shot's unshot power,
                       --emitted-rays for the whole emitted power, at least
                       --min-rays; a shot worth more than --max-rays shoots
                       that share of its power and keeps the rest for later
                       shots. fixed: --rays every shot (the old default)
  --rays N             fixed: Monte Carlo rays per shot (4096); given alone it
                       selects --ray-alloc fixed
  --emitted-rays M     power: the rays the emitted power is worth (4000000);
                       a shot of power P traces M * P / emitted power rays,
                       rounded up or down at random from the shot's stream
  --min-rays F         power: the fewest rays a shot traces (default 16)
  --max-rays C         power: the most rays a shot traces (default 8192);
                       also Method R's packet bits
  --sampler S          sobol (default): scrambled Sobol' points over a
                       shot's origin x direction; random: independent draws
  --ray-budget N       stop once N form-factor rays have been traced
  --elements K         receivers finer than shooters: each patch is a
                       quadtree of elements that split where the radiosity
                       received changes fast (shadow edges, contact shadows,
                       corners); the pool holds K elements per patch beyond
                       the patches themselves (default 8; 0: no refinement).
                       When it is used up refinement stops (run.json says so)
  --element-depth D    the deepest an element splits, 0-16 (default 4: 1/16
                       of the patch's edge)
  --element-spread S   an element splits only where its quarters' radiosity
                       differs by more than S (relative RMS, default 0.1) and
                       more than its Monte Carlo noise explains
  --element-chi2 X     ... explains: chi-square (3 dof) of its quarters
                       against an even spread above X (default 20)
  --seed S             random seed, unsigned 64-bit (default 1)
  --stop-unshot F      stop when unshot power < F * emitted power, 0 <= F < 1
                       (default 1e-3)
  --max-shots N        stop after N shots (default: no limit)
  --max-seconds T      stop after T seconds of solving (default: no limit;
                       a time limit makes the result depend on speed)
  --width W, --height H   image size in pixels (default 512 x 512)
  --camera ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg
                       eye, target, up and vertical field of view (default:
                       the --view side that shows the most front-facing
                       surface, front on a tie)
  --view SIDE          front | back | left | right | top | bottom: frame the
                       scene's bounding box from that side, its larger extent
                       filling the view: front from -z looking +z, back from
                       +z, left from +x and right from -x (as they appear in
                       the front view), top from +y, bottom from -y. Without
                       --view or --camera, the side is chosen by rays from
                       each side's eye: the most image showing the front of
                       a polygon, occlusion included. Not with --camera
  --exposure E         linear exposure for image.png (default: automatic)
  --aa on|off          on: each pixel is the exact area-weighted mean of what
                       it sees (a 1-pixel box filter: every piece's coverage
                       of the pixel square, computed analytically); off: the
                       pixel centre only, quads as two Gouraud triangles
                       (the images before --aa existed); default on
  --smooth on|off      on: where polygons with a smoothing group ('s N') or
                       vertex normals ('vn') meet, the image shades across
                       them smoothly, within the crease angle; default on
  --crease DEG         smoothing's crease angle, 0..180: the most two vertex
                       normals, or two faces of one smoothing group, may
                       differ by and be shaded as one surface (default 30)
  --quiet              no progress line on stderr
  --strict             refuse degenerate, non-planar and self-intersecting
                       faces (exit 2, file:line) instead of mending them:
                       by default a non-planar face is triangulated, a
                       repeated or collinear corner removed, and a face with
                       no area or crossing edges dropped, each kind counted
                       in one warning line
  --emit NAME=R,G,B    make material NAME an emitter of exitance Ke =
                       (R, G, B), each >= 0, replacing the MTL's Ke (said
                       in a warning when that was not 0); NAME=ka takes the
                       material's Ka (scenes that give the light's strength
                       there); repeatable; a NAME no MTL defines exits 2
  --two-sided          both sides of every polygon receive, reflect and show
                       (for scenes wound inconsistently): each polygon is
                       meshed twice, the copy reversed; patches double.
                       An emitter's copy reflects but does not emit unless
                       --two-sided-emitters is given too
  --two-sided-emitters emitters emit from both sides, Ke from each: twice
                       the emitted power of the one-sided emitter (their
                       back sides also reflect)
  --reference REF.pfm  measure the image's relative RMSE against REF.pfm
                       (same size) when the solve ends, in convergence.csv
                       and run.json; the time it takes is not solve time
  --error-every K      with --reference: also every K shots during the solve
  --exclude MASK.pgm   with --reference: leave out of the relative RMSE the
                       pixels where MASK.pgm (8-bit PGM, same size) is
                       nonzero, e.g. visible emitters (tools/reference)
  --correct-unshot on|off
                       on: patches.csv's b includes kd * the ambient term
                       (Cohen's estimate of what the still-unshot power will
                       add, which the image always shows); default off
  --stop-error E       also stop when the estimated relative bias of b from
                       the power not yet shot is below E, 0 < E < 1: the
                       share rho*U/(1-rho) of the radiosity power still to
                       come (times 1-rho with --correct-unshot on), which
                       unlike --stop-unshot counts the 1/(1-rho)
                       amplification of stiff scenes (default: off)

local environments and visibility masks:
  --envs NX[xNY[xNZ]]  split the scene's box into a grid of environments
                       (default 1); each owns only its own patches and grid
  --envs auto[:N]      N environments (default: --ranks, or under mpirun the
                       world size), the grid's shape and its split planes
                       chosen from the scene: each axis cut where the
                       patches (estimated from the polygons' areas) divide
                       evenly, so every slab holds about as many; still a
                       grid. The default when --envs is not given and the
                       run has more than one rank
  --mask-method M      none | A | B | C | R (default B): how a shooter's
                       visibility mask is filled. A: from the form-factor rays
                       that hit (cheap, leaks light where no ray hit); B: one
                       ray from the shooter's centre per open pixel (exact at
                       its resolution); C: pixels the rays only hit close,
                       only passed stay open, B's ray for the rest; R: one bit
                       per ray of the shot (--rays or --max-rays bits), every ray absorbed
                       in exactly one environment; none: no mask (light
                       passes occluders)
  --mask-res R         mask resolution: R rows (theta) x 4R columns (phi),
                       1 <= R <= 4096 (default 50; not used by R)
  --round-shots K      at most K shots per environment per round (default
                       with several environments: 64, fewer when 6 packets
                       a shot would fill more than 512 KiB; with one: 1).
                       Given alone (no --round-work), the rounds of before:
                       K shots, no work limit
  --round-work N       a round ends for an environment once its rays (and
                       B's and C's centre rays) have done N steps of grid
                       walking, cells entered plus patches tested: a count
                       that tracks CPU time but never depends on it, so
                       rounds are the same whatever the machine, ranks or
                       transport. Default with several environments: about
                       16 full shots' worth (16 x (--max-rays, or --rays,
                       + 4R^2 for B and C) x the cube root of an
                       environment's grid cells); 0: no limit
  --mask-cache K       KiB per environment for Methods B and C's centre masks
                       of local shooters, kept for their later shots (the
                       mask depends only on the shooter); same output,
                       fewer centre rays; 0: none (default 8192)
  --queue Q            foreign shooters an environment holds at once; a
                       full queue holds back new ones (default: the
                       environments x the round's shots, so that every
                       environment can make a whole round, within 1 MiB of
                       slots an environment, and at least 64)
  --ranks N            run on N processes on this host, connected by POSIX
                       pipes (default 1); environments are dealt to ranks in
                       contiguous blocks; N <= the number of environments
  --transport T        loop | pipe | mpi: loop keeps every environment in
                       one process; pipe is the default for --ranks > 1; mpi
                       is what build/vismask-mpi uses (under mpirun)
  --rank-timeout S     a rank that waits for a peer and hears nothing from
                       it for S seconds ends the run (exit 3, naming the
                       silent rank; a stopped or hung rank). The limit is
                       S or 10 times the longest wait of the run so far,
                       whichever is longer, so S must exceed how much
                       longer one rank's round or init takes than another's
                       and rank 0's output writing (default 60; 0: wait
                       forever)
  --mem-budget BYTES   refuse at init (exit 2, with the numbers) when a rank
                       would reserve more than BYTES (suffix K, M or G for
                       KiB, MiB, GiB); a run that starts never runs out
  --env-order I,J,...  run the environments in this order within each round
                       (a permutation of 0..N-1); a check of determinism:
                       the results must not change

outputs (in --out DIR):
  image.png         tone-mapped sRGB image
  image.pfm         linear float RGB radiance (B/pi, with the ambient term)
  patches.csv       id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b
                    (b = solved radiosity, without the ambient term)
  convergence.csv   shot,seconds,unshot_fraction (one row per round: each
                    environment's shots of that round); with --reference two
                    more columns, relative_rmse,error_seconds (filled on the
                    rows where the error was measured; error_seconds is the
                    total spent measuring so far, not part of seconds)
  run.json          options, counts, energy balance, timings, memory
  FILE.glb          with --export (where it names): the solved mesh, glTF 2.0

view (vismask view OUT_DIR):
  serves, on 127.0.0.1 with python3's http.server, the viewer page and
  OUT_DIR, and prints the URL: the mesh 'render --export OUT_DIR/NAME.glb'
  wrote, shown as image.png shows it (exposure slider, sRGB), to orbit
  (drag) or fly through (F; W A S D), starting from run.json's camera.
  --glb NAME.glb       the mesh in OUT_DIR (default: the one .glb there)
  --port P             the port (default: any free port)
  The page is found beside the binary: PREFIX/share/vismask/viewer when
  installed (make install), viewer/ in the source tree (make viewer).

exit status: 0 success; 1 an output could not be written (view: the viewer
page or python3 is missing); 2 bad input or
options (the message names file:line or the option); 3 a rank was lost
or silent (--rank-timeout); 4 the solve stalled (no environment could shoot
while power was left)
)";
}

namespace {

// The least normal float: options stored as float refuse anything smaller
// rather than silently becoming 0 (--patch-size 0 is "automatic").
constexpr double kFloatMin = 1.17549435e-38;

Status Bad(const std::string& flag, const std::string& value, const std::string& expected) {
  return Status::Error("vismask: " + flag + ": expected " + expected + ", got '" + value + "'");
}

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty() || std::isspace(static_cast<unsigned char>(s[0]))) return false;
  errno = 0;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseU64(const std::string& s, uint64_t* out) {
  if (s.empty() || !std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  errno = 0;
  char* end = nullptr;
  unsigned long long v = std::strtoull(s.c_str(), &end, 10);
  if (end != s.c_str() + s.size() || errno == ERANGE) return false;
  *out = v;
  return true;
}

}  // namespace

namespace {

uint32_t MostRaysAShot(const Options& o) {
  return o.rayAlloc == Options::RayAlloc::kPower ? o.maxRays : o.rays;
}

}  // namespace

void ResolveRounds(int numEnvs, Options* o) {
  o->roundWorkAuto = false;
  const uint64_t packet = PacketBytes(MaskShapeOf(o->maskMethod, o->maskRes, MostRaysAShot(*o)));
  if (o->hasRoundWork || o->hasRoundShots || numEnvs <= 1) {
    if (!o->hasRoundShots) o->roundShots = o->hasRoundWork ? kAutoRoundShots : 1;
    if (!o->hasRoundWork) o->roundWork = 0;
  } else {
    // The outbox holds 6 packets a shot: fewer shots a round with big packets.
    uint64_t shots = kAutoRoundOutboxBytes / (6 * packet);
    o->roundShots =
        static_cast<uint32_t>(std::max<uint64_t>(1, std::min<uint64_t>(kAutoRoundShots, shots)));
    o->roundWorkAuto = true;
  }
  if (!o->hasQueue) o->queue = AutoQueue(numEnvs, o->roundShots, packet);
}

uint32_t AutoQueue(int numEnvs, uint32_t roundShots, uint64_t packetBytes) {
  // Admission shares the free slots among the environments, so a round of
  // `roundShots` local shots in each needs numEnvs x roundShots of them.
  const uint64_t want = uint64_t(std::max(numEnvs, 1)) * roundShots;
  const uint64_t fit = kAutoQueueBytes / std::max<uint64_t>(packetBytes, 1);
  return static_cast<uint32_t>(std::max<uint64_t>(kMinAutoQueue, std::min(want, fit)));
}

bool SetWorldSize(int ranks, Options* o) {
  if (o->hasEnvs || ranks <= 1 || o->envsAuto) return false;
  o->envsAuto = true;
  o->envsAutoCount = std::min(ranks, kMaxAutoEnvs);
  if (!ChooseEnvShape(o->envsAutoCount, glm::vec3(1.0f), o->envs)) return false;
  ResolveRounds(o->envsAutoCount, o);
  return true;
}

uint64_t AutoRoundWork(const Options& o, double patches, int numEnvs, float gridDensity) {
  // B's and C's centre rays (one per mask pixel at most) walk like rays.
  double rays = MostRaysAShot(o);
  if (o.maskMethod == MaskMethod::kB || o.maskMethod == MaskMethod::kC)
    rays += 4.0 * o.maskRes * o.maskRes;
  double cells = gridDensity * patches / std::max(1, numEnvs);
  double steps = std::max(1.0, std::cbrt(std::max(cells, 1.0)));
  return static_cast<uint64_t>(kAutoRoundWorkShots * rays * steps);
}

Status ParseArgs(int argc, const char* const* argv, Options* o) {
  *o = Options();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return Status::Error("vismask: no command (try 'vismask --help')");
  size_t i = 0;
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    o->help = true;
    return Status::Ok();
  }
  if (args[0] == "compare") {
    const bool mask = args.size() == 5 && args[3] == "--exclude" && !args[4].empty();
    if (args.size() != 3 && !mask)
      return Status::Error(
          "vismask: compare: usage: vismask compare A.pfm B.pfm [--exclude MASK.pgm]");
    o->command = "compare";
    o->compareA = args[1];
    o->compareB = args[2];
    if (mask) o->exclude = args[4];
    return Status::Ok();
  }
  if (args[0] == "view") {
    o->command = "view";
    for (i = 1; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a == "--help" || a == "-h") {
        o->help = true;
        return Status::Ok();
      }
      if (a == "--glb" || a == "--port") {
        if (i + 1 >= args.size()) return Status::Error("vismask: view: " + a + ": missing value");
        const std::string& v = args[++i];
        uint64_t u = 0;
        if (a == "--glb") {
          if (v.empty()) return Bad(a, v, "a file name");
          o->viewGlb = v;
        } else {
          if (!ParseU64(v, &u) || u < 1 || u > 65535) return Bad(a, v, "a port in [1, 65535]");
          o->viewPort = static_cast<int>(u);
        }
        continue;
      }
      if (a.rfind("--", 0) == 0)
        return Status::Error("vismask: view: unknown option '" + a +
                             "' (try 'vismask view --help')");
      if (!o->viewDir.empty())
        return Status::Error("vismask: view: unexpected argument '" + a + "' (one OUT_DIR)");
      if (a.empty()) return Status::Error("vismask: view: OUT_DIR is empty");
      o->viewDir = a;
    }
    if (o->viewDir.empty())
      return Status::Error(
          "vismask: view: usage: vismask view OUT_DIR [--glb NAME.glb] [--port P]");
    return Status::Ok();
  }
  if (args[0] != "render" && args[0] != "footprint")
    return Status::Error("vismask: unknown command '" + args[0] + "' (try 'vismask --help')");
  o->command = args[i++];
  for (; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      o->help = true;
      return Status::Ok();
    }
    if (a == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (a == "--strict") {
      o->load.strict = true;
      continue;
    }
    if (a == "--two-sided") {
      o->twoSided = true;
      continue;
    }
    if (a == "--two-sided-emitters") {
      o->twoSidedEmitters = true;
      continue;
    }
    if (a == "--json") {
      if (o->command != "footprint")
        return Status::Error("vismask: --json is an option of 'vismask footprint', not of '" +
                             o->command + "'");
      o->json = true;
      continue;
    }
    if (a.rfind("--", 0) != 0) {
      if (!o->scene.empty())
        return Status::Error("vismask: unexpected argument '" + a + "' (one scene per run)");
      o->scene = a;
      continue;
    }
    if (i + 1 >= args.size()) return Status::Error("vismask: " + a + ": missing value");
    // A value that is itself an option ("--out --quiet") is a missing value,
    // not a directory called --quiet.
    if (args[i + 1].rfind("--", 0) == 0)
      return Status::Error("vismask: " + a + ": missing value (the next argument is the option '" +
                           args[i + 1] + "')");
    const std::string& v = args[++i];
    double d = 0.0;
    uint64_t u = 0;
    if (a == "--out") {
      if (v.empty()) return Bad(a, v, "a directory");
      o->outDir = v;
    } else if (a == "--export") {
      // A file name ending in .glb (any case), not a directory.
      bool glb = v.size() > 4 && v[v.size() - 5] != '/';
      for (size_t k = 0; glb && k < 4; ++k)
        glb = std::tolower(static_cast<unsigned char>(v[v.size() - 4 + k])) == ".glb"[k];
      if (!glb) return Bad(a, v, "a file name ending in .glb (binary glTF)");
      o->exportPath = v;
    } else if (a == "--patch-size") {
      if (!ParseDouble(v, &d) || !(d > 0.0) || d > 3.4e38) return Bad(a, v, "a length > 0");
      if (d < kFloatMin) return Bad(a, v, "a length float can hold (>= 1.2e-38; smaller is 0)");
      o->patchSize = static_cast<float>(d);
    } else if (a == "--rays") {
      if (!ParseU64(v, &u) || u < 1 || u > 100000000) return Bad(a, v, "an integer in [1, 1e8]");
      o->rays = static_cast<uint32_t>(u);
      o->hasRays = true;
    } else if (a == "--ray-alloc") {
      if (v == "power")
        o->rayAlloc = Options::RayAlloc::kPower;
      else if (v == "fixed")
        o->rayAlloc = Options::RayAlloc::kFixed;
      else
        return Bad(a, v, "power or fixed");
      o->hasRayAlloc = true;
    } else if (a == "--emitted-rays") {
      if (!ParseU64(v, &u) || u < 1 || u > 1000000000000ull)
        return Bad(a, v, "an integer in [1, 1e12]");
      o->emittedRays = u;
    } else if (a == "--min-rays" || a == "--max-rays") {
      if (!ParseU64(v, &u) || u < 1 || u > 100000000) return Bad(a, v, "an integer in [1, 1e8]");
      (a == "--min-rays" ? o->minRays : o->maxRays) = static_cast<uint32_t>(u);
    } else if (a == "--sampler") {
      if (v == "sobol")
        o->sobol = true;
      else if (v == "random")
        o->sobol = false;
      else
        return Bad(a, v, "sobol or random");
    } else if (a == "--elements") {
      if (!ParseU64(v, &u) || u > 1024) return Bad(a, v, "an integer in [0, 1024]");
      o->elementsPerPatch = static_cast<uint32_t>(u);
    } else if (a == "--element-depth") {
      if (!ParseU64(v, &u) || u > 16) return Bad(a, v, "an integer in [0, 16]");
      o->elementDepth = static_cast<uint32_t>(u);
    } else if (a == "--element-chi2") {
      if (!ParseDouble(v, &d) || !(d >= 0.0) || d > 1e6) return Bad(a, v, "a number in [0, 1e6]");
      o->elementChi2 = static_cast<float>(d);
    } else if (a == "--element-spread") {
      if (!ParseDouble(v, &d) || !(d >= 0.0) || d > 100.0) return Bad(a, v, "a number in [0, 100]");
      o->elementSpread = static_cast<float>(d);
    } else if (a == "--ray-budget") {
      if (!ParseU64(v, &u) || u < 1) return Bad(a, v, "a positive integer");
      o->rayBudget = u;
    } else if (a == "--seed") {
      if (!ParseU64(v, &u)) return Bad(a, v, "an unsigned 64-bit integer");
      o->seed = u;
    } else if (a == "--stop-unshot") {
      if (!ParseDouble(v, &d) || d < 0.0 || d >= 1.0) return Bad(a, v, "a number in [0, 1)");
      o->stopUnshot = d;
    } else if (a == "--max-shots") {
      if (!ParseU64(v, &u) || u < 1) return Bad(a, v, "a positive integer");
      o->maxShots = u;
    } else if (a == "--max-seconds") {
      if (!ParseDouble(v, &d) || !(d > 0.0)) return Bad(a, v, "a number of seconds > 0");
      o->maxSeconds = d;
    } else if (a == "--width" || a == "--height") {
      if (!ParseU64(v, &u) || u < 1 || u > 16384) return Bad(a, v, "an integer in [1, 16384]");
      (a == "--width" ? o->width : o->height) = static_cast<int>(u);
    } else if (a == "--exposure") {
      if (!ParseDouble(v, &d) || !(d > 0.0) || d > 3.4e38) return Bad(a, v, "a number > 0");
      if (d < kFloatMin) return Bad(a, v, "a number float can hold (>= 1.2e-38; smaller is 0)");
      o->hasExposure = true;
      o->exposure = static_cast<float>(d);
    } else if (a == "--camera") {
      std::vector<std::string> parts(1);
      for (char ch : v) {
        if (ch == ',')
          parts.emplace_back();
        else
          parts.back() += ch;
      }
      double c[10];
      bool good = parts.size() == 10;
      for (size_t k = 0; good && k < 10; ++k) good = ParseDouble(parts[k], &c[k]);
      if (!good) return Bad(a, v, "ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg (10 numbers)");
      o->hasCamera = true;
      o->camera.eye = glm::vec3(c[0], c[1], c[2]);
      o->camera.target = glm::vec3(c[3], c[4], c[5]);
      o->camera.up = glm::vec3(c[6], c[7], c[8]);
      o->camera.fovyDeg = static_cast<float>(c[9]);
      View view;
      if (!MakeView(o->camera, 1, 1, &view))
        return Bad(a, v, "eye != target, up not parallel to the view direction, 0 < fovy < 180");
    } else if (a == "--view") {
      if (!ParseViewSide(v.c_str(), &o->view))
        return Bad(a, v, "front, back, left, right, top or bottom");
      o->hasView = true;
    } else if (a == "--envs") {
      o->hasEnvs = true;
      o->envsAuto = false;
      if (v == "auto" || v.rfind("auto:", 0) == 0) {
        o->envsAuto = true;
        o->envsAutoCount = 0;  // --ranks, once all options are read
        if (v.size() > 4 && (!ParseU64(v.substr(5), &u) || u < 1 || u > kMaxAutoEnvs))
          return Bad(a, v,
                     "NX[xNY[xNZ]] (each 1..64), auto or auto:N (N in 1.." +
                         std::to_string(kMaxAutoEnvs) + ")");
        if (v.size() > 4) o->envsAutoCount = static_cast<int>(u);
      } else if (!ParseEnvGrid(v.c_str(), o->envs)) {
        return Bad(a, v, "NX[xNY[xNZ]] (each 1..64), auto or auto:N");
      }
    } else if (a == "--mask-method") {
      if (v == "none")
        o->maskMethod = MaskMethod::kNone;
      else if (v == "A")
        o->maskMethod = MaskMethod::kA;
      else if (v == "B")
        o->maskMethod = MaskMethod::kB;
      else if (v == "C")
        o->maskMethod = MaskMethod::kC;
      else if (v == "R")
        o->maskMethod = MaskMethod::kR;
      else
        return Bad(a, v, "none, A, B, C or R");
    } else if (a == "--mask-res") {
      if (!ParseU64(v, &u) || u < 1 || u > 4096) return Bad(a, v, "an integer in [1, 4096]");
      o->maskRes = static_cast<uint32_t>(u);
    } else if (a == "--round-shots") {
      if (!ParseU64(v, &u) || u < 1 || u > 1000000) return Bad(a, v, "an integer in [1, 1e6]");
      o->roundShots = static_cast<uint32_t>(u);
      o->hasRoundShots = true;
    } else if (a == "--round-work") {
      if (!ParseU64(v, &u) || u > 1000000000000000ull)
        return Bad(a, v, "an integer in [0, 1e15] (0: no limit)");
      o->roundWork = u;
      o->hasRoundWork = true;
    } else if (a == "--env-order") {
      o->envOrder.clear();
      std::string part;
      for (size_t k = 0; k <= v.size(); ++k) {
        if (k < v.size() && v[k] != ',') {
          part += v[k];
          continue;
        }
        if (!ParseU64(part, &u) || u > 1000000) return Bad(a, v, "a comma-separated permutation");
        o->envOrder.push_back(static_cast<uint32_t>(u));
        part.clear();
      }
    } else if (a == "--ranks") {
      if (!ParseU64(v, &u) || u < 1 || u > 256) return Bad(a, v, "an integer in [1, 256]");
      o->ranks = static_cast<int>(u);
    } else if (a == "--rank-timeout") {
      if (!ParseDouble(v, &d) || d < 0.0 || d > 1e9)
        return Bad(a, v, "seconds in [0, 1e9] (0: none)");
      o->rankTimeout = d;
    } else if (a == "--transport") {
      if (v != "loop" && v != "pipe" && v != "mpi") return Bad(a, v, "loop, pipe or mpi");
      o->transport = v;
    } else if (a == "--mem-budget") {
      std::string digits = v;
      uint64_t scale = 1;
      if (!digits.empty() &&
          (digits.back() == 'K' || digits.back() == 'M' || digits.back() == 'G')) {
        scale = digits.back() == 'K'   ? 1024ull
                : digits.back() == 'M' ? 1024ull * 1024
                                       : 1024ull * 1024 * 1024;
        digits.pop_back();
      }
      if (!ParseU64(digits, &u) || u < 1 || u > ~0ull / scale)
        return Bad(a, v, "a number of bytes >= 1 (suffix K, M or G allowed)");
      o->memBudget = u * scale;
    } else if (a == "--reference") {
      if (v.empty()) return Bad(a, v, "a PFM file");
      o->reference = v;
    } else if (a == "--exclude") {
      if (v.empty()) return Bad(a, v, "a PGM file");
      o->exclude = v;
    } else if (a == "--error-every") {
      if (!ParseU64(v, &u) || u < 1) return Bad(a, v, "a positive number of shots");
      o->errorEvery = u;
    } else if (a == "--stop-error") {
      if (!ParseDouble(v, &d) || !(d > 0.0) || d >= 1.0) return Bad(a, v, "a number in (0, 1)");
      o->stopError = d;
    } else if (a == "--aa") {
      if (v != "on" && v != "off") return Bad(a, v, "on or off");
      o->aa = v == "on";
    } else if (a == "--smooth") {
      if (v != "on" && v != "off") return Bad(a, v, "on or off");
      o->smooth = v == "on";
    } else if (a == "--crease") {
      if (!ParseDouble(v, &d) || !(d >= 0.0) || d > 180.0)
        return Bad(a, v, "an angle in [0, 180] degrees");
      o->creaseDeg = static_cast<float>(d);
    } else if (a == "--correct-unshot") {
      if (v != "on" && v != "off") return Bad(a, v, "on or off");
      o->correctUnshot = v == "on";
    } else if (a == "--emit") {
      const char* expected = "NAME=R,G,B (each a number >= 0) or NAME=ka";
      size_t eq = v.rfind('=');
      if (eq == std::string::npos || eq == 0) return Bad(a, v, expected);
      EmitOverride e;
      e.material = v.substr(0, eq);
      std::string value = v.substr(eq + 1);
      if (value == "ka" || value == "Ka") {
        e.fromKa = true;
      } else {
        std::vector<std::string> parts(1);
        for (char ch : value) {
          if (ch == ',')
            parts.emplace_back();
          else
            parts.back() += ch;
        }
        double c[3];
        bool good = parts.size() == 3;
        for (size_t k = 0; good && k < 3; ++k)
          good = ParseDouble(parts[k], &c[k]) && c[k] >= 0.0 && c[k] <= 3.4e38;
        if (!good) return Bad(a, v, expected);
        e.ke = glm::vec3(c[0], c[1], c[2]);
      }
      o->load.emit.push_back(e);
    } else if (a == "--mask-cache") {
      if (!ParseU64(v, &u) || u > (uint64_t{1} << 26))
        return Bad(a, v, "an integer in [0, 2^26] (KiB)");
      o->maskCacheKiB = static_cast<uint32_t>(u);
    } else if (a == "--queue") {
      if (!ParseU64(v, &u) || u < 1 || u > 1000000) return Bad(a, v, "an integer in [1, 1e6]");
      o->queue = static_cast<uint32_t>(u);
      o->hasQueue = true;
    } else {
      return Status::Error("vismask: unknown option '" + a + "' (try 'vismask --help')");
    }
  }
  if (o->scene.empty())
    return Status::Error("vismask: " + o->command + ": no scene given (vismask " + o->command +
                         " SCENE.obj)");
  if (o->hasView && o->hasCamera)
    return Status::Error(
        "vismask: --view and --camera: give one or the other (--view frames the "
        "bounding box from a side, --camera places the camera itself)");
  if (o->errorEvery > 0 && o->reference.empty())
    return Status::Error("vismask: --error-every: needs --reference REF.pfm to measure against");
  // --rays N alone keeps its meaning: N rays every shot.
  if (!o->hasRayAlloc && o->hasRays) o->rayAlloc = Options::RayAlloc::kFixed;
  if (o->rayAlloc == Options::RayAlloc::kPower && o->hasRays)
    return Status::Error(
        "vismask: --rays: sets every shot's rays under --ray-alloc fixed; with "
        "--ray-alloc power use --emitted-rays, --min-rays and --max-rays");
  if (o->minRays > o->maxRays)
    return Status::Error("vismask: --min-rays " + std::to_string(o->minRays) +
                         " is above --max-rays " + std::to_string(o->maxRays));
  if (!o->exclude.empty() && o->reference.empty())
    return Status::Error(
        "vismask: --exclude: needs --reference REF.pfm (the mask applies to its error)");
  // --ranks N > 1 without --envs: --envs auto, one balanced environment a
  // rank (under mpirun, SetWorldSize does the same with the world's size).
  if (!o->hasEnvs && o->ranks > 1) o->envsAuto = true;
  if (o->envsAuto) {
    // auto: as many environments as ranks (pipe; under mpirun, the world).
    if (o->envsAutoCount == 0) o->envsAutoCount = std::max(o->ranks, 1);
    // A placeholder shape of the right count; init picks it from the scene.
    if (!ChooseEnvShape(o->envsAutoCount, glm::vec3(1.0f), o->envs))
      return Status::Error("vismask: --envs: auto:" + std::to_string(o->envsAutoCount) +
                           ": no grid of that many environments with at most 64 a side");
  }
  int numEnvs = o->envs[0] * o->envs[1] * o->envs[2];
  ResolveRounds(numEnvs, o);
  if (o->ranks > numEnvs)
    return Status::Error("vismask: --ranks: " + std::to_string(o->ranks) + " ranks for " +
                         std::to_string(numEnvs) +
                         " environments (each rank needs one; see --envs)");
  if (o->transport == "loop" && o->ranks > 1)
    return Status::Error(
        "vismask: --transport loop runs one process; use --transport pipe with --ranks");
  if (!o->envOrder.empty()) {
    size_t n = size_t(o->envs[0]) * o->envs[1] * o->envs[2];
    std::vector<bool> seen(n, false);
    bool ok = o->envOrder.size() == n;
    for (uint32_t e : o->envOrder) {
      if (e >= n || seen[e])
        ok = false;
      else
        seen[e] = true;
    }
    if (!ok)
      return Status::Error("vismask: --env-order: expected a permutation of 0.." +
                           std::to_string(n - 1));
  }
  return Status::Ok();
}

}  // namespace vismask
