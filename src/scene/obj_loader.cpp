// The OBJ statements (scene_parse.h): vertices, faces (mended by ShapeFace
// and handed on one at a time), materials, groups and smoothing groups.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "scene_parse.h"
#include "vismask/scene/face.h"

namespace vismask::objload {

void Loader::Reserve(const ObjCounts& counts) {
  vertices_.reserve(counts.vertices);
  uvs_.reserve(counts.uvs);
  normals_.reserve(counts.normals);
}

uint32_t Loader::DefaultMaterial(const std::string& name, const std::string& path, int line) {
  std::vector<Material>& materials = *materials_;
  const std::string where = path + ":" + std::to_string(line);
  auto [it, added] =
      materialIndex_.emplace(name, std::make_pair(static_cast<uint32_t>(materials.size()), where));
  if (!added) return it->second.first;
  Material m;
  m.name = name;
  m.kd = glm::vec3(kDefaultKd);
  m.where = where;
  materials.push_back(std::move(m));
  finishes_.emplace_back();
  return it->second.first;
}

Status Loader::Face(const Tokens& t, int line, uint32_t material, uint32_t smoothing,
                    std::vector<Polygon>* pieces, const PolygonVisitor& visit) {
  const std::string& path = path_;
  const size_t args = t.size() - 1;
  std::string err;
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
    if (withUv != 0)
      Warn(path, line, "texture coordinates on some corners of a face only: ignored");
    p.uv.clear();
  }
  if (withNormal != args) {
    if (withNormal != 0) Warn(path, line, "normals on some corners of a face only: ignored");
    p.vn.clear();
  }
  pieces->clear();
  FaceResult r = ShapeFace(p, options_.strict, pieces);
  if (r.fate == FaceResult::kRefused) return Status::At(path, line, r.error);
  for (const Polygon& piece : *pieces) visit(piece);
  if (r.removedCorners > 0 &&
      (r.fate == FaceResult::kKept || r.fate == FaceResult::kTriangulated)) {
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
  if (r.fate == FaceResult::kDegenerate || r.fate == FaceResult::kSelfIntersecting)
    droppedFace_.emplace(material, std::make_pair(line, r.fate == FaceResult::kDegenerate
                                                            ? "has no area"
                                                            : "has edges that cross (a bow tie)"));
  return Status::Ok();
}

Status Loader::LoadObj(const std::string& path, LineSource& lines, const PolygonVisitor& visit) {
  path_ = path;
  std::string err;
  bool haveMaterial = false;
  uint32_t material = 0;
  uint32_t smoothing = 0;
  std::vector<Polygon> pieces;  // what one face became
  Statement statement;
  while (lines.NextStatement(&statement)) {
    const auto& [text, line, t, key, args] = statement;
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
      if (!haveMaterial) {
        if (options_.strict) return Status::At(path, line, "face before any 'usemtl'");
        // Faces with no material (an OBJ without usemtl, or faces above
        // the first): the default grey, said once.
        material = DefaultMaterial(kDefaultMaterial, path, line);
        haveMaterial = true;
        Warn(path, line,
             "faces before any 'usemtl': they get the default grey material '" +
                 std::string(kDefaultMaterial) + "' (Kd 0.5)");
      }
      Status st = Face(t, line, material, smoothing, &pieces, visit);
      if (!st.ok()) return st;
    } else if (key == "usemtl") {
      if (args != 1) return Status::At(path, line, "'usemtl' needs 1 name, got " + Str(args));
      auto it = materialIndex_.find(t[1]);
      if (it == materialIndex_.end()) {
        if (options_.strict) return Status::At(path, line, "undefined material " + Quote(t[1]));
        // A name no MTL defines (its MTL missing, or left out of it): the
        // default grey under that name, so that --emit may name it; the
        // names go in one warning after loading.
        if (undefinedMaterials_.empty()) undefinedWhere_ = path + ":" + std::to_string(line);
        undefinedMaterials_.push_back(t[1]);
        material = DefaultMaterial(t[1], path, line);
      } else {
        material = it->second.first;
      }
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
        if (g > 0xffffffffull)
          return Status::At(path, line, "smoothing group " + Quote(t[1]) + " is too large");
        smoothing = static_cast<uint32_t>(g);
      }
    } else if (key != "o" && key != "g") {
      return Status::At(path, line, "unknown statement " + Quote(key));
    }
  }
  return Status::Ok();
}

}  // namespace vismask::objload
