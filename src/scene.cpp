#include "vismask/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vector_relational.hpp>

#include "geometry_util.h"
#include "vismask/face.h"

namespace vismask {
namespace {

// The largest OBJ or MTL file read (the whole file is held in memory at init).
constexpr uintmax_t kMaxFileBytes = uintmax_t{4} << 30;

// What float geometry and float images can carry (docs/STABILITY.md). Ray
// tests multiply coordinates and square lengths in float (max 3.4e38, least
// normal 1.2e-38), so coordinates stay within 1e15 and faces above 1e-15 in
// size; radiosity is bounded by max Ke / (1 - max Kd) (when max Kd < 1), and the image holds it
// in float, so that bound stays within 1e36, and above 1e-30 so that the
// image is not all denormals.
constexpr double kMaxCoordinate = 1e15;
// A scene far from the origin for its size: its float coordinates step by
// more than this share of its extent (Cornell moved by 3e6 in each axis:
// steps of 0.25 on a 559 box, image 0.56% off; by 1e7: 55% off).
constexpr double kMaxStepShare = 2.5e-4;
constexpr double kMinFaceSize = 1e-15;
constexpr double kMaxRadiosity = 1e36;
constexpr double kMinRadiosity = 1e-30;

std::string Num(double x);

std::string CoordinateError(double x) {
  return "coordinate " + Num(x) + " is beyond +-" + Num(kMaxCoordinate) +
         " (float ray tests would overflow); scale the scene down";
}

using Tokens = std::vector<std::string>;

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Splits a line at whitespace; '#' starts a comment, a CR (CRLF files) is space.
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

std::string Str(size_t n) { return std::to_string(n); }

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
  for (size_t i = 0; i < s.size() && i < kMax; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      q += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      q += hex;
    }
  }
  return q + (s.size() > kMax ? "'..." : "'");
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

// Splits text into lines as std::getline does: at '\n', the last line kept
// even without one, no empty line after a final '\n'; a leading BOM dropped.
void SplitLines(const std::string& text, std::vector<std::string>* lines) {
  // A UTF-8 byte-order mark (some Windows editors write one) is not text.
  size_t start = text.compare(0, 3, "\xef\xbb\xbf") == 0 ? 3 : 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    lines->push_back(text.substr(start, end - start));
    start = end + 1;
  }
}

// Reads a whole file; returns an error message, empty on success.
std::string ReadText(const std::string& path, std::string* text) {
  // Only regular files, of a size the loader can hold: a device (/dev/zero)
  // or a FIFO would be read until memory runs out.
  std::error_code ec;
  std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec) return std::string("cannot open (") + ec.message() + ")";
  if (!std::filesystem::is_regular_file(st)) return "cannot read: not a regular file";
  uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return std::string("cannot read (") + ec.message() + ")";
  if (size > kMaxFileBytes)
    return "cannot read: " + std::to_string(size) + " bytes, more than the " +
           std::to_string(kMaxFileBytes) + " a scene file may have";
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::string("cannot open (") + std::strerror(errno) + ")";
  // istream::read, not istreambuf_iterator: a read error (a directory)
  // sets badbit instead of throwing.
  std::string all;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) all.append(buf, static_cast<size_t>(in.gcount()));
  if (in.bad()) return "cannot read";
  *text = std::move(all);
  return "";
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
    if (std::fabs(d) > std::numeric_limits<float>::max()) return "number " + Quote(s) + " is too large";
    if (d != 0.0 && std::fabs(d) < std::numeric_limits<float>::min())
      return "number " + Quote(s) + " is too small for float (it would be 0 or denormal; least 1.2e-38)";
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
std::string ResolveIndex(const std::string& s, const std::string& corner, size_t count,
                         const char* what, const char* plural, size_t* index) {
  long long i = std::strtoll(s.c_str(), nullptr, 10);  // saturates: then out of range
  if (i == 0)
    return std::string(what) + " index 0 in " + Quote(corner) + " (OBJ indices start at 1)";
  long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
  if (resolved < 0 || resolved >= static_cast<long long>(count))
    return std::string(what) + " index " + (s.size() > 20 ? s.substr(0, 20) + "..." : s) + " out of range (" + Str(count) + " " + plural +
           " so far)";
  *index = static_cast<size_t>(resolved);
  return "";
}

