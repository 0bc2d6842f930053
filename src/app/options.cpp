#include "vismask/app/options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vismask/solve/packet.h"
#include "vismask/solve/partition.h"

namespace vismask {

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

// A count: decimal digits, or a number in scientific notation whose value
// is exactly an integer (1e6, 2.5e3, 10e-1; not 1.5 or 1e-1), read exactly
// in decimal (no rounding through double), at most 2^64 - 1.
bool ParseU64(const std::string& s, uint64_t* out) {
  if (s.empty() || !std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  auto digit = [&](size_t i) {
    return i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]));
  };
  std::string digits;  // the mantissa's digits, the point removed
  long shift = 0;      // value = digits * 10^shift
  size_t i = 0;
  while (digit(i)) digits += s[i++];
  if (i < s.size() && s[i] == '.') {
    ++i;
    if (!digit(i)) return false;
    while (digit(i)) {
      digits += s[i++];
      --shift;
    }
  }
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    const bool negative = i < s.size() && s[i] == '-';
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (!digit(i)) return false;
    long e = 0;
    while (digit(i)) {
      e = std::min(e * 10 + (s[i++] - '0'), 100000L);  // beyond any count: capped
    }
    shift += negative ? -e : e;
  }
  if (i != s.size()) return false;
  // A negative shift drops digits that must be zeros (10e-1, 2.50e1).
  for (; shift < 0; ++shift) {
    if (digits.empty()) break;
    if (digits.back() != '0') return false;
    digits.pop_back();
  }
  digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size()));
  if (digits.empty()) {
    *out = 0;
    return true;
  }
  if (shift > 20) return false;  // a nonzero value beyond 10^20
  digits.append(static_cast<size_t>(shift), '0');
  uint64_t v = 0;
  for (char c : digits) {
    const uint64_t d = static_cast<uint64_t>(c - '0');
    if (v > (~uint64_t{0} - d) / 10) return false;
    v = v * 10 + d;
  }
  *out = v;
  return true;
}

}  // namespace

