#include "vismask/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

#include "geometry_util.h"

namespace vismask {
namespace {

// Face checks, relative to the face's size (its largest corner-to-corner
// distance). Planarity: corners may be off the Newell plane by 1e-4 of the
// size (0.06 mm on a 0.6 m wall), far above float rounding (~1e-7), below a
// modelling error (the published Cornell left wall is 1e-3 off, so
// scenes/cornell.obj splits it). The others reject only true degeneracy.
constexpr double kPlanarTol = 1e-4;     // max corner distance from the plane
constexpr double kRepeatTol = 1e-6;     // min distance between two corners
constexpr double kAreaTol = 1e-6;       // min area, times size^2
constexpr double kCollinearTol = 1e-5;  // min |sin| of the angle at a corner

// What float geometry and float images can carry (docs/STABILITY.md). Ray
// tests multiply coordinates and square lengths in float (max 3.4e38, least
// normal 1.2e-38), so coordinates stay within 1e15 and faces above 1e-15 in
// size; radiosity is bounded by max Ke / (1 - max Kd), and the image holds it
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

// Splits text into lines as std::getline does: at '\n', the last line kept
// even without one, no empty line after a final '\n'.
void SplitLines(const std::string& text, std::vector<std::string>* lines) {
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    lines->push_back(text.substr(start, end - start));
    start = end + 1;
  }
}

// Reads a whole file; returns an error message, empty on success.
std::string ReadText(const std::string& path, std::string* text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot open";
  // istream::read, not istreambuf_iterator: a read error (a directory)
  // sets badbit instead of throwing.
  std::string all;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) all.append(buf, static_cast<size_t>(in.gcount()));
  if (in.bad()) return "cannot read";
  *text = std::move(all);
  return "";
}