// A face corner's indices, 0-based; kNone where the corner gives none.
constexpr size_t kNone = static_cast<size_t>(-1);
struct CornerIndex {
  size_t v = kNone, vt = kNone, vn = kNone;
};

// Resolves a face corner "i", "i/t", "i/t/n" or "i//n".
std::string ParseCorner(const std::string& s, size_t numVertices, size_t numUvs,
                        size_t numNormals, CornerIndex* out) {
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
  if (err.empty() && !uv.empty()) err = ResolveIndex(uv, s, numUvs, "texture coordinate", "texture coordinates", &c.vt);
  if (err.empty() && !normal.empty()) err = ResolveIndex(normal, s, numNormals, "normal", "normals", &c.vn);
  *out = c;
  return err;
}

// "1 face", "3 faces".
std::string Count(size_t n, const char* one, const char* many) {
  return Str(n) + " " + (n == 1 ? one : many);
}

// A kind of mended face, counted: how many, the first one's line, and the
// farthest corner off the plane (non-planar faces).
struct FaceTally {
  size_t faces = 0;
  size_t corners = 0;  // corners removed
  int line = 0;
  double off = 0.0;
  void Add(int at) {
    if (faces++ == 0) line = at;
  }
};

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
  static const char* const kKeys[] = {"Ns", "Ni", "d", "Tr", "Tf", "illum", "Ks", "sharpness",
                                      "map_Ka", "map_Ks", "map_Ns", "map_bump", "map_Bump",
                                      "bump", "disp", "decal", "refl", "Km"};
  for (const char* k : kKeys)
    if (key == k) return true;
  return false;
}

// What makes a material more than diffuse: kept per material while its MTL
// is read, for one warning after loading.
struct Finish {
  int illum = -1;   // -1: not given
  bool ks = false;  // some Ks channel > 0
  bool tf = false;  // some Tf channel < 1
  double d = 1.0;   // dissolve (1 - Tr)
};

// Why a material is not purely diffuse, or "" if it is.
std::string NotDiffuse(const Finish& f) {
  if (f.illum >= 3 && f.illum <= 9) return "illum " + std::to_string(f.illum);
  if (f.ks && f.illum != 0 && f.illum != 1) return "Ks";
  if (f.d < 1.0) return "d " + Num(f.d);
  if (f.tf) return "Tf";
  return "";
}

class Loader {
 public:
  Loader(Scene* scene, const SceneFileReader& readMtl, const LoadOptions& options)
      : scene_(scene), readMtl_(readMtl), options_(options) {}
  Status LoadObj(const std::string& path, const std::string& text);
  // Applies options.emit; an --emit that names no material is an error.
  Status ApplyEmit();
  // The warnings, one line per kind, in the order they first arose and the
  // aggregate ones after.
  std::vector<std::string> Warnings() const;

 private:
  Status LoadMtl(const std::string& path, const std::string& objPath, int objLine);
  // One warning line per distinct `what`, at its first file:line.
  void Warn(const std::string& path, int line, const std::string& what) {
    if (!warnedKeys_.insert(what).second) return;
    warnings_.push_back(path + ":" + std::to_string(line) + ": warning: " + what);
  }

  Scene* scene_;
  const SceneFileReader& readMtl_;
  const LoadOptions& options_;
  std::vector<std::string> warnings_;
  std::vector<glm::vec3> vertices_;
  std::vector<glm::vec2> uvs_;
  std::vector<glm::vec3> normals_;
  std::map<std::string, std::pair<uint32_t, std::string>> materials_;  // index, "file:line"
  std::vector<Finish> finishes_;                                       // per material
  std::set<std::string> loadedMtls_;
  std::set<std::string> warnedKeys_;
  std::vector<std::string> ignoredKeys_;  // unknown MTL keys, in order of first use
  std::string ignoredWhere_;              // "file:line" of the first
  size_t notMtlLines_ = 0;                // lines whose first word is no MTL key at all
  std::string notMtlWhere_;               // "file:line" of the first
  std::string path_;                      // the OBJ
  FaceTally triangulated_, cornersRemoved_, degenerate_, selfIntersecting_;
  std::vector<std::string> replacedKe_;  // "name (Ke r g b)" of each --emit that replaced one
  std::string replacedWhere_;
};