Status ParseArgs(int argc, const char* const* argv, Options* o) {
  *o = Options();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return Status::Error("vismask: no command (try 'vismask --help')");
  size_t i = 0;
  // --help [all]: the short usage, or every option (what follows is
  // ignored, as it always was after --help).
  auto help = [&](size_t at) {
    o->help = true;
    o->helpAll = at + 1 < args.size() && args[at + 1] == "all";
    return Status::Ok();
  };
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") return help(0);
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
  if (args[0] == "verify") {
    if (args.size() != 2 || args[1].empty() || args[1].rfind("--", 0) == 0)
      return Status::Error("vismask: verify: usage: vismask verify OUT_DIR");
    o->command = "verify";
    o->verifyDir = args[1];
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
    if (a == "--help" || a == "-h") return help(i);
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
      o->hasEmittedRays = true;
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
      o->hasMaskMethod = true;
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
      o->hasMaskRes = true;
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
    } else if (a == "--checkpoint" || a == "--resume") {
      if (v.empty()) return Bad(a, v, "a directory");
      (a == "--checkpoint" ? o->checkpointDir : o->resumeDir) = v;
    } else if (a == "--checkpoint-every") {
      if (!ParseDouble(v, &d) || d < 0.0 || d > 1e9)
        return Bad(a, v, "seconds in [0, 1e9] (0: every round)");
      o->checkpointEvery = d;
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
    } else if (a == "--direct-samples") {
      if (!ParseU64(v, &u) || u > 1024) return Bad(a, v, "an integer in [0, 1024]");
      o->directSamples = static_cast<int>(u);
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
    } else if (a == "--sky") {
      if (!ParseSky(v, &o->outside))
        return Bad(a, v, "R,G,B (the sky's radiance, each >= 0) or FILE.hdr");
      o->load.outsideLight = o->outside.Any();
    } else if (a == "--sun") {
      if (!ParseSun(v, &o->outside))
        return Bad(a, v,
                   "X,Y,Z,R,G,B[,DEG]: the direction towards the sun (not 0), its irradiance "
                   "(each >= 0) and angular diameter in degrees (0 to 90, default 0.53)");
      o->load.outsideLight = o->outside.Any();
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
    } else if (a == "--centre-rays") {
      if (v == "all")
        o->centreRays = CentreChoice::kAll;
      else if (v == "read")
        o->centreRays = CentreChoice::kRead;
      else if (v == "auto")
        o->centreRays = CentreChoice::kAuto;
      else
        return Bad(a, v, "all, read or auto");
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
  if (o->command != "render" && (!o->checkpointDir.empty() || !o->resumeDir.empty()))
    return Status::Error("vismask: --checkpoint and --resume are options of 'vismask render'");
  if (o->checkpointDir.empty()) o->checkpointDir = o->resumeDir;
  // What a checkpoint must agree with: the arguments as given, less the
  // scene (compared by its bytes), --envs (by its meaning) and the options
  // that leave the result as it is.
  o->resultArgs.clear();
  for (size_t k = 1; k < args.size(); ++k) {
    const std::string& a = args[k];
    const bool flag = a.rfind("--", 0) == 0;
    const bool noValue = a == "--quiet" || a == "--strict" || a == "--two-sided" ||
                         a == "--two-sided-emitters" || a == "--json";
    if (!flag) continue;  // the scene (values are taken with their flag)
    bool neutral = a == "--envs";
    for (const char* n : kResultNeutral) neutral = neutral || a == n;
    if (!neutral) {
      o->resultArgs.push_back(a);
      if (!noValue && k + 1 < args.size()) o->resultArgs.push_back(args[k + 1]);
    }
    if (!noValue) ++k;
  }
  if (o->hasView && o->hasCamera)
    return Status::Error(
        "vismask: --view and --camera: give one or the other (--view frames the "
        "bounding box from a side, --camera places the camera itself)");
  if (o->hasCamera) {
    // Each pixel must span an angle float rays can tell apart: below 2^-20
    // radians (8 float steps of a unit direction) neighbouring pixels see
    // the same thing, and the projection overflows to a black image.
    const double pixel = o->camera.fovyDeg * 3.14159265358979 / 180.0 / o->height;
    if (pixel < std::ldexp(1.0, -20)) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "vismask: --camera: a field of view of %g degrees over %d pixels gives each "
                    "pixel %.3g radians, below the %.3g (2^-20) that float rays can tell apart; "
                    "widen the field of view",
                    static_cast<double>(o->camera.fovyDeg), o->height, pixel, std::ldexp(1.0, -20));
      return Status::Error(text);
    }
  }
  if (o->errorEvery > 0 && o->reference.empty())
    return Status::Error("vismask: --error-every: needs --reference REF.pfm to measure against");
  // --rays N alone keeps its meaning: N rays every shot.
  if (!o->hasRayAlloc && o->hasRays) o->rayAlloc = Options::RayAlloc::kFixed;
  // A resolution is a hemisphere mask's: given alone, it selects Method B.
  if (!o->hasMaskMethod && o->hasMaskRes) o->maskMethod = MaskMethod::kB;
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
  // Unshot power reaches 0 only when every queue drains, which a scene
  // that reflects never does: --stop-unshot 0 needs another stop.
  if (o->stopUnshot == 0.0 && o->maxShots == 0 && o->maxSeconds == 0.0 && o->rayBudget == 0 &&
      o->stopError == 0.0)
    return Status::Error(
        "vismask: --stop-unshot 0: would stop only when every queue drains, which a scene "
        "that reflects never does; give --max-shots, --max-seconds, --ray-budget or "
        "--stop-error too, or a fraction above 0");
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
  // Per-pixel direct light traces its shadow rays in one environment's grid.
  if (o->directSamples > 0 && numEnvs > 1)
    return Status::Error("vismask: --direct-samples: " + std::to_string(o->directSamples) +
                         " with " + std::to_string(numEnvs) +
                         " environments: per-pixel direct light needs one environment (give "
                         "--direct-samples 0, or no --envs)");
  if (o->directSamples < 0) o->directSamples = numEnvs == 1 ? kDefaultDirectSamples : 0;
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

std::string EnvSpec(const Options& o) {
  if (o.envsAuto) return "auto:" + std::to_string(o.envsAutoCount);
  return std::to_string(o.envs[0]) + "x" + std::to_string(o.envs[1]) + "x" +
         std::to_string(o.envs[2]);
}

}  // namespace vismask