// The directory part of a path, with its trailing '/' ("" for a bare name).
std::string DirOf(const std::string& path) {
  size_t slash = path.rfind('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

// Parses tokens[first..first+count) as finite floats into out[].
std::string ParseFloats(const Tokens& tokens, size_t first, size_t count, float* out) {
  for (size_t i = 0; i < count; ++i) {
    const std::string& s = tokens[first + i];
    char* end = nullptr;
    double d = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end != '\0') return "bad number '" + s + "'";
    if (!std::isfinite(d)) return "number '" + s + "' is not finite";
    if (std::fabs(d) > std::numeric_limits<float>::max()) return "number '" + s + "' is too large";
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
    return std::string(what) + " index 0 in '" + corner + "' (OBJ indices start at 1)";
  long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
  if (resolved < 0 || resolved >= static_cast<long long>(count))
    return std::string(what) + " index " + s + " out of range (" + Str(count) + " " + plural +
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
  const std::string bad = "bad face vertex '" + s + "'";
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

double Orient(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Whether p, known to be on the line ab, lies within the segment ab.
bool OnSegment(glm::dvec2 a, glm::dvec2 b, glm::dvec2 p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

// Whether the closed segments ab and cd cross or touch.
bool SegmentsMeet(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c, glm::dvec2 d) {
  double o1 = Orient(a, b, c), o2 = Orient(a, b, d), o3 = Orient(c, d, a), o4 = Orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  return (o1 == 0 && OnSegment(a, b, c)) || (o2 == 0 && OnSegment(a, b, d)) ||
         (o3 == 0 && OnSegment(c, d, a)) || (o4 == 0 && OnSegment(c, d, b));
}

// Checks a face's shape and sets its normal and area; returns an error message
// for a degenerate, non-planar or self-intersecting face.
std::string FinishPolygon(Polygon* p) {
  const size_t n = p->corners.size();
  std::vector<glm::dvec3> c;
  for (const glm::vec3& v : p->corners) c.emplace_back(v);
  double size = 0.0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) size = std::max(size, glm::length(c[i] - c[j]));
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (glm::length(c[i] - c[j]) <= kRepeatTol * size)
        return "degenerate face: vertices " + Str(i + 1) + " and " + Str(j + 1) + " coincide";
  for (size_t i = 0; i < n; ++i) {
    glm::dvec3 a = c[(i + n - 1) % n] - c[i], b = c[(i + 1) % n] - c[i];
    if (glm::length(glm::cross(a, b)) <= kCollinearTol * glm::length(a) * glm::length(b))
      return "degenerate face: vertex " + Str(i + 1) + " is collinear with its neighbours";
  }
  // Newell's method, about corner 0 for precision.
  glm::dvec3 sum = NewellSum(c);
  double twiceArea = glm::length(sum);
  if (twiceArea / 2 <= kAreaTol * size * size) return "degenerate face: zero area";
  glm::dvec3 normal = sum / twiceArea;
  glm::dvec3 centroid(0.0);
  for (const glm::dvec3& v : c) centroid += v / static_cast<double>(n);
  for (size_t i = 0; i < n; ++i) {
    double off = std::fabs(glm::dot(normal, c[i] - centroid));
    if (off > kPlanarTol * size)
      return "non-planar face: vertex " + Str(i + 1) + " is " + Num(off) +
             " off the face's plane (tolerance " + Num(kPlanarTol * size) + ")";
  }
  // Simple polygon: no two non-adjacent edges meet (in the plane's projection).
  glm::dvec3 an = glm::abs(normal);
  int axis = an.x > an.y ? (an.x > an.z ? 0 : 2) : (an.y > an.z ? 1 : 2);
  auto at = [&](size_t i) {
    return glm::dvec2(c[i % n][(axis + 1) % 3], c[i % n][(axis + 2) % 3]);
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j)
      if (!(i == 0 && j == n - 1) && SegmentsMeet(at(i), at(i + 1), at(j), at(j + 1)))
        return "self-intersecting face: edges " + Str(i + 1) + " and " + Str(j + 1) + " meet";
  p->normal = glm::vec3(normal);
  p->area = twiceArea / 2;
  return "";
}

class Loader {
 public:
  Loader(Scene* scene, const SceneFileReader& readMtl, std::vector<std::string>* warnings)
      : scene_(scene), readMtl_(readMtl), warnings_(warnings) {}
  Status LoadObj(const std::string& path, const std::string& text);

 private:
  Status LoadMtl(const std::string& path, const std::string& objPath, int objLine);
  // One warning line per distinct `what`, at its first file:line.
  void Warn(const std::string& path, int line, const std::string& what) {
    if (!warnedKeys_.insert(what).second) return;
    std::string w = path + ":" + std::to_string(line) + ": warning: " + what;
    if (warnings_) warnings_->push_back(w);
    else std::fprintf(stderr, "%s\n", w.c_str());
  }

  Scene* scene_;
  const SceneFileReader& readMtl_;
  std::vector<std::string>* warnings_;  // null: print to stderr
  std::vector<glm::vec3> vertices_;
  std::vector<glm::vec2> uvs_;
  std::vector<glm::vec3> normals_;
  std::map<std::string, std::pair<uint32_t, std::string>> materials_;  // index, "file:line"
  std::set<std::string> loadedMtls_;
  std::set<std::string> warnedKeys_;
};

Status Loader::LoadObj(const std::string& path, const std::string& text) {
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
      err = FinishPolygon(&p);
      if (!err.empty()) return Status::At(path, line, err);
      scene_->polygons.push_back(std::move(p));
    } else if (key == "usemtl") {
      if (args != 1) return Status::At(path, line, "'usemtl' needs 1 name, got " + Str(args));
      auto it = materials_.find(t[1]);
      if (it == materials_.end())
        return Status::At(path, line, "undefined material '" + t[1] + "'");
      material = it->second.first;
      haveMaterial = true;
    } else if (key == "mtllib") {
      if (args == 0) return Status::At(path, line, "'mtllib' needs a file name");
      for (size_t k = 1; k <= args; ++k) {
        Status s = LoadMtl(DirOf(path) + t[k], path, line);
        if (!s.ok()) return s;
      }
    } else if (key == "l" || key == "p") {
      return Status::At(path, line, "'" + key + "': lines and points are not supported");
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
          return Status::At(path, line, "bad smoothing group '" + t[1] + "'");
        unsigned long long g = std::strtoull(t[1].c_str(), nullptr, 10);
        if (g > 0xffffffffull) return Status::At(path, line, "smoothing group '" + t[1] + "' is too large");
        smoothing = static_cast<uint32_t>(g);
      }
    } else if (key != "o" && key != "g") {
      return Status::At(path, line, "unknown statement '" + key + "'");
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
                          "duplicate material '" + t[1] + "' (first at " + it->second.second + ")");
      Material m;
      m.name = t[1];
      m.where = where;
      materials.push_back(std::move(m));
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
      materials.back().mapKd = DirOf(path) + t.back();
      materials.back().mapKdWhere = path + ":" + std::to_string(line);
    } else if (key == "Kd" || key == "Ke") {
      if (!haveMaterial) return Status::At(path, line, "'" + key + "' before any 'newmtl'");
      if (args != 3)
        return Status::At(path, line, "'" + key + "' needs 3 numbers, got " + Str(args));
      float rgb[3];
      err = ParseFloats(t, 1, 3, rgb);
      if (!err.empty()) return Status::At(path, line, err);
      for (float x : rgb) {
        if (key == "Kd" && !(x >= 0.0f && x < 1.0f))
          return Status::At(path, line, "Kd must be in [0, 1), got " + Num(x));
        if (key == "Ke" && x < 0.0f)
          return Status::At(path, line, "Ke must be >= 0, got " + Num(x));
      }
      (key == "Kd" ? materials.back().kd : materials.back().ke) = glm::vec3(rgb[0], rgb[1], rgb[2]);
    } else {
      Warn(path, line, "ignoring MTL key '" + key + "'");
    }
  }
  return Status::Ok();
}

}  // namespace

