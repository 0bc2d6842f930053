// Scene loading: the scene-wide checks as reductions over the polygon
// stream, the closed-scene check, and the whole-file loader (scene.h). The
// parser is in scene_text.cpp, scene_lines.cpp, obj_loader.cpp and mtl_loader.cpp; the
// streaming passes in scene_stream.cpp.
#include "vismask/scene/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "geometry_util.h"
#include "scene_parse.h"
#include "vismask/core/os.h"

namespace vismask {
namespace objload {

void SceneTally::Add(const std::string& objPath, size_t numMaterials, const Polygon& p) {
  if (used.size() < numMaterials) {
    used.resize(numMaterials, 0);
    firstLine.resize(numMaterials, 0);
    noUvLine.resize(numMaterials, 0);
  }
  if (!used[p.material]) {
    used[p.material] = 1;
    firstLine[p.material] = p.line;
  }
  if (p.uv.empty() && noUvLine[p.material] == 0) noUvLine[p.material] = p.line;
  if (polygons++ == 0) bounds.lo = bounds.hi = p.corners[0];
  for (const glm::vec3& v : p.corners) {
    bounds.lo = glm::min(bounds.lo, v);
    bounds.hi = glm::max(bounds.hi, v);
    for (int a = 0; a < 3; ++a)
      if (std::fabs(v[a]) > largest) {
        largest = std::fabs(v[a]);
        farLine = p.line;
      }
  }
  // Ranges: refused at init rather than solved into Inf or zeros.
  if (!firstBad.ok()) return;
  for (const glm::vec3& v : p.corners)
    for (int a = 0; a < 3; ++a)
      if (std::fabs(v[a]) > kMaxCoordinate) {
        firstBad = Status::At(objPath, p.line, CoordinateError(v[a]));
        return;
      }
  if (std::sqrt(p.area) < kMinFaceSize)
    firstBad = Status::At(objPath, p.line,
                          "face of area " + Num(p.area) + " is below " + Num(kMinFaceSize) +
                              " squared (float ray tests would underflow); scale the scene up");
}

Status SceneTally::Check(const std::string& objPath, const std::vector<Material>& materials,
                         bool perfect[3], bool lit) const {
  auto isUsed = [&](size_t m) { return m < used.size() && used[m]; };
  bool emits = false;
  for (size_t m = 0; m < materials.size(); ++m) {
    const glm::vec3& ke = materials[m].ke;
    emits = emits || (isUsed(m) && (ke.x > 0.0f || ke.y > 0.0f || ke.z > 0.0f));
  }
  if (!emits && !lit)
    return Status::At(objPath, 0,
                      "no emitter: no face has a material with Ke > 0 (--emit NAME=R,G,B or "
                      "NAME=ka makes material NAME one; --sky or --sun light a scene from "
                      "outside)");
  if (!firstBad.ok()) return firstBad;
  // The brightest Ke and the first face (in file order) that has it.
  double maxKd = 0.0, maxKe = 0.0;
  int keLine = 0;
  for (size_t m = 0; m < materials.size(); ++m) {
    if (!isUsed(m)) continue;
    for (int c = 0; c < 3; ++c) {
      maxKd = std::max(maxKd, static_cast<double>(materials[m].kd[c]));
      if (materials[m].ke[c] > maxKe) maxKe = materials[m].ke[c];
    }
  }
  for (size_t m = 0; m < materials.size(); ++m) {
    if (!isUsed(m)) continue;
    const glm::vec3& ke = materials[m].ke;
    if (std::max(ke.x, std::max(ke.y, ke.z)) == maxKe && maxKe > 0.0 &&
        (keLine == 0 || firstLine[m] < keLine))
      keLine = firstLine[m];
  }
  glm::vec3 size = bounds.hi - bounds.lo;
  double extent = std::max(size.x, std::max(size.y, size.z));
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
  // channel is refused by the closed-scene check.
  double bound = maxKd < 1.0 ? maxKe / (1.0 - maxKd) : 0.0;
  if (bound > kMaxRadiosity)
    return Status::At(objPath, keLine,
                      "radiosity may reach " + Num(bound) + " (max Ke / (1 - max Kd)), beyond " +
                          Num(kMaxRadiosity) + " that the float image can hold; scale Ke down");
  if (maxKe < kMinRadiosity && !lit)  // --sky and --sun bound their own values (outside.h)
    return Status::At(objPath, keLine,
                      "brightest Ke " + Num(maxKe) + " is below " + Num(kMinRadiosity) +
                          " (the float image would underflow); scale Ke up");
  for (int c = 0; c < 3; ++c) {
    perfect[c] = true;
    for (size_t m = 0; m < materials.size(); ++m)
      if (isUsed(m)) perfect[c] = perfect[c] && materials[m].kd[c] >= 1.0f;
  }
  return Status::Ok();
}

Status CannotLosePower(const std::string& objPath, int c) {
  static const char* const kChannel[3] = {"red", "green", "blue"};
  return Status::At(objPath, 0,
                    std::string("the scene cannot lose power in the ") + kChannel[c] +
                        " channel: every face has Kd 1 there and the faces close space with "
                        "their fronts facing in, so nothing is absorbed and nothing escapes "
                        "(the solve would never end); give some face a Kd below 1 or open the "
                        "scene");
}

Status ParseObj(const std::string& objPath, LineSource& lines, const ObjCounts* counts,
                const SceneFileReader& readMtl, const LoadOptions& options,
                const PolygonVisitor& visit, std::vector<Material>* materials, SceneTally* tally,
                std::vector<std::string>* warnings, bool perfect[3]) {
  materials->clear();
  *tally = SceneTally();
  Loader loader(materials, readMtl, options);
  if (counts) loader.Reserve(*counts);
  Status s = loader.LoadObj(objPath, lines, [&](const Polygon& p) {
    tally->Add(objPath, materials->size(), p);
    visit(p);
  });
  // A read error ended the lines early: it comes first (what the loader
  // made of the lines before it is beside the point).
  if (!lines.error().empty()) return Status::At(objPath, lines.errorLine(), lines.error());
  if (!s.ok()) return s;
  s = loader.ApplyEmit();
  if (!s.ok()) return s;
  s = tally->Check(objPath, *materials, perfect, options.outsideLight);
  if (!s.ok()) {
    // "no emitter" because the emitting faces were dropped: said at the face.
    std::vector<uint8_t> used = tally->used;
    used.resize(materials->size(), 0);
    Status dropped = loader.DroppedEmitters(used);
    if (!dropped.ok()) return dropped;
  }
  // No emitter, and materials the loader made up (no MTL defines them):
  // name them, as one may be the light.
  if (!s.ok() && s.line() == 0 && s.message().rfind("no emitter", 0) == 0 &&
      !loader.UndefinedMaterials().empty())
    return Status::At(objPath, 0,
                      s.message() + "; materials no MTL defines: " + loader.UndefinedMaterials());
  if (!s.ok()) return s;
  std::vector<uint8_t> used = tally->used;
  used.resize(materials->size(), 0);
  *warnings = loader.Warnings(used);
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
    auto [it, added] =
        parts.try_emplace(root(f), 0.0, Bounds{polys[f].corners[0], polys[f].corners[0]});
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
    if (glm::any(glm::lessThan(b.lo, room->lo)) || glm::any(glm::greaterThan(b.hi, room->hi)))
      return false;
  }
  return true;
}

}  // namespace objload