Status Loader::ApplyEmit() {
  std::vector<Material>& materials = scene_->materials;
  for (const EmitOverride& e : options_.emit) {
    auto it = materials_.find(e.material);
    if (it == materials_.end()) {
      std::string names;
      for (const Material& m : materials) names += (names.empty() ? "" : ", ") + m.name;
      return Status::Error("vismask: --emit: no material '" + e.material + "' in " + path_ +
                           (names.empty() ? " (it defines none)" : " (its materials: " + names + ")"));
    }
    Material& m = materials[it->second.first];
    if (m.ke != glm::vec3(0.0f)) {
      if (replacedKe_.empty()) replacedWhere_ = m.where;
      replacedKe_.push_back(m.name + " (Ke " + Num(m.ke.x) + " " + Num(m.ke.y) + " " + Num(m.ke.z) + ")");
    }
    m.ke = e.fromKa ? m.ka : e.ke;
  }
  return Status::Ok();
}

std::vector<std::string> Loader::Warnings() const {
  std::vector<std::string> w = warnings_;
  auto at = [&](int line) { return path_ + ":" + std::to_string(line) + ": warning: "; };
  if (!ignoredKeys_.empty()) {
    std::string keys;
    for (const std::string& k : ignoredKeys_) keys += (keys.empty() ? "'" : ", '") + k + "'";
    w.push_back(ignoredWhere_ + ": warning: ignoring MTL key" + (ignoredKeys_.size() > 1 ? "s " : " ") +
                keys + (ignoredKeys_.size() > 1 ? " (first here)" : ""));
  }
  if (notMtlLines_ > 0)
    w.push_back(notMtlWhere_ + ": warning: " + std::to_string(notMtlLines_) +
                (notMtlLines_ > 1 ? " lines are" : " line is") +
                " not MTL statements: ignored (first here; is it an MTL file?)");
  // Specular or transparent materials that faces use, in material order.
  std::vector<bool> used(scene_->materials.size(), false);
  for (const Polygon& p : scene_->polygons) used[p.material] = true;
  std::string named, where;
  for (size_t i = 0; i < scene_->materials.size(); ++i) {
    std::string why = used[i] ? NotDiffuse(finishes_[i]) : "";
    if (why.empty()) continue;
    if (named.empty()) where = scene_->materials[i].where;
    named += (named.empty() ? "" : ", ") + scene_->materials[i].name + " (" + why + ")";
  }
  if (!named.empty())
    w.push_back(where + ": warning: specular materials rendered as diffuse with their Kd: " + named);
  if (!replacedKe_.empty()) {
    std::string list;
    for (const std::string& r : replacedKe_) list += (list.empty() ? "" : ", ") + r;
    w.push_back(replacedWhere_ + ": warning: --emit replaces the MTL's Ke of " + list);
  }
  const FaceTally& t = triangulated_;
  if (t.faces)
    w.push_back(at(t.line) + Count(t.faces, "non-planar face", "non-planar faces") +
                " triangulated (first here; up to " + Num(t.off) + " off " +
                (t.faces == 1 ? "its" : "their") + " plane)");
  if (cornersRemoved_.faces)
    w.push_back(at(cornersRemoved_.line) +
                Count(cornersRemoved_.corners, "repeated or collinear corner", "repeated or collinear corners") +
                " removed from " + Count(cornersRemoved_.faces, "face", "faces") + " (first here)");
  if (degenerate_.faces)
    w.push_back(at(degenerate_.line) + Count(degenerate_.faces, "degenerate face", "degenerate faces") +
                " dropped (zero area: repeated or collinear vertices; first here)");
  if (selfIntersecting_.faces)
    w.push_back(at(selfIntersecting_.line) +
                Count(selfIntersecting_.faces, "self-intersecting face", "self-intersecting faces") +
                " dropped (first here)");
  return w;
}