Status LoadScene(const std::string& objPath, Scene* scene) {
  std::string text;
  std::string err = ReadText(objPath, &text);
  if (!err.empty()) return Status::At(objPath, 0, err + " file");
  return LoadSceneFromText(objPath, text, ReadText, scene);
}

Status LoadSceneFromText(const std::string& objPath, const std::string& objText,
                         const SceneFileReader& readMtl, Scene* scene,
                         std::vector<std::string>* warnings) {
  Scene result;
  result.objPath = objPath;
  Loader loader(&result, readMtl, warnings);
  Status s = loader.LoadObj(objPath, objText);
  if (!s.ok()) return s;
  bool emits = false;
  for (const Polygon& p : result.polygons) {
    const glm::vec3& ke = result.materials[p.material].ke;
    emits = emits || ke.x > 0.0f || ke.y > 0.0f || ke.z > 0.0f;
  }
  if (!emits) return Status::At(objPath, 0, "no emitter: no face has a material with Ke > 0");
  // Ranges: refused here, at init, rather than solved into Inf or zeros.
  double maxKd = 0.0, maxKe = 0.0;
  int keLine = 0;
  for (const Polygon& p : result.polygons) {
    for (const glm::vec3& v : p.corners)
      for (int a = 0; a < 3; ++a)
        if (std::fabs(v[a]) > kMaxCoordinate)
          return Status::At(objPath, p.line,
                            "coordinate " + Num(v[a]) + " is beyond +-" + Num(kMaxCoordinate) +
                                " (float ray tests would overflow); scale the scene down");
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
  double bound = maxKe / (1.0 - maxKd);
  if (bound > kMaxRadiosity)
    return Status::At(objPath, keLine,
                      "radiosity may reach " + Num(bound) + " (max Ke / (1 - max Kd)), beyond " +
                          Num(kMaxRadiosity) + " that the float image can hold; scale Ke down");
  if (maxKe < kMinRadiosity)
    return Status::At(objPath, keLine,
                      "brightest Ke " + Num(maxKe) + " is below " + Num(kMinRadiosity) +
                          " (the float image would underflow); scale Ke up");
  *scene = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
