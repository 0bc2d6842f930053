// glTF 2.0 input (scene.h, LoadGltf): a .gltf or .glb parsed by tinygltf
// (Debian's libtinygltf-dev, header only, compiled here with nlohmann json;
// its image decoding and writing are left out: stb_image is compiled once,
// in texture_decode.cpp, which decodes the textures), then its triangles, node
// transforms, materials and first camera made into the Scene the OBJ loader
// makes. Files are read through vismask's reader (regular files, 4 GiB at
// most); every accessor is bounds-checked before it is read. The accessors,
// transforms and materials are src/scene/gltf_model.cpp's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <string>
#include <utility>
#include <vector>

#include "vismask/core/os.h"
#include "vismask/scene/face.h"
#include "vismask/scene/scene.h"

#define TINYGLTF_IMPLEMENTATION
#include "gltf_internal.h"

namespace vismask {

bool IsGltfPath(const std::string& path) {
  auto endsWith = [&](const char* ext) {
    const size_t n = std::strlen(ext);
    if (path.size() < n) return false;
    for (size_t i = 0; i < n; ++i) {
      char c = path[path.size() - n + i];
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
      if (c != ext[i]) return false;
    }
    return true;
  };
  return endsWith(".gltf") || endsWith(".glb");
}

namespace {

using namespace objload;

constexpr uint32_t kNoMaterial = 0xffffffffu;

// tinygltf's file access, through vismask's reader.
bool FsExists(const std::string& path, void*) {
  return os::Exists(path.c_str());
}
std::string FsExpand(const std::string& path, void*) {
  return path;
}
bool FsRead(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
  std::string text;
  const std::string why = objload::ReadBytes(path, &text);
  if (!why.empty()) {
    if (err) *err += "'" + path + "': " + why;
    return false;
  }
  out->assign(text.begin(), text.end());
  return true;
}
bool FsWrite(std::string*, const std::string&, const std::vector<unsigned char>&, void*) {
  return false;
}

// Images stay encoded: a data: URI's bytes are kept (texture_decode.cpp decodes
// them); a buffer view's are taken later, bounds-checked, from the buffer.
bool KeepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void*) {
  if (image->bufferView == -1 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

using gltf::Access;
using gltf::Elements;
using gltf::LocalTransform;
using gltf::Unused;

// The file parsed by tinygltf into *m (its buffers read, its images kept
// encoded).
Status ReadModel(const std::string& path, tinygltf::Model* m) {
  std::string bytes;
  std::string err = objload::ReadBytes(path, &bytes);
  if (!err.empty()) return Status::At(path, 0, err);
  tinygltf::TinyGLTF reader;
  reader.SetFsCallbacks({FsExists, FsExpand, FsRead, FsWrite, nullptr});
  reader.SetImageLoader(KeepImageBytes, nullptr);
  std::string gerr, gwarn;
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  if (bytes.size() > 0xffffffffu) return Status::At(path, 0, "a glTF file of 4 GiB or more");
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  const bool ok =
      binary ? reader.LoadBinaryFromMemory(m, &gerr, &gwarn,
                                           reinterpret_cast<const unsigned char*>(bytes.data()),
                                           static_cast<unsigned>(bytes.size()), dir)
             : reader.LoadASCIIFromString(m, &gerr, &gwarn, bytes.data(),
                                          static_cast<unsigned>(bytes.size()), dir);
  if (!ok) {
    std::string why = gerr.empty() ? "not a glTF 2.0 file" : gerr;
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    for (char& c : why)
      if (c == '\n') c = ';';
    return Status::At(path, 0, "cannot read glTF: " + why);
  }
  return Status::Ok();
}

// The default scene's root nodes (every node no other names as a child,
// when the file has no scene).
std::vector<int> Roots(const tinygltf::Model& m) {
  std::vector<int> roots;
  if (!m.scenes.empty()) {
    const size_t sc = m.defaultScene >= 0 && static_cast<size_t>(m.defaultScene) < m.scenes.size()
                          ? static_cast<size_t>(m.defaultScene)
                          : 0;
    roots = m.scenes[sc].nodes;
  } else {
    std::vector<uint8_t> child(m.nodes.size(), 0);
    for (const tinygltf::Node& n : m.nodes)
      for (int c : n.children)
        if (c >= 0 && static_cast<size_t>(c) < m.nodes.size()) child[static_cast<size_t>(c)] = 1;
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (!child[i]) roots.push_back(static_cast<int>(i));
  }
  return roots;
}

// A primitive's accessors, checked: positions, and uv, normals and indices
// where it has them.
struct PrimitiveData {
  Elements pos, uv, nrm, idx;
  bool hasUv = false, hasNormal = false;
  size_t numIndices = 0;
};

std::string AccessPrimitive(const tinygltf::Model& m, const tinygltf::Primitive& prim,
                            PrimitiveData* d) {
  auto attr = [&](const char* name) {
    auto it = prim.attributes.find(name);
    return it == prim.attributes.end() ? -1 : it->second;
  };
  if (attr("POSITION") < 0) return "no POSITION";
  std::string err =
      Access(m, attr("POSITION"), "POSITION", {TINYGLTF_COMPONENT_TYPE_FLOAT}, 3, &d->pos);
  if (!err.empty()) return err;
  d->hasUv = attr("TEXCOORD_0") >= 0;
  d->hasNormal = attr("NORMAL") >= 0;
  if (d->hasUv) {
    err = Access(m, attr("TEXCOORD_0"), "TEXCOORD_0",
                 {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                 2, &d->uv);
    if (!err.empty()) return err;
    if (d->uv.count != d->pos.count) return "TEXCOORD_0 count differs";
  }
  if (d->hasNormal) {
    err = Access(m, attr("NORMAL"), "NORMAL", {TINYGLTF_COMPONENT_TYPE_FLOAT}, 3, &d->nrm);
    if (!err.empty()) return err;
    if (d->nrm.count != d->pos.count) return "NORMAL count differs";
  }
  d->numIndices = d->pos.count;
  if (prim.indices >= 0) {
    err = Access(m, prim.indices, "indices",
                 {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                 1, &d->idx);
    if (!err.empty()) return err;
    d->numIndices = d->idx.count;
  }
  return "";
}

// The corner indices (into the primitive's vertex order) of triangle t of
// a list, strip or fan.
void TriangleCorners(int mode, size_t t, size_t k[3]) {
  if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    k[0] = t;
    k[1] = t % 2 ? t + 2 : t + 1;
    k[2] = t % 2 ? t + 1 : t + 2;
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    k[0] = t + 1;
    k[1] = t + 2;
    k[2] = 0;
  } else {
    k[0] = 3 * t;
    k[1] = 3 * t + 1;
    k[2] = 3 * t + 2;
  }
}

// The default scene's nodes walked depth first, each with its world
// transform: the first perspective camera taken, every triangle primitive
// made into polygons through ShapeFace as an OBJ face is.
class NodeWalk {
 public:
  NodeWalk(const std::string& path, const LoadOptions& options, const tinygltf::Model& m,
           Scene* result, Unused* unused)
      : path_(path), options_(options), m_(m), result_(result), unused_(unused) {}

  Status Walk() {
    std::vector<std::pair<int, glm::dmat4>> stack;
    const std::vector<int> roots = Roots(m_);
    for (auto it = roots.rbegin(); it != roots.rend(); ++it)
      stack.emplace_back(*it, glm::dmat4(1.0));
    size_t visited = 0;
    while (!stack.empty()) {
      auto [index, parent] = stack.back();
      stack.pop_back();
      if (index < 0 || static_cast<size_t>(index) >= m_.nodes.size())
        return Status::At(path_, 0, "node " + std::to_string(index) + " does not exist");
      if (++visited > 4 * m_.nodes.size() + 4)
        return Status::At(path_, 0, "the node hierarchy has a cycle");
      const tinygltf::Node& node = m_.nodes[static_cast<size_t>(index)];
      const glm::dmat4 world = parent * LocalTransform(node);
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
        stack.emplace_back(*c, world);
      Status s = Visit(index, node, world);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

  uint32_t defaultMaterial() const { return defaultMaterial_; }
  size_t defaultFaces() const { return defaultFaces_; }
  const FaceTally& degenerate() const { return degenerate_; }

 private:
  Status Visit(int index, const tinygltf::Node& node, const glm::dmat4& world) {
    const std::string nodeName =
        "node " + (node.name.empty() ? std::to_string(index) : Quote(node.name));
    if (node.camera >= 0 && !result_->camera.has) {
      if (static_cast<size_t>(node.camera) >= m_.cameras.size())
        return Status::At(path_, 0,
                          nodeName + ": camera " + std::to_string(node.camera) + " does not exist");
      TakeCamera(m_.cameras[static_cast<size_t>(node.camera)], world);
    }
    if (node.mesh < 0) return Status::Ok();
    if (static_cast<size_t>(node.mesh) >= m_.meshes.size())
      return Status::At(path_, 0,
                        nodeName + ": mesh " + std::to_string(node.mesh) + " does not exist");
    if (node.skin >= 0) unused_->Add("skinned meshes (drawn unskinned)", "node", "nodes");
    const tinygltf::Mesh& mesh = m_.meshes[static_cast<size_t>(node.mesh)];
    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = mesh.primitives[pi];
      const std::string where = nodeName + " mesh " +
                                (mesh.name.empty() ? std::to_string(node.mesh) : Quote(mesh.name)) +
                                " primitive " + std::to_string(pi) + ": ";
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          prim.mode != TINYGLTF_MODE_TRIANGLE_FAN && prim.mode != -1) {
        unused_->Add("points and lines", "primitive", "primitives");
        continue;
      }
      if (!prim.targets.empty()) unused_->Add("morph targets", "primitive", "primitives");
      Status s = AddPrimitive(prim, world, where);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

  void TakeCamera(const tinygltf::Camera& cam, const glm::dmat4& world) {
    if (cam.type == "perspective" && cam.perspective.yfov > 0.0 && cam.perspective.yfov < M_PI) {
      // A glTF camera looks down its local -z, up +y.
      const glm::dvec3 eye(world * glm::dvec4(0, 0, 0, 1));
      const glm::dvec3 ahead = glm::normalize(glm::dvec3(world * glm::dvec4(0, 0, -1, 0)));
      const glm::dvec3 up = glm::normalize(glm::dvec3(world * glm::dvec4(0, 1, 0, 0)));
      result_->camera.has = true;
      result_->camera.eye = glm::vec3(eye);
      result_->camera.target = glm::vec3(eye + ahead);
      result_->camera.up = glm::vec3(up);
      result_->camera.fovyDeg = static_cast<float>(cam.perspective.yfov * 180.0 / M_PI);
    } else {
      unused_->Add("camera not perspective", "camera", "cameras");
    }
  }

  // The primitive's material, or the default grey one (made at its first use).
  Status MaterialOf(const tinygltf::Primitive& prim, const std::string& where, uint32_t* material) {
    if (prim.material >= 0) {
      if (static_cast<size_t>(prim.material) >= result_->materials.size())
        return Status::At(path_, 0,
                          where + "material " + std::to_string(prim.material) + " does not exist");
      *material = static_cast<uint32_t>(prim.material);
      return Status::Ok();
    }
    if (defaultMaterial_ == kNoMaterial) {
      Material d;
      d.name = kDefaultMaterial;
      d.kd = glm::vec3(kDefaultKd);
      d.where = path_;
      defaultMaterial_ = static_cast<uint32_t>(result_->materials.size());
      result_->materials.push_back(std::move(d));
    }
    *material = defaultMaterial_;
    return Status::Ok();
  }

  Status AddPrimitive(const tinygltf::Primitive& prim, const glm::dmat4& world,
                      const std::string& where) {
    const glm::dmat3 linear(world);
    const bool flip = glm::determinant(linear) < 0.0;
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
    PrimitiveData d;
    const std::string err = AccessPrimitive(m_, prim, &d);
    if (!err.empty()) return Status::At(path_, 0, where + err);
    uint32_t material = 0;
    Status s = MaterialOf(prim, where, &material);
    if (!s.ok()) return s;
    // The triangles' index triples.
    size_t numTriangles = 0;
    if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP || prim.mode == TINYGLTF_MODE_TRIANGLE_FAN)
      numTriangles = d.numIndices >= 3 ? d.numIndices - 2 : 0;
    else
      numTriangles = d.numIndices / 3;
    for (size_t t = 0; t < numTriangles; ++t) {
      size_t k[3];
      TriangleCorners(prim.mode, t, k);
      if (flip) std::swap(k[1], k[2]);
      Polygon p;
      p.material = material;
      p.line = 0;
      for (int c = 0; c < 3; ++c) {
        size_t v = prim.indices >= 0 ? static_cast<size_t>(d.idx.Get(k[c], 0)) : k[c];
        if (v >= d.pos.count)
          return Status::At(path_, 0, where + "index " + std::to_string(v) + " is out of range");
        s = Corner(d, v, world, normalMatrix, where, &p);
        if (!s.ok()) return s;
      }
      for (const glm::vec2& u : p.uv)
        if (!std::isfinite(u.x) || !std::isfinite(u.y))
          return Status::At(path_, 0, where + "TEXCOORD_0 is not finite");
      if (material == defaultMaterial_) ++defaultFaces_;
      pieces_.clear();
      FaceResult r = ShapeFace(p, options_.strict, &pieces_);
      if (r.fate == FaceResult::kRefused)
        return Status::At(path_, 0, where + "triangle " + std::to_string(t) + ": " + r.error);
      if (r.fate == FaceResult::kDegenerate || r.fate == FaceResult::kSelfIntersecting)
        degenerate_.Add(0);
      for (Polygon& piece : pieces_) result_->polygons.push_back(std::move(piece));
    }
    return Status::Ok();
  }

  // Vertex v's corner of *p: its world position, uv and normal.
  Status Corner(const PrimitiveData& d, size_t v, const glm::dmat4& world,
                const glm::dmat3& normalMatrix, const std::string& where, Polygon* p) {
    const glm::dvec4 x = world * glm::dvec4(d.pos.Get(v, 0), d.pos.Get(v, 1), d.pos.Get(v, 2), 1.0);
    for (int a = 0; a < 3; ++a)
      if (!(std::fabs(x[a]) <= kMaxCoordinate))
        return Status::At(path_, 0, where + CoordinateError(x[a]));
    p->corners.emplace_back(static_cast<float>(x.x), static_cast<float>(x.y),
                            static_cast<float>(x.z));
    // glTF's v runs down the image, vismask's (OBJ's) up.
    if (d.hasUv)
      p->uv.emplace_back(static_cast<float>(d.uv.Get(v, 0)),
                         static_cast<float>(1.0 - d.uv.Get(v, 1)));
    if (d.hasNormal) {
      glm::dvec3 n = normalMatrix * glm::dvec3(d.nrm.Get(v, 0), d.nrm.Get(v, 1), d.nrm.Get(v, 2));
      const double len = glm::length(n);
      p->vn.push_back(len > 0.0 && std::isfinite(len) ? glm::vec3(n / len) : glm::vec3(0.0f));
    }
    return Status::Ok();
  }

  const std::string& path_;
  const LoadOptions& options_;
  const tinygltf::Model& m_;
  Scene* result_;
  Unused* unused_;
  uint32_t defaultMaterial_ = kNoMaterial;
  size_t defaultFaces_ = 0;
  FaceTally degenerate_;
  std::vector<Polygon> pieces_;
};

// --emit and the scene-wide checks, as for an OBJ, and the load's warnings.
Status FinishScene(const std::string& path, const LoadOptions& options, const NodeWalk& walk,
                   const Unused& unused, Scene* result, std::vector<std::string>* warnings) {
  std::vector<std::string> replaced;
  std::string replacedWhere;
  Status s = ApplyEmitOverrides(path, options.emit, &result->materials, &replaced, &replacedWhere);
  if (!s.ok()) return s;
  SceneTally tally;
  for (const Polygon& p : result->polygons) tally.Add(path, result->materials.size(), p);
  bool perfect[3] = {false, false, false};
  s = tally.Check(path, result->materials, perfect, options.outsideLight);
  if (!s.ok()) return s;
  for (int c = 0; c < 3; ++c)
    if (perfect[c] && ClosedFacingIn(result->polygons)) return CannotLosePower(path, c);
  result->bounds = tally.bounds;

  std::vector<std::string> w;
  if (walk.degenerate().faces)
    w.push_back(path + ": warning: " +
                Count(walk.degenerate().faces, "degenerate triangle", "degenerate triangles") +
                " dropped (zero area: repeated or collinear vertices)");
  if (walk.defaultFaces())
    w.push_back(path + ": warning: " + Count(walk.defaultFaces(), "triangle", "triangles") +
                " with no material: the default grey material '" + kDefaultMaterial + "' (Kd 0.5)");
  const std::string line = unused.Line(path);
  if (!line.empty()) w.push_back(line);
  if (!replaced.empty()) {
    std::string list;
    for (const std::string& r : replaced) list += (list.empty() ? "" : ", ") + r;
    w.push_back(path + ": warning: --emit replaces the file's emission of " + list);
  }
  warnings->insert(warnings->end(), w.begin(), w.end());
  return Status::Ok();
}

}  // namespace

Status LoadGltf(const std::string& path, const LoadOptions& options, Scene* scene,
                std::vector<std::string>* warnings) {
  tinygltf::Model m;
  Status s = ReadModel(path, &m);
  if (!s.ok()) return s;

  Scene result;
  result.objPath = path;
  Unused unused;
  s = gltf::MakeMaterials(path, m, &unused, &result.materials);
  if (!s.ok()) return s;
  for (const auto& [name, value] : m.extensions) unused.Add(name, "file", "files");
  if (!m.animations.empty()) unused.Add("animations", "animation", "animations");
  if (!m.skins.empty()) unused.Add("skins", "skin", "skins");
  NodeWalk walk(path, options, m, &result, &unused);
  s = walk.Walk();
  if (!s.ok()) return s;
  s = FinishScene(path, options, walk, unused, &result, warnings);
  if (!s.ok()) return s;
  *scene = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
