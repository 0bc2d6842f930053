// The parser's text helpers (scene_parse.h): tokens, numbers, names,
// corners; its files and lines are src/scene/scene_lines.cpp's.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

#include "scene_parse.h"

namespace vismask::objload {

std::string CoordinateError(double x) {
  return "coordinate " + Num(x) + " is beyond +-" + Num(kMaxCoordinate) +
         " (float ray tests would overflow); scale the scene down";
}

namespace {
bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

}  // namespace

Tokens Tokenize(const std::string& line) {
  Tokens tokens;
  size_t i = 0;
  while (i < line.size() && line[i] != '#') {
    if (IsSpace(line[i])) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < line.size() && !IsSpace(line[j]) && line[j] != '#') ++j;
    tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

std::string MapName(const std::string& line, const Tokens& t, bool* hadOptions) {
  // The options of a texture map statement and how many values each takes
  // at most (numbers; -blendu and the like take one word).
  struct Option {
    const char* name;
    size_t values;
    bool numbers;
  };
  static const Option kOptions[] = {
      {"-blendu", 1, false}, {"-blendv", 1, false}, {"-bm", 1, true},       {"-boost", 1, true},
      {"-cc", 1, false},     {"-clamp", 1, false},  {"-imfchan", 1, false}, {"-mm", 2, true},
      {"-o", 3, true},       {"-s", 3, true},       {"-t", 3, true},        {"-texres", 1, true},
      {"-type", 1, false}};
  *hadOptions = false;
  size_t k = 1;
  while (k < t.size() && t[k].size() > 1 && t[k][0] == '-') {
    const Option* o = nullptr;
    for (const Option& c : kOptions)
      if (t[k] == c.name) o = &c;
    if (!o) break;  // not an option: a name that starts with '-'
    *hadOptions = true;
    ++k;
    for (size_t v = 0; v < o->values && k + 1 < t.size(); ++v, ++k) {
      if (!o->numbers) continue;
      char* end = nullptr;
      std::strtod(t[k].c_str(), &end);
      if (end == t[k].c_str() || *end != '\0') break;
    }
  }
  if (k >= t.size()) return "";
  // The tokens are the line's own bytes in order: the name runs from the
  // k-th to the end of the last, with the spaces between kept as written.
  size_t at = 0, begin = 0, end = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    at = line.find(t[i], at);
    if (i == k) begin = at;
    at += t[i].size();
  }
  end = at;
  return line.substr(begin, end - begin);
}

std::string Str(size_t n) {
  return std::to_string(n);
}

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", x);
  return buf;
}

// A piece of the input quoted in a message: at most 32 bytes, anything but
// printable ASCII escaped (\xNN), so that binary garbage, terminal escapes
// or a megabyte line never reach the terminal whole.
std::string Quote(const std::string& s) {
  constexpr size_t kMax = 32;
  std::string q = "'";
  for (size_t i = 0; i < s.size() && i < kMax; ++i)
    AppendEscaped(&q, static_cast<unsigned char>(s[i]));
  return q + (s.size() > kMax ? "'..." : "'");
}

void AppendEscaped(std::string* out, unsigned char c) {
  if (c >= 0x20 && c < 0x7f && c != '\\') {
    *out += static_cast<char>(c);
  } else {
    char hex[8];
    std::snprintf(hex, sizeof hex, "\\x%02x", c);
    *out += hex;
  }
}

// Whether an unknown MTL key may be named in a warning: a short identifier,
// as MTL keys are. Anything else (a line of a file that is not MTL at all)
// is counted, never echoed.
bool LooksLikeKey(const std::string& s) {
  if (s.empty() || s.size() > 24) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

// A file named inside another (mtllib in an OBJ, map_Kd in an MTL): relative
// to the naming file's directory, or as it is when absolute.
std::string Beside(const std::string& namingFile, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  size_t slash = namingFile.rfind('/');
  return (slash == std::string::npos ? "" : namingFile.substr(0, slash + 1)) + name;
}

// Parses tokens[first..first+count) as finite floats into out[].
std::string ParseFloats(const Tokens& tokens, size_t first, size_t count, float* out) {
  for (size_t i = 0; i < count; ++i) {
    const std::string& s = tokens[first + i];
    char* end = nullptr;
    double d = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end != '\0') return "bad number " + Quote(s);
    if (!std::isfinite(d)) return "number " + Quote(s) + " is not finite";
    if (std::fabs(d) > std::numeric_limits<float>::max())
      return "number " + Quote(s) + " is too large";
    if (d != 0.0 && std::fabs(d) < std::numeric_limits<float>::min())
      return "number " + Quote(s) +
             " is too small for float (it would be 0 or denormal; least 1.2e-38)";
    out[i] = static_cast<float>(d);
  }
  return "";
}

