// The option table (options_table.h): one row per option, and the parsers
// of the options whose syntax is their own (a list, a camera, a grid).
#include "vismask/app/options_table.h"

#include <cctype>
#include <cstring>
#include <type_traits>

#include "options_read.h"
#include "vismask/solve/partition.h"

namespace vismask {

namespace {

// The least normal float: options stored as float refuse anything smaller
// rather than silently becoming 0 (--patch-size 0 is "automatic").
constexpr double kFloatMin = 1.17549435e-38;

// A row under construction: the kind's constructor, then what applies.
struct Row {
  OptionSpec s;
  Row& Given(bool Options::*g) { return s.given = g, *this; }
  Row& Open(bool lo, bool hi) { return s.loOpen = lo, s.hiOpen = hi, *this; }
  Row& Tiny(const char* words) { return s.tiny = words, *this; }
  Row& Help(const char* arg, const char* help) { return s.arg = arg, s.help = help, *this; }
  Row& More(const char* label, const char* help) {
    return s.moreLabel = label, s.moreHelp = help, *this;
  }
  Row& Usage() { return s.usage = true, *this; }
  Row& Envs() { return s.section = HelpSection::kEnvironments, *this; }
  Row& Resume(ResumeRule rule) { return s.resume = rule, *this; }
  Row& MayDiffer() { return Resume(ResumeRule::kMayDiffer); }
  Row& Json(const char* key) { return s.json = key, *this; }
};

Row Make(const char* name, OptionKind kind, OptionField field) {
  Row r;
  r.s.name = name;
  r.s.kind = kind;
  r.s.field = field;
  return r;
}
Row Flag(const char* name, OptionField field) {
  return Make(name, OptionKind::kFlag, field);
}
Row Count(const char* name, OptionField field, double lo, double hi, const char* expected) {
  Row r = Make(name, OptionKind::kCount, field);
  r.s.lo = lo, r.s.hi = hi, r.s.expected = expected;
  return r;
}
Row Number(const char* name, OptionField field, double lo, double hi, const char* expected) {
  Row r = Count(name, field, lo, hi, expected);
  r.s.kind = OptionKind::kNumber;
  return r;
}
Row Choice(const char* name, OptionField field, const char* choices) {
  Row r = Make(name, OptionKind::kChoice, field);
  r.s.choices = choices;
  return r;
}
Row Text(const char* name, OptionField field, const char* expected) {
  Row r = Make(name, OptionKind::kText, field);
  r.s.expected = expected;
  return r;
}
Row Custom(const char* name, decltype(OptionSpec::parse) parse) {
  Row r = Make(name, OptionKind::kCustom, std::monostate());
  r.s.parse = parse;
  return r;
}
Row Flag(const char* name, decltype(OptionSpec::parse) parse) {
  Row r = Custom(name, parse);
  r.s.kind = OptionKind::kFlag;
  return r;
}

// --export: a file name ending in .glb (any case), not a directory.
Status ParseExport(const std::string& a, const std::string& v, Options* o) {
  bool glb = v.size() > 4 && v[v.size() - 5] != '/';
  for (size_t k = 0; glb && k < 4; ++k)
    glb = std::tolower(static_cast<unsigned char>(v[v.size() - 4 + k])) == ".glb"[k];
  if (!glb) return BadValue(a, v, "a file name ending in .glb (binary glTF)");
  o->exportPath = v;
  return Status::Ok();
}

Status ParseCamera(const std::string& a, const std::string& v, Options* o) {
  std::vector<std::string> parts = SplitCommas(v);
  double c[10];
  bool good = parts.size() == 10;
  for (size_t k = 0; good && k < 10; ++k) good = ParseNumber(parts[k], &c[k]);
  if (!good) return BadValue(a, v, "ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg (10 numbers)");
  o->camera.eye = glm::vec3(c[0], c[1], c[2]);
  o->camera.target = glm::vec3(c[3], c[4], c[5]);
  o->camera.up = glm::vec3(c[6], c[7], c[8]);
  o->camera.fovyDeg = static_cast<float>(c[9]);
  View view;
  if (!MakeView(o->camera, 1, 1, &view))
    return BadValue(a, v, "eye != target, up not parallel to the view direction, 0 < fovy < 180");
  return Status::Ok();
}

// --envs NX[xNY[xNZ]], auto or auto:N (N: --ranks when not given, once
// every option is read).
Status ParseEnvs(const std::string& a, const std::string& v, Options* o) {
  o->envsAuto = false;
  if (v != "auto" && v.rfind("auto:", 0) != 0) {
    if (!ParseEnvGrid(v.c_str(), o->envs))
      return BadValue(a, v, "NX[xNY[xNZ]] (each 1..64), auto or auto:N");
    return Status::Ok();
  }
  o->envsAuto = true;
  o->envsAutoCount = 0;
  if (v.size() == 4) return Status::Ok();
  uint64_t u = 0;
  if (!ParseCount(v.substr(5), &u) || u < 1 || u > kMaxAutoEnvs)
    return BadValue(
        a, v,
        "NX[xNY[xNZ]] (each 1..64), auto or auto:N (N in 1.." + std::to_string(kMaxAutoEnvs) + ")");
  o->envsAutoCount = static_cast<int>(u);
  return Status::Ok();
}

// --env-order I,J,...: checked to be a permutation once --envs is known.
Status ParseEnvOrder(const std::string& a, const std::string& v, Options* o) {
  o->envOrder.clear();
  for (const std::string& part : SplitCommas(v)) {
    uint64_t u = 0;
    if (!ParseCount(part, &u) || u > 1000000)
      return BadValue(a, v, "a comma-separated permutation");
    o->envOrder.push_back(static_cast<uint32_t>(u));
  }
  return Status::Ok();
}

// --mem-budget BYTES, with an optional K, M or G (binary) suffix.
Status ParseMemBudget(const std::string& a, const std::string& v, Options* o) {
  std::string digits = v;
  uint64_t scale = 1;
  const char suffix = digits.empty() ? '\0' : digits.back();
  if (suffix == 'K' || suffix == 'M' || suffix == 'G') {
    scale = suffix == 'K' ? 1024ull : suffix == 'M' ? 1024ull * 1024 : 1024ull * 1024 * 1024;
    digits.pop_back();
  }
  uint64_t u = 0;
  if (!ParseCount(digits, &u) || u < 1 || u > ~0ull / scale)
    return BadValue(a, v, "a number of bytes >= 1 (suffix K, M or G allowed)");
  o->memBudget = u * scale;
  return Status::Ok();
}

// --sky: a radiance (ParseSky, outside.h), the one place its syntax is read.
Status ParseSkyOption(const std::string& a, const std::string& v, Options* o) {
  if (!ParseSky(v, &o->outside)) return BadValue(a, v, "R,G,B: the sky's radiance, each >= 0");
  o->load.outsideLight = o->outside.Any();
  return Status::Ok();
}

Status ParseSunOption(const std::string& a, const std::string& v, Options* o) {
  if (!ParseSun(v, &o->outside))
    return BadValue(a, v,
                    "X,Y,Z,R,G,B[,DEG]: the direction towards the sun (not 0), its irradiance "
                    "(each >= 0) and angular diameter in degrees (0 to 90, default 0.53)");
  o->load.outsideLight = o->outside.Any();
  return Status::Ok();
}

// --emit NAME=R,G,B or NAME=ka (repeatable).
Status ParseEmit(const std::string& a, const std::string& v, Options* o) {
  const char* expected = "NAME=R,G,B (each a number >= 0) or NAME=ka";
  const size_t eq = v.rfind('=');
  if (eq == std::string::npos || eq == 0) return BadValue(a, v, expected);
  EmitOverride e;
  e.material = v.substr(0, eq);
  const std::string value = v.substr(eq + 1);
  if (value == "ka" || value == "Ka") {
    e.fromKa = true;
  } else {
    std::vector<std::string> parts = SplitCommas(value);
    double c[3];
    bool good = parts.size() == 3;
    for (size_t k = 0; good && k < 3; ++k)
      good = ParseNumber(parts[k], &c[k]) && c[k] >= 0.0 && c[k] <= 3.4e38;
    if (!good) return BadValue(a, v, expected);
    e.ke = glm::vec3(c[0], c[1], c[2]);
  }
  o->load.emit.push_back(e);
  return Status::Ok();
}

Status ParseStrict(const std::string&, const std::string&, Options* o) {
  o->load.strict = true;
  return Status::Ok();
}

Status ParseJson(const std::string&, const std::string&, Options* o) {
  if (o->command != "footprint")
    return Status::Error("vismask: --json is an option of 'vismask footprint', not of '" +
                         o->command + "'");
  o->json = true;
  return Status::Ok();
}

}  // namespace

namespace {

using O = Options;

// Where the run writes, how big a solve is and when it stops.
void AddSolveRows(std::vector<Row>* t) {
  t->insert(t->end(),
            {
                Text("--out", &O::outDir, "a directory")
                    .Help("DIR", "output directory (default out/); created if missing")
                    .Usage()
                    .MayDiffer(),
                Custom("--export", ParseExport)
                    .Help("FILE.glb",
                          "also write the solved mesh as binary glTF 2.0 to\n"
                          "FILE.glb (a path from the current directory, not\n"
                          "under --out; its directory must exist): every\n"
                          "patch's lattice vertices and triangles, COLOR_0 the\n"
                          "linear display radiance image.pfm shows there\n"
                          "(emission included, unclamped), an unlit material;\n"
                          "scene units and the OBJ's axes")
                    .Usage()
                    .MayDiffer()
                    .Json("export"),
                Number("--patch-size", &O::patchSize, 0.0, 3.4e38, "a length > 0")
                    .Open(true, false)
                    .Tiny("a length float can hold (>= 1.2e-38; smaller is 0)")
                    .Help("L",
                          "longest patch edge, scene units (default: largest\n"
                          "scene extent / 28)")
                    .Usage()
                    .Json("patch_size"),
                Choice("--ray-alloc", &O::rayAlloc, "power|fixed")
                    .Given(&O::hasRayAlloc)
                    .Help("power|fixed",
                          "how many Monte Carlo rays a shot traces. power (the\n"
                          "default): in proportion to the shot's unshot power,\n"
                          "--emitted-rays for the whole emitted power, at least\n"
                          "--min-rays; a shot worth more than --max-rays shoots\n"
                          "that share of its power and keeps the rest for later\n"
                          "shots. fixed: --rays every shot (the old default)")
                    .Json("ray_alloc"),
                Count("--rays", &O::rays, 1, 1e8, "an integer in [1, 1e8]")
                    .Given(&O::hasRays)
                    .Help("N",
                          "fixed: Monte Carlo rays per shot (4096); given alone it\n"
                          "selects --ray-alloc fixed")
                    .Json("rays"),
                Count("--emitted-rays", &O::emittedRays, 1, 1e12, "an integer in [1, 1e12]")
                    .Given(&O::hasEmittedRays)
                    .Help("M",
                          "power: the rays the emitted power is worth (4000000);\n"
                          "a shot of power P traces M * P / emitted power rays,\n"
                          "rounded up or down at random from the shot's stream")
                    .Json("emitted_rays"),
                Count("--min-rays", &O::minRays, 1, 1e8, "an integer in [1, 1e8]")
                    .Help("F", "power: the fewest rays a shot traces (default 16)")
                    .Json("min_rays"),
                Count("--max-rays", &O::maxRays, 1, 1e8, "an integer in [1, 1e8]")
                    .Help("C",
                          "power: the most rays a shot traces (default 8192);\n"
                          "also Method R's packet bits")
                    .Json("max_rays"),
                Choice("--sampler", &O::sobol, "sobol|random")
                    .Help("S",
                          "sobol (default): scrambled Sobol' points over a\n"
                          "shot's origin x direction; random: independent draws")
                    .Json("sampler"),
                Count("--ray-budget", &O::rayBudget, 1, kNoLimit, "a positive integer")
                    .Help("N", "stop once N form-factor rays have been traced")
                    .Json("ray_budget"),
                Count("--elements", &O::elementsPerPatch, 0, 1024, "an integer in [0, 1024]")
                    .Help("K",
                          "receivers finer than shooters: each patch is a\n"
                          "quadtree of elements that split where the radiosity\n"
                          "received changes fast (shadow edges, contact shadows,\n"
                          "corners); the pool holds K elements per patch beyond\n"
                          "the patches themselves (default 8; 0: no refinement).\n"
                          "When it is used up refinement stops (run.json says so)"),
                Count("--element-depth", &O::elementDepth, 0, 16, "an integer in [0, 16]")
                    .Help("D",
                          "the deepest an element splits, 0-16 (default 4: 1/16\n"
                          "of the patch's edge)"),
                Number("--element-spread", &O::elementSpread, 0.0, 100.0, "a number in [0, 100]")
                    .Help("S",
                          "an element splits only where its quarters' radiosity\n"
                          "differs by more than S (relative RMS, default 0.1) and\n"
                          "more than its Monte Carlo noise explains"),
                Number("--element-chi2", &O::elementChi2, 0.0, 1e6, "a number in [0, 1e6]")
                    .Help("X",
                          "... explains: chi-square (3 dof) of its quarters\n"
                          "against an even spread above X (default 20)"),
                Count("--seed", &O::seed, 0, kNoLimit, "an unsigned 64-bit integer")
                    .Help("S", "random seed, unsigned 64-bit (default 1)")
                    .Json("seed"),
                Number("--stop-unshot", &O::stopUnshot, 0.0, 1.0, "a number in [0, 1)")
                    .Open(false, true)
                    .Help("F",
                          "stop when unshot power < F * emitted power, 0 <= F < 1\n"
                          "(default 1e-3); 0 needs another stop as well")
                    .Json("stop_unshot"),
                Count("--max-shots", &O::maxShots, 1, kNoLimit, "a positive integer")
                    .Help("N", "stop after N shots (default: no limit)")
                    .Json("max_shots"),
                Number("--max-seconds", &O::maxSeconds, 0.0, kNoLimit, "a number of seconds > 0")
                    .Open(true, false)
                    .Help("T",
                          "stop after T seconds of solving (default: no limit;\n"
                          "a time limit makes the result depend on speed).\n"
                          "Without --emitted-rays (one rank, power allocation)\n"
                          "it plans them: the rays a solve that ends within\n"
                          "about T can afford, from the rays per second timed\n"
                          "through the scene's grid at init (run.json:\n"
                          "emitted_rays, emitted_rays_planned)")
                    .Usage()
                    .Json("max_seconds"),
            });
}

// The image: its size, camera, exposure and filtering.
void AddImageRows(std::vector<Row>* t) {
  t->insert(t->end(),
            {
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
                    .Help("ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg",
                          "eye, target, up and vertical field of view (default:\n"
                          "the --view side that shows the most front-facing\n"
                          "surface, front on a tie)")
                    .Usage()
                    .Json("camera"),
                Choice("--view", &O::view, "front|back|left|right|top|bottom")
                    .Given(&O::hasView)
                    .Help("SIDE",
                          "front | back | left | right | top | bottom: frame the\n"
                          "scene's bounding box from that side, its larger extent\n"
                          "filling the view: front from -z looking +z, back from\n"
                          "+z, left from +x and right from -x (as they appear in\n"
                          "the front view), top from +y, bottom from -y. Without\n"
                          "--view or --camera, the side is chosen by rays from\n"
                          "each side's eye: the most image showing the front of\n"
                          "a polygon, occlusion included. Not with --camera")
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
                    .Help("on|off",
                          "on: each pixel is the exact area-weighted mean of what\n"
                          "it sees (a 1-pixel box filter: every piece's coverage\n"
                          "of the pixel square, computed analytically); off: the\n"
                          "pixel centre only, quads as two Gouraud triangles\n"
                          "(the images before --aa existed); default on")
                    .Json("aa"),
                Count("--direct-samples", &O::directSamples, 0, 1024, "an integer in [0, 1024]")
                    .Help("N",
                          "direct light gathered per pixel, 0..1024: the image's\n"
                          "direct part is the exact unoccluded irradiance of the\n"
                          "emitters times the share of N shadow rays that reach\n"
                          "them (rays to the emitters' corners and 4 first; all\n"
                          "N only where those disagree); the solve supplies the\n"
                          "rest; 0: the solved radiosity alone (the images\n"
                          "before it). Default 32 with one environment, 0 with\n"
                          "several (where it is refused)")
                    .Json("direct_samples"),
                Choice("--smooth", &O::smooth, "on|off")
                    .Help("on|off",
                          "on: where polygons with a smoothing group ('s N') or\n"
                          "vertex normals ('vn') meet, the image shades across\n"
                          "them smoothly, within the crease angle; default on")
                    .Json("smooth"),
                Number("--crease", &O::creaseDeg, 0.0, 180.0, "an angle in [0, 180] degrees")
                    .Help("DEG",
                          "smoothing's crease angle, 0..180: the most two vertex\n"
                          "normals, or two faces of one smoothing group, may\n"
                          "differ by and be shaded as one surface (default 30)")
                    .Json("crease"),
                Flag("--quiet", &O::quiet)
                    .Help(nullptr, "no progress line on stderr")
                    .Usage()
                    .MayDiffer(),
            });
}

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

}  // namespace

const std::vector<OptionSpec>& OptionTable() {
  static const std::vector<OptionSpec> table = [] {
    std::vector<Row> rows;
    AddSolveRows(&rows);
    AddImageRows(&rows);
    AddSceneRows(&rows);
    AddEnvironmentRows(&rows);
    AddRunRows(&rows);
    std::vector<OptionSpec> specs;
    for (const Row& r : rows) specs.push_back(r.s);
    return specs;
  }();
  return table;
}

const OptionSpec* FindOption(const std::string& name) {
  for (const OptionSpec& s : OptionTable())
    if (name == s.name) return &s;
  return nullptr;
}

std::vector<std::string> ChoiceWords(const OptionSpec& spec) {
  std::vector<std::string> words(1);
  for (const char* c = spec.choices ? spec.choices : ""; *c; ++c) {
    if (*c == '|')
      words.emplace_back();
    else
      words.back() += *c;
  }
  return words;
}

bool ChoiceWordAt(const OptionSpec& spec, int index, const char** word, size_t* length) {
  const char* at = spec.choices;
  for (int k = 0; at && k < index; ++k) {
    at = std::strchr(at, '|');
    if (at) ++at;
  }
  if (!at || index < 0) return false;
  const char* end = std::strchr(at, '|');
  *word = at;
  *length = end ? static_cast<size_t>(end - at) : std::strlen(at);
  return true;
}

int ChosenIndex(const OptionSpec& spec, const Options& o) {
  return std::visit(
      [&](auto field) -> int {
        if constexpr (std::is_same_v<decltype(field), std::monostate>) {
          return -1;
        } else {
          const auto& v = o.*field;
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<V, bool>) {
            return v ? 0 : 1;
          } else if constexpr (std::is_enum_v<V>) {
            return static_cast<int>(v);
          } else if constexpr (std::is_same_v<V, std::string>) {
            const char* word = nullptr;
            size_t length = 0;
            for (int k = 0; ChoiceWordAt(spec, k, &word, &length); ++k)
              if (v.size() == length && v.compare(0, length, word, length) == 0) return k;
            return -1;
          } else {
            return -1;
          }
        }
      },
      spec.field);
}

}  // namespace vismask
