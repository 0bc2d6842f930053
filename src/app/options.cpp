#include "vismask/app/options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "options_read.h"
#include "vismask/app/options_table.h"
#include "vismask/parallel/transport.h"
#include "vismask/solve/partition.h"

namespace vismask {

Status BadValue(const std::string& flag, const std::string& value, const std::string& expected) {
  return Status::Error("vismask: " + flag + ": expected " + expected + ", got '" + value + "'");
}

bool ParseNumber(const std::string& s, double* out) {
  if (s.empty() || std::isspace(static_cast<unsigned char>(s[0]))) return false;
  errno = 0;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseCount(const std::string& s, uint64_t* out) {
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

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> parts(1);
  for (char ch : s) {
    if (ch == ',')
      parts.emplace_back();
    else
      parts.back() += ch;
  }
  return parts;
}

namespace {

// The least normal float: options stored as float refuse anything smaller
// rather than silently becoming 0 (--patch-size 0 is "automatic").
constexpr double kFloatMin = 1.17549435e-38;

bool InRange(const OptionSpec& s, double v) {
  const bool low = s.loOpen ? v > s.lo : v >= s.lo;
  const bool high = s.hi >= kNoLimit || (s.hiOpen ? v < s.hi : v <= s.hi);
  return low && high;
}

// "a, b or c": a choice's words as its error lists them.
std::string OneOf(const std::vector<std::string>& words) {
  std::string text;
  for (size_t k = 0; k < words.size(); ++k)
    text += (k == 0 ? "" : k + 1 == words.size() ? " or " : ", ") + words[k];
  return text;
}

// Stores a read value into the row's field: a count or number as the
// field's type, a choice as its index (enum), first word (bool) or word
// (string), a flag as true.
void Store(const OptionSpec& s, uint64_t count, double number, int choice, const std::string& word,
           Options* o) {
  std::visit(
      [&](auto field) {
        if constexpr (!std::is_same_v<decltype(field), std::monostate>) {
          auto& x = o->*field;
          using V = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<V, bool>) {
            x = s.kind == OptionKind::kFlag || choice == 0;
          } else if constexpr (std::is_same_v<V, std::string>) {
            x = word;
          } else if constexpr (std::is_enum_v<V>) {
            x = static_cast<V>(choice);
          } else if constexpr (std::is_floating_point_v<V>) {
            x = static_cast<V>(s.kind == OptionKind::kCount ? static_cast<double>(count) : number);
          } else {
            x = static_cast<V>(count);
          }
        }
      },
      s.field);
}

// Reads `v`, the value given to the row's option, into the options (a
// flag's is empty): the row's parser, or its kind's reader and range.
Status ReadValue(const OptionSpec& s, const std::string& v, Options* o) {
  uint64_t count = 0;
  double number = 0.0;
  int choice = -1;
  if (s.parse) {
    Status st = s.parse(s.name, v, o);
    if (!st.ok()) return st;
  } else if (s.kind == OptionKind::kCount) {
    if (!ParseCount(v, &count) || !InRange(s, static_cast<double>(count)))
      return BadValue(s.name, v, s.expected);
  } else if (s.kind == OptionKind::kNumber) {
    if (!ParseNumber(v, &number) || !InRange(s, number)) return BadValue(s.name, v, s.expected);
    if (s.tiny && number < kFloatMin) return BadValue(s.name, v, s.tiny);
  } else if (s.kind == OptionKind::kChoice) {
    const std::vector<std::string> words = ChoiceWords(s);
    for (size_t k = 0; k < words.size() && choice < 0; ++k)
      if (words[k] == v) choice = static_cast<int>(k);
    if (choice < 0) return BadValue(s.name, v, OneOf(words));
  } else if (s.kind == OptionKind::kText) {
    if (v.empty()) return BadValue(s.name, v, s.expected);
  }
  if (!s.parse) Store(s, count, number, choice, v, o);
  if (s.given) o->*s.given = true;
  return Status::Ok();
}

// vismask view OUT_DIR [--glb NAME.glb] [--port P]: its own two options.
Status ParseView(const std::vector<std::string>& args, Options* o) {
  o->command = "view";
  for (size_t i = 1; i < args.size(); ++i) {
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
        if (v.empty()) return BadValue(a, v, "a file name");
        o->viewGlb = v;
      } else {
        if (!ParseCount(v, &u) || u < 1 || u > 65535) return BadValue(a, v, "a port in [1, 65535]");
        o->viewPort = static_cast<int>(u);
      }
      continue;
    }
    if (a.rfind("--", 0) == 0)
      return Status::Error("vismask: view: unknown option '" + a + "' (try 'vismask view --help')");
    if (!o->viewDir.empty())
      return Status::Error("vismask: view: unexpected argument '" + a + "' (one OUT_DIR)");
    if (a.empty()) return Status::Error("vismask: view: OUT_DIR is empty");
    o->viewDir = a;
  }
  if (o->viewDir.empty())
    return Status::Error("vismask: view: usage: vismask view OUT_DIR [--glb NAME.glb] [--port P]");
  return Status::Ok();
}

// compare and verify: fixed arguments.
Status ParseCompareOrVerify(const std::vector<std::string>& args, Options* o) {
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
  if (args.size() != 2 || args[1].empty() || args[1].rfind("--", 0) == 0)
    return Status::Error("vismask: verify: usage: vismask verify OUT_DIR");
  o->command = "verify";
  o->verifyDir = args[1];
  return Status::Ok();
}