bool IsInteger(const std::string& s) {
  size_t i = (!s.empty() && (s[0] == '-' || s[0] == '+')) ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

// Resolves a 1-based OBJ index (negative: counts back from the last element
// defined so far) against `count` elements of `what` ("vertex", ...).
namespace {
std::string ResolveIndex(const std::string& s, const std::string& corner, size_t count,
                         const char* what, const char* plural, size_t* index) {
  long long i = std::strtoll(s.c_str(), nullptr, 10);  // saturates: then out of range
  if (i == 0)
    return std::string(what) + " index 0 in " + Quote(corner) + " (OBJ indices start at 1)";
  long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
  if (resolved < 0 || resolved >= static_cast<long long>(count))
    return std::string(what) + " index " + (s.size() > 20 ? s.substr(0, 20) + "..." : s) +
           " out of range (" + Str(count) + " " + plural + " so far)";
  *index = static_cast<size_t>(resolved);
  return "";
}

}  // namespace

std::string ParseCorner(const std::string& s, size_t numVertices, size_t numUvs, size_t numNormals,
                        CornerIndex* out) {
  const std::string bad = "bad face vertex " + Quote(s);
  size_t slash = s.find('/');
  std::string pos = s.substr(0, slash), uv, normal;
  if (slash != std::string::npos) {
    std::string rest = s.substr(slash + 1);
    size_t slash2 = rest.find('/');
    uv = rest.substr(0, slash2);
    if (slash2 != std::string::npos) {
      normal = rest.substr(slash2 + 1);
      if (!IsInteger(normal)) return bad;
    }
    if (!(IsInteger(uv) || (uv.empty() && slash2 != std::string::npos))) return bad;
  }
  if (!IsInteger(pos)) return bad;
  CornerIndex c;
  std::string err = ResolveIndex(pos, s, numVertices, "vertex", "vertices", &c.v);
  if (err.empty() && !uv.empty())
    err = ResolveIndex(uv, s, numUvs, "texture coordinate", "texture coordinates", &c.vt);
  if (err.empty() && !normal.empty())
    err = ResolveIndex(normal, s, numNormals, "normal", "normals", &c.vn);
  *out = c;
  return err;
}

// "1 face", "3 faces".
std::string Count(size_t n, const char* one, const char* many) {
  return Str(n) + " " + (n == 1 ? one : many);
}

// Parses "a b c" (or one number) leniently, for keys only read to warn.
bool LenientFloats(const Tokens& t, size_t count, double* out) {
  if (t.size() < count + 1) return false;
  for (size_t i = 0; i < count; ++i) {
    char* end = nullptr;
    out[i] = std::strtod(t[i + 1].c_str(), &end);
    if (end == t[i + 1].c_str() || *end != '\0' || !std::isfinite(out[i])) return false;
  }
  return true;
}

// MTL keys that do not matter to diffuse radiosity, read silently (those
// that describe a specular or transparent material are looked at for the
// warning that names such materials).
bool IsSilentMtlKey(const std::string& key) {
  static const char* const kKeys[] = {
      "Ns",     "Ni",     "d",        "Tr",       "Tf",   "illum", "Ks",    "sharpness", "map_Ka",
      "map_Ks", "map_Ns", "map_bump", "map_Bump", "bump", "disp",  "decal", "refl",      "Km"};
  for (const char* k : kKeys)
    if (key == k) return true;
  return false;
}

// Why a material is not purely diffuse, or "" if it is.
std::string NotDiffuse(const Finish& f) {
  if (f.illum >= 3 && f.illum <= 9) return "illum " + std::to_string(f.illum);
  if (f.ks && f.illum != 0 && f.illum != 1) return "Ks";
  if (f.d < 1.0) return "d " + Num(f.d);
  if (f.tf) return "Tf";
  return "";
}

}  // namespace vismask::objload