Status Loader::LoadObj(const std::string& path, const std::string& text) {
  path_ = path;
  std::vector<std::string> lines;
  SplitLines(text, &lines);
  std::string err;
  bool haveMaterial = false;
  uint32_t material = 0;
  uint32_t smoothing = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const Tokens t = Tokenize(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    const size_t args = t.size() - 1;
    if (key == "v") {
      if (args != 3 && args != 4)
        return Status::At(path, line, "'v' needs 3 or 4 numbers, got " + Str(args));
      float xyzw[4];
      err = ParseFloats(t, 1, args, xyzw);  // w is checked, then ignored
      if (!err.empty()) return Status::At(path, line, err);
      // Checked here, at the vertex's own line, before any face made of it
      // is judged (a face with a far corner looks degenerate).
      for (int a = 0; a < 3; ++a)
        if (std::fabs(xyzw[a]) > kMaxCoordinate)
          return Status::At(path, line, CoordinateError(xyzw[a]));
      vertices_.emplace_back(xyzw[0], xyzw[1], xyzw[2]);
    } else if (key == "f") {
      if (args < 3)
        return Status::At(path, line, "face with " + Str(args) + " vertices (needs 3 or more)");
      if (!haveMaterial) return Status::At(path, line, "face before any 'usemtl'");
      Polygon p;
      p.material = material;
      p.line = line;
      p.smoothing = smoothing;
      size_t withUv = 0, withNormal = 0;
      for (size_t k = 1; k <= args; ++k) {
        CornerIndex c;
        err = ParseCorner(t[k], vertices_.size(), uvs_.size(), normals_.size(), &c);
        if (!err.empty()) return Status::At(path, line, err);
        p.corners.push_back(vertices_[c.v]);
        p.uv.push_back(c.vt == kNone ? glm::vec2(0.0f) : uvs_[c.vt]);
        p.vn.push_back(c.vn == kNone ? glm::vec3(0.0f) : normals_[c.vn]);
        withUv += c.vt != kNone;
        withNormal += c.vn != kNone;
      }
      // Per-corner data is all or nothing: a face that gives it for some
      // corners only keeps none (said once per kind).
      if (withUv != args) {
        if (withUv != 0) Warn(path, line, "texture coordinates on some corners of a face only: ignored");
        p.uv.clear();
      }
      if (withNormal != args) {
        if (withNormal != 0) Warn(path, line, "normals on some corners of a face only: ignored");
        p.vn.clear();
      }
      FaceResult r = ShapeFace(p, options_.strict, &scene_->polygons);
      if (r.fate == FaceResult::kRefused) return Status::At(path, line, r.error);
      if (r.removedCorners > 0 && (r.fate == FaceResult::kKept || r.fate == FaceResult::kTriangulated)) {
        cornersRemoved_.Add(line);
        cornersRemoved_.corners += r.removedCorners;
      }
      if (r.fate == FaceResult::kTriangulated) {
        triangulated_.Add(line);
        triangulated_.off = std::max(triangulated_.off, r.offPlane);
        // Triangles too thin to keep are degenerate pieces of the face.
        if (r.droppedTriangles > 0) degenerate_.Add(line);
      }
      if (r.fate == FaceResult::kDegenerate) degenerate_.Add(line);
      if (r.fate == FaceResult::kSelfIntersecting) selfIntersecting_.Add(line);
    } else if (key == "usemtl") {
      if (args != 1) return Status::At(path, line, "'usemtl' needs 1 name, got " + Str(args));
      auto it = materials_.find(t[1]);
      if (it == materials_.end())
        return Status::At(path, line, "undefined material " + Quote(t[1]));
      material = it->second.first;
      haveMaterial = true;
    } else if (key == "mtllib") {
      if (args == 0) return Status::At(path, line, "'mtllib' needs a file name");
      for (size_t k = 1; k <= args; ++k) {
        Status s = LoadMtl(Beside(path, t[k]), path, line);
        if (!s.ok()) return s;
      }
    } else if (key == "l" || key == "p") {
      return Status::At(path, line, Quote(key) + ": lines and points are not supported");
    } else if (key == "vt") {
      if (args < 1 || args > 3)
        return Status::At(path, line, "'vt' needs 1 to 3 numbers, got " + Str(args));
      float uvw[3] = {0.0f, 0.0f, 0.0f};
      err = ParseFloats(t, 1, args, uvw);  // w is checked, then ignored
      if (!err.empty()) return Status::At(path, line, err);
      uvs_.emplace_back(uvw[0], uvw[1]);
    } else if (key == "vn") {
      if (args != 3) return Status::At(path, line, "'vn' needs 3 numbers, got " + Str(args));
      float xyz[3];
      err = ParseFloats(t, 1, 3, xyz);
      if (!err.empty()) return Status::At(path, line, err);
      normals_.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (key == "s") {
      if (args != 1) return Status::At(path, line, "'s' needs 1 group or 'off', got " + Str(args));
      if (t[1] == "off") {
        smoothing = 0;
      } else {
        if (!IsInteger(t[1]) || t[1][0] == '-')
          return Status::At(path, line, "bad smoothing group " + Quote(t[1]));
        unsigned long long g = std::strtoull(t[1].c_str(), nullptr, 10);
        if (g > 0xffffffffull) return Status::At(path, line, "smoothing group " + Quote(t[1]) + " is too large");
        smoothing = static_cast<uint32_t>(g);
      }
    } else if (key != "o" && key != "g") {
      return Status::At(path, line, "unknown statement " + Quote(key));
    }
  }
  return Status::Ok();
}

Status Loader::LoadMtl(const std::string& path, const std::string& objPath, int objLine) {
  if (!loadedMtls_.insert(path).second) return Status::Ok();
  std::string text;
  std::string err = readMtl_(path, &text);
  if (!err.empty()) return Status::At(objPath, objLine, err + " MTL file '" + path + "'");
  std::vector<std::string> lines;
  SplitLines(text, &lines);
  std::vector<Material>& materials = scene_->materials;
  bool haveMaterial = false;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const Tokens t = Tokenize(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    const size_t args = t.size() - 1;
    if (key == "newmtl") {
      if (args != 1) return Status::At(path, line, "'newmtl' needs 1 name, got " + Str(args));
      std::string where = path + ":" + std::to_string(line);
      auto [it, added] =
          materials_.emplace(t[1], std::make_pair(static_cast<uint32_t>(materials.size()), where));
      if (!added)
        return Status::At(path, line,
                          "duplicate material " + Quote(t[1]) + " (first at " + it->second.second + ")");
      Material m;
      m.name = t[1];
      m.where = where;
      materials.push_back(std::move(m));
      finishes_.emplace_back();
      haveMaterial = true;
    } else if (key == "Ka") {
      if (!haveMaterial) return Status::At(path, line, "'Ka' before any 'newmtl'");
      if (args != 3) return Status::At(path, line, "'Ka' needs 3 numbers, got " + Str(args));
      float rgb[3];
      err = ParseFloats(t, 1, 3, rgb);
      if (!err.empty()) return Status::At(path, line, err);
      for (float x : rgb)
        if (x < 0.0f) return Status::At(path, line, "Ka must be >= 0, got " + Num(x));
      materials.back().ka = glm::vec3(rgb[0], rgb[1], rgb[2]);
    } else if (key == "map_Kd") {
      if (!haveMaterial) return Status::At(path, line, "'map_Kd' before any 'newmtl'");
      if (args == 0) return Status::At(path, line, "'map_Kd' needs a file name");
      // Options (-bm 1, -s 1 1 1, ...) come before the name, which is the
      // last token; they are not applied, and said so once.
      if (args > 1) Warn(path, line, "ignoring map_Kd options");
      materials.back().mapKd = Beside(path, t.back());
      materials.back().mapKdWhere = path + ":" + std::to_string(line);
    } else if (key == "Kd" || key == "Ke") {
      if (!haveMaterial) return Status::At(path, line, Quote(key) + " before any 'newmtl'");
      if (args != 3)
        return Status::At(path, line, Quote(key) + " needs 3 numbers, got " + Str(args));
      float rgb[3];
      err = ParseFloats(t, 1, 3, rgb);
      if (!err.empty()) return Status::At(path, line, err);
      for (float x : rgb) {
        if (key == "Kd" && !(x >= 0.0f && x <= 1.0f))
          return Status::At(path, line, "Kd must be in [0, 1], got " + Num(x));
        if (key == "Ke" && x < 0.0f)
          return Status::At(path, line, "Ke must be >= 0, got " + Num(x));
      }
      (key == "Kd" ? materials.back().kd : materials.back().ke) = glm::vec3(rgb[0], rgb[1], rgb[2]);
    } else if (IsSilentMtlKey(key)) {
      // Read only to name specular or transparent materials after loading.
      if (!haveMaterial) continue;
      Finish& f = finishes_.back();
      double v[3];
      // Models are 0 to 10: a number beyond them is none (as if not given),
      // never converted to int (outside its range that is undefined).
      if (key == "illum" && LenientFloats(t, 1, v)) f.illum = v[0] >= 0.0 && v[0] < 11.0 ? static_cast<int>(v[0]) : -1;
      if (key == "Ks" && LenientFloats(t, 3, v)) f.ks = v[0] > 0.0 || v[1] > 0.0 || v[2] > 0.0;
      if (key == "Tf" && LenientFloats(t, 3, v)) f.tf = v[0] < 1.0 || v[1] < 1.0 || v[2] < 1.0;
      if (key == "d" && LenientFloats(t, 1, v)) f.d = v[0];
      if (key == "Tr" && LenientFloats(t, 1, v)) f.d = 1.0 - v[0];
    } else if (!LooksLikeKey(key)) {
      if (notMtlLines_++ == 0) notMtlWhere_ = path + ":" + std::to_string(line);
    } else {
      if (ignoredKeys_.empty()) ignoredWhere_ = path + ":" + std::to_string(line);
      if (std::find(ignoredKeys_.begin(), ignoredKeys_.end(), key) == ignoredKeys_.end())
        ignoredKeys_.push_back(key);
    }
  }
  return Status::Ok();
}

// Whether the faces close space with their fronts facing in, so that no
// ray leaving a front can escape or reach a back face: every edge is run by
// exactly two faces in opposite directions (edges matched by their end
// points as read, so a T-junction leaves a scene open), and of the
// edge-connected parts exactly one faces in (negative signed volume), its
// box holding every other part, which all face out (blocks standing in a
// room). Other nestings are taken as open: a part inside another part is
// not looked into.
bool ClosedFacingIn(const std::vector<Polygon>& polys) {
  using Point = std::array<float, 3>;
  auto point = [](const glm::vec3& v) { return Point{v.x, v.y, v.z}; };
  std::map<std::pair<Point, Point>, std::vector<uint32_t>> edges;  // directed edge -> faces
  for (uint32_t f = 0; f < polys.size(); ++f) {
    const std::vector<glm::vec3>& c = polys[f].corners;
    for (size_t i = 0; i < c.size(); ++i)
      edges[{point(c[i]), point(c[(i + 1) % c.size()])}].push_back(f);
  }
  std::vector<uint32_t> parent(polys.size());
  for (uint32_t f = 0; f < polys.size(); ++f) parent[f] = f;
  auto root = [&](uint32_t f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  for (const auto& [edge, faces] : edges) {
    auto twin = edges.find({edge.second, edge.first});
    if (faces.size() != 1 || twin == edges.end() || twin->second.size() != 1) return false;
    parent[root(faces[0])] = root(twin->second[0]);
  }
  // Signed volume (divergence theorem over planar faces) and box of each part.
  std::map<uint32_t, std::pair<double, Bounds>> parts;
  for (uint32_t f = 0; f < polys.size(); ++f) {
    std::vector<glm::dvec3> c;
    for (const glm::vec3& v : polys[f].corners) c.emplace_back(v);
    auto [it, added] = parts.try_emplace(root(f), 0.0, Bounds{polys[f].corners[0], polys[f].corners[0]});
    it->second.first += glm::dot(c[0], NewellSum(c)) / 6.0;
    for (const glm::vec3& v : polys[f].corners) {
      it->second.second.lo = glm::min(it->second.second.lo, v);
      it->second.second.hi = glm::max(it->second.second.hi, v);
    }
  }
  const Bounds* room = nullptr;
  for (const auto& [r, part] : parts) {
    if (part.first < 0.0) {
      if (room) return false;
      room = &part.second;
    } else if (!(part.first > 0.0)) {
      return false;
    }
  }
  if (!room) return false;
  for (const auto& [r, part] : parts) {
    const Bounds& b = part.second;
    if (&b == room) continue;
    if (glm::any(glm::lessThan(b.lo, room->lo)) || glm::any(glm::greaterThan(b.hi, room->hi))) return false;
  }
  return true;
}

}  // namespace

Status LoadScene(const std::string& objPath, Scene* scene, const LoadOptions& options) {
  std::string text;
  std::string err = ReadText(objPath, &text);
  if (!err.empty()) return Status::At(objPath, 0, err + " file");
  return LoadSceneFromText(objPath, text, ReadText, scene, nullptr, options);
}

Status LoadSceneFromText(const std::string& objPath, const std::string& objText,
                         const SceneFileReader& readMtl, Scene* scene,
                         std::vector<std::string>* warnings, const LoadOptions& options) {
  Scene result;
  result.objPath = objPath;
  Loader loader(&result, readMtl, options);
  Status s = loader.LoadObj(objPath, objText);
  if (!s.ok()) return s;
  s = loader.ApplyEmit();
  if (!s.ok()) return s;
  bool emits = false;
  for (const Polygon& p : result.polygons) {
    const glm::vec3& ke = result.materials[p.material].ke;
    emits = emits || ke.x > 0.0f || ke.y > 0.0f || ke.z > 0.0f;
  }
  if (!emits)
    return Status::At(objPath, 0,
                      "no emitter: no face has a material with Ke > 0 (--emit NAME=R,G,B or "
                      "NAME=ka makes material NAME one)");
  // Ranges: refused here, at init, rather than solved into Inf or zeros.
  double maxKd = 0.0, maxKe = 0.0;
  int keLine = 0;
  for (const Polygon& p : result.polygons) {
    for (const glm::vec3& v : p.corners)
      for (int a = 0; a < 3; ++a)
        if (std::fabs(v[a]) > kMaxCoordinate) return Status::At(objPath, p.line, CoordinateError(v[a]));
    if (std::sqrt(p.area) < kMinFaceSize)
      return Status::At(objPath, p.line,
                        "face of area " + Num(p.area) + " is below " + Num(kMinFaceSize) +
                            " squared (float ray tests would underflow); scale the scene up");
    const Material& m = result.materials[p.material];
    for (int c = 0; c < 3; ++c) {
      maxKd = std::max(maxKd, static_cast<double>(m.kd[c]));
      if (m.ke[c] > maxKe) {
        maxKe = m.ke[c];
        keLine = p.line;
      }
    }
  }
  result.bounds.lo = result.bounds.hi = result.polygons[0].corners[0];
  for (const Polygon& p : result.polygons) {
    for (const glm::vec3& v : p.corners) {
      result.bounds.lo = glm::min(result.bounds.lo, v);
      result.bounds.hi = glm::max(result.bounds.hi, v);
    }
  }
  glm::vec3 size = result.bounds.hi - result.bounds.lo;
  double extent = std::max(size.x, std::max(size.y, size.z));
  float largest = 0.0f;
  int farLine = 0;
  for (const Polygon& p : result.polygons)
    for (const glm::vec3& v : p.corners)
      for (int a = 0; a < 3; ++a)
        if (std::fabs(v[a]) > largest) {
          largest = std::fabs(v[a]);
          farLine = p.line;
        }
  double step = std::nextafter(largest, std::numeric_limits<float>::infinity()) - largest;
  if (step > kMaxStepShare * extent)
    return Status::At(objPath, farLine,
                      "the scene is far from the origin for its size: coordinates up to " +
                          Num(largest) + " step by " + Num(step) + " in float, more than " +
                          Num(kMaxStepShare) + " of its extent " + Num(extent) +
                          "; move it towards the origin");
  // With a perfect reflector (max Kd 1) the bound is infinite, and the
  // check is skipped: a face with Kd 1 passes on all it receives, and what
  // the scene loses instead (absorbed by other faces or back faces, or
  // escaped) no local figure bounds; a scene that cannot lose power in a
  // channel is refused below.
  double bound = maxKd < 1.0 ? maxKe / (1.0 - maxKd) : 0.0;
  if (bound > kMaxRadiosity)
    return Status::At(objPath, keLine,
                      "radiosity may reach " + Num(bound) + " (max Ke / (1 - max Kd)), beyond " +
                          Num(kMaxRadiosity) + " that the float image can hold; scale Ke down");
  if (maxKe < kMinRadiosity)
    return Status::At(objPath, keLine,
                      "brightest Ke " + Num(maxKe) + " is below " + Num(kMinRadiosity) +
                          " (the float image would underflow); scale Ke up");
  static const char* const kChannel[3] = {"red", "green", "blue"};
  for (int c = 0; c < 3; ++c) {
    bool perfect = true;
    for (const Polygon& p : result.polygons) perfect = perfect && result.materials[p.material].kd[c] >= 1.0f;
    if (perfect && ClosedFacingIn(result.polygons))
      return Status::At(objPath, 0,
                        std::string("the scene cannot lose power in the ") + kChannel[c] +
                            " channel: every face has Kd 1 there and the faces close space with "
                            "their fronts facing in, so nothing is absorbed and nothing escapes "
                            "(the solve would never end); give some face a Kd below 1 or open the "
                            "scene");
  }
  std::vector<std::string> lines = loader.Warnings();
  if (warnings) warnings->insert(warnings->end(), lines.begin(), lines.end());
  else
    for (const std::string& w : lines) std::fprintf(stderr, "%s\n", w.c_str());
  *scene = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