// What a checkpoint must agree with: the arguments as given, less the
// scene (compared by its bytes), --envs (by its meaning) and the options
// the table lets differ.
std::vector<std::string> ResultArgs(const std::vector<std::string>& args) {
  std::vector<std::string> result;
  for (size_t k = 1; k < args.size(); ++k) {
    const OptionSpec* s = FindOption(args[k]);
    if (!s) continue;  // the scene (values are taken with their flag)
    const bool flag = s->kind == OptionKind::kFlag;
    if (s->resume == ResumeRule::kMustMatch) {
      result.push_back(args[k]);
      if (!flag && k + 1 < args.size()) result.push_back(args[k + 1]);
    }
    if (!flag) ++k;
  }
  return result;
}

// The rules between options that concern the image, the rays and the stop.
Status CheckCombinations(Options* o) {
  if (o->command != "render" && (!o->checkpointDir.empty() || !o->resumeDir.empty()))
    return Status::Error("vismask: --checkpoint and --resume are options of 'vismask render'");
  if (o->checkpointDir.empty()) o->checkpointDir = o->resumeDir;
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
  return Status::Ok();
}

// The environments, the ranks over them and what depends on their count.
Status ResolveEnvironments(Options* o) {
  AutoEnvsForRanks(o->ranks, o);
  if (o->envsAuto) {
    // auto: as many environments as ranks (pipe; under mpirun, the world).
    if (o->envsAutoCount == 0) o->envsAutoCount = std::max(o->ranks, 1);
    // A placeholder shape of the right count; init picks it from the scene.
    if (!ChooseEnvShape(o->envsAutoCount, glm::vec3(1.0f), o->envs))
      return Status::Error("vismask: --envs: auto:" + std::to_string(o->envsAutoCount) +
                           ": no grid of that many environments with at most 64 a side");
  }
  const int numEnvs = o->envs[0] * o->envs[1] * o->envs[2];
  ResolveRounds(numEnvs, o);
  // Per-pixel direct light: the default whatever the environments (with
  // several each gathers every environment's emitters through the transit
  // maps, or with --foreign-mask-res 0 its own: docs/design/direct-light.md).
  if (o->directSamples < 0) o->directSamples = kDefaultDirectSamples;
  ResolveEmissionRays(numEnvs, o);
  if (o->ranks > numEnvs)
    return Status::Error("vismask: --ranks: " + std::to_string(o->ranks) + " ranks for " +
                         std::to_string(numEnvs) +
                         " environments (each rank needs one; see --envs)");
  const std::string loop = LoopTransportError(o->transport, o->ranks);
  if (!loop.empty()) return Status::Error(loop);
  if (!o->envOrder.empty()) {
    const size_t n = size_t(numEnvs);
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

}  // namespace

Status ParseArgs(int argc, const char* const* argv, Options* o) {
  *o = Options();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return Status::Error("vismask: no command (try 'vismask --help')");
  // --help [all]: the short usage, or every option (what follows is
  // ignored, as it always was after --help).
  auto help = [&](size_t at) {
    o->help = true;
    o->helpAll = at + 1 < args.size() && args[at + 1] == "all";
    return Status::Ok();
  };
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") return help(0);
  if (args[0] == "compare" || args[0] == "verify") return ParseCompareOrVerify(args, o);
  if (args[0] == "view") return ParseView(args, o);
  if (args[0] != "render" && args[0] != "footprint" && args[0] != "scene-dump")
    return Status::Error("vismask: unknown command '" + args[0] + "' (try 'vismask --help')");
  o->command = args[0];
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") return help(i);
    if (a.rfind("--", 0) != 0) {
      if (!o->scene.empty())
        return Status::Error("vismask: unexpected argument '" + a + "' (one scene per run)");
      o->scene = a;
      continue;
    }
    const OptionSpec* spec = FindOption(a);
    if (spec && spec->kind == OptionKind::kFlag) {
      Status s = ReadValue(*spec, "", o);
      if (!s.ok()) return s;
      continue;
    }
    if (i + 1 >= args.size()) return Status::Error("vismask: " + a + ": missing value");
    // A value that is itself an option ("--out --quiet") is a missing value,
    // not a directory called --quiet.
    if (args[i + 1].rfind("--", 0) == 0)
      return Status::Error("vismask: " + a + ": missing value (the next argument is the option '" +
                           args[i + 1] + "')");
    if (!spec) return Status::Error("vismask: unknown option '" + a + "' (try 'vismask --help')");
    Status s = ReadValue(*spec, args[++i], o);
    if (!s.ok()) return s;
  }
  if (o->scene.empty())
    return Status::Error("vismask: " + o->command + ": no scene given (vismask " + o->command +
                         " SCENE.obj)");
  o->resultArgs = ResultArgs(args);
  Status s = CheckCombinations(o);
  return s.ok() ? ResolveEnvironments(o) : s;
}

std::string EnvSpec(const Options& o) {
  if (o.envsAuto) return "auto:" + std::to_string(o.envsAutoCount);
  return std::to_string(o.envs[0]) + "x" + std::to_string(o.envs[1]) + "x" +
         std::to_string(o.envs[2]);
}

}  // namespace vismask
