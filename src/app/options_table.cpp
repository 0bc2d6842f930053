// The option table (options_table.h): one row per option, and the parsers
// of the options whose syntax is their own (a list, a camera, a grid).
#include "vismask/app/options_table.h"

#include <cctype>
#include <cstring>
#include <type_traits>

#include "options_read.h"
#include "options_rows.h"
#include "vismask/solve/partition.h"

namespace vismask {

namespace option_rows {

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
  if (!ParseSky(v, &o->outside))
    return BadValue(a, v, "R,G,B (the sky's radiance, each >= 0) or FILE.hdr");
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

}  // namespace option_rows

using option_rows::Row;

const std::vector<OptionSpec>& OptionTable() {
  static const std::vector<OptionSpec> table = [] {
    std::vector<OptionSpec> specs;
    for (auto section : {option_rows::SolveRows, option_rows::ImageRows, option_rows::SceneRows,
                         option_rows::EnvironmentRows, option_rows::RunRows})
      for (const Row& r : section()) specs.push_back(r.s);
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