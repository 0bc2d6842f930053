// The streaming passes over an OBJ (scene_stream.h), on the parser that
// LoadScene uses (scene_parse.h).
#include "vismask/scene/scene_stream.h"

#include <string>
#include <vector>

#include "scene_parse.h"

namespace vismask {

using namespace objload;

Status CountObj(const std::string& objPath, SceneInfo* info) {
  if (IsGltfPath(objPath)) {  // parsed whole by ScanObj: only checked here
    std::string err = CheckReadable(objPath);
    if (!err.empty()) return Status::At(objPath, 0, err + " file");
    info->objPath = objPath;
    return Status::Ok();
  }
  FileLines lines;
  std::string err = lines.Open(objPath);
  if (!err.empty()) return Status::At(objPath, 0, err);
  ObjCounts c = CountStatements(lines);
  if (!lines.error().empty()) return Status::At(objPath, lines.errorLine(), lines.error());
  info->objPath = objPath;
  info->lines = c.lines;
  info->vertices = c.vertices;
  info->uvs = c.uvs;
  info->normals = c.normals;
  info->faces = c.faces;
  info->faceCorners = c.faceCorners;
  return Status::Ok();
}

namespace {

// One pass of the parser over the file, reserved to pass 0's counts.
Status Pass(const std::string& objPath, const LoadOptions& options, const SceneInfo& counted,
            const PolygonVisit& visit, std::vector<Material>* materials, SceneTally* tally,
            std::vector<std::string>* warnings, bool perfect[3]) {
  FileLines lines;
  std::string err = lines.Open(objPath);
  if (!err.empty()) return Status::At(objPath, 0, err);
  ObjCounts counts;
  counts.vertices = counted.vertices;
  counts.uvs = counted.uvs;
  counts.normals = counted.normals;
  uint32_t index = 0;
  return ParseObj(
      objPath, lines, &counts, ReadText, options, [&](const Polygon& p) { visit(index++, p); },
      materials, tally, warnings, perfect);
}

}  // namespace

Status ScanObj(const std::string& objPath, const LoadOptions& options, const PolygonVisit& visit,
               SceneInfo* info) {
  if (IsGltfPath(objPath)) {
    auto scene = std::make_shared<Scene>();
    Status s = LoadGltf(objPath, options, scene.get(), &info->warnings);
    if (!s.ok()) return s;
    info->objPath = objPath;
    info->materials = scene->materials;
    info->bounds = scene->bounds;
    info->numPolygons = scene->polygons.size();
    info->camera = scene->camera;
    info->usedMaterials.assign(scene->materials.size(), 0);
    info->noUvLine.assign(scene->materials.size(), 0);
    info->heldBytes = 0;
    for (const Polygon& p : scene->polygons) {
      info->usedMaterials[p.material] = 1;
      info->heldBytes += sizeof(Polygon) + 16 * 3 + p.corners.capacity() * sizeof(glm::vec3) +
                         p.uv.capacity() * sizeof(glm::vec2) + p.vn.capacity() * sizeof(glm::vec3);
    }
    info->faces = info->numPolygons;
    info->held = scene;
    for (uint32_t i = 0; i < scene->polygons.size(); ++i) visit(i, scene->polygons[i]);
    return Status::Ok();
  }
  SceneTally tally;
  bool perfect[3] = {false, false, false};
  Status s =
      Pass(objPath, options, *info, visit, &info->materials, &tally, &info->warnings, perfect);
  if (!s.ok()) return s;
  info->objPath = objPath;
  info->bounds = tally.bounds;
  info->numPolygons = tally.polygons;
  info->usedMaterials = tally.used;
  info->usedMaterials.resize(info->materials.size(), 0);
  info->noUvLine = tally.noUvLine;
  info->noUvLine.resize(info->materials.size(), 0);
  if (perfect[0] || perfect[1] || perfect[2]) {
    // Every face reflects all it receives in some channel: whether the
    // faces close space needs them all at once (a documented exception to
    // the bounded passes; such a scene is refused or solved with Kd 1).
    std::vector<Polygon> all;
    s = StreamObj(*info, options, [&](uint32_t, const Polygon& p) { all.push_back(p); });
    if (!s.ok()) return s;
    for (int c = 0; c < 3; ++c)
      if (perfect[c] && ClosedFacingIn(all)) return CannotLosePower(objPath, c);
  }
  return Status::Ok();
}

Status StreamObj(const SceneInfo& info, const LoadOptions& options, const PolygonVisit& visit) {
  if (info.held) {
    for (uint32_t i = 0; i < info.held->polygons.size(); ++i) visit(i, info.held->polygons[i]);
    return Status::Ok();
  }
  std::vector<Material> materials;
  SceneTally tally;
  std::vector<std::string> warnings;
  bool perfect[3];
  return Pass(info.objPath, options, info, visit, &materials, &tally, &warnings, perfect);
}

}  // namespace vismask