Status LoadScene(const std::string& objPath, Scene* scene, const LoadOptions& options) {
  if (IsGltfPath(objPath)) {
    std::vector<std::string> warnings;
    Status s = LoadGltf(objPath, options, scene, &warnings);
    if (s.ok())
      for (const std::string& w : warnings) os::PrintErr("%s\n", w.c_str());
    return s;
  }
  std::string text;
  std::string err = objload::ReadText(objPath, &text);
  if (!err.empty()) return Status::At(objPath, 0, err);
  return LoadSceneFromText(objPath, text, objload::ReadText, scene, nullptr, options);
}

Status LoadSceneFromText(const std::string& objPath, const std::string& objText,
                         const SceneFileReader& readMtl, Scene* scene,
                         std::vector<std::string>* warnings, const LoadOptions& options) {
  using namespace objload;
  Scene result;
  result.objPath = objPath;
  TextLines lines(objText);
  SceneTally tally;
  std::vector<std::string> lines_;
  bool perfect[3] = {false, false, false};
  Status s = ParseObj(
      objPath, lines, nullptr, readMtl, options,
      [&](const Polygon& p) { result.polygons.push_back(p); }, &result.materials, &tally, &lines_,
      perfect);
  if (!s.ok()) return s;
  result.bounds = tally.bounds;
  for (int c = 0; c < 3; ++c)
    if (perfect[c] && ClosedFacingIn(result.polygons)) return CannotLosePower(objPath, c);
  if (warnings)
    warnings->insert(warnings->end(), lines_.begin(), lines_.end());
  else
    for (const std::string& w : lines_) os::PrintErr("%s\n", w.c_str());
  *scene = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
