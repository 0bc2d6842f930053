// glTF 2.0 input (scene.h, LoadGltf): a .gltf or .glb parsed by tinygltf
// (Debian's libtinygltf-dev, header only, compiled here with nlohmann json;
// its image decoding and writing are left out: stb_image is compiled once,
// in texture_decode.cpp, which decodes the textures), then its triangles, node
// transforms, materials and first camera made into the Scene the OBJ loader
// makes. Files are read through vismask's reader (regular files, 4 GiB at
// most); every accessor is bounds-checked here before it is read.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "scene_parse.h"
#include "vismask/core/os.h"
#include "vismask/scene/face.h"
#include "vismask/scene/scene.h"

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
// tinygltf 2.7.0's writer (compiled, never called) names std::ofstream even
// with TINYGLTF_NO_FS.
#include <fstream>
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <tiny_gltf.h>
#pragma GCC diagnostic pop

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

using objload::Num;
using objload::Quote;

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

// An accessor's elements, checked against its buffer view and buffer.
struct Elements {
  const unsigned char* data = nullptr;
  size_t count = 0, stride = 0;
  int componentType = 0, components = 0;
  bool normalized = false;

  // Component c of element i as a number (normalized integers in [0, 1]).
  double Get(size_t i, int c) const {
    const unsigned char* p = data + i * stride;
    switch (componentType) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        std::memcpy(&f, p + 4 * c, 4);
        return f;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[c] / 255.0 : p[c];
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t u;
        std::memcpy(&u, p + 2 * c, 2);
        return normalized ? u / 65535.0 : u;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t u;
        std::memcpy(&u, p + 4 * c, 4);
        return u;
      }
    }
    return 0.0;
  }
};

int ComponentBytes(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
  }
  return 0;
}

int Components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
      return 4;
  }
  return 0;
}

// The bytes of buffer view `index`, checked against its buffer.
std::string ViewBytes(const tinygltf::Model& m, int index, const unsigned char** data,
                      size_t* size) {
  if (index < 0 || static_cast<size_t>(index) >= m.bufferViews.size())
    return "bufferView " + std::to_string(index) + " does not exist";
  const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(index)];
  if (v.buffer < 0 || static_cast<size_t>(v.buffer) >= m.buffers.size())
    return "bufferView " + std::to_string(index) + ": buffer " + std::to_string(v.buffer) +
           " does not exist";
  const std::vector<unsigned char>& b = m.buffers[static_cast<size_t>(v.buffer)].data;
  if (v.byteOffset > b.size() || v.byteLength > b.size() - v.byteOffset)
    return "bufferView " + std::to_string(index) + " runs past the end of its buffer";
  *data = b.data() + v.byteOffset;
  *size = v.byteLength;
  return "";
}

// Accessor `index` as `what` wants it: one of `types` (component types),
// `components` per element.
std::string Access(const tinygltf::Model& m, int index, const char* what,
                   std::initializer_list<int> types, int components, Elements* out) {
  const std::string name = std::string(what) + " (accessor " + std::to_string(index) + ")";
  if (index < 0 || static_cast<size_t>(index) >= m.accessors.size())
    return name + ": no such accessor";
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(index)];
  if (a.sparse.isSparse) return name + ": sparse accessors are not supported";
  if (std::find(types.begin(), types.end(), a.componentType) == types.end() ||
      Components(a.type) != components)
    return name + ": unexpected component type or element type";
  if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && components > 1 && !a.normalized &&
      std::strcmp(what, "TEXCOORD_0") == 0)
    return name + ": integer texture coordinates must be normalized";
  const unsigned char* data = nullptr;
  size_t size = 0;
  if (a.bufferView < 0) return name + ": no bufferView (all zeros) is not supported";
  std::string err = ViewBytes(m, a.bufferView, &data, &size);
  if (!err.empty()) return name + ": " + err;
  const size_t elem = static_cast<size_t>(ComponentBytes(a.componentType) * components);
  const size_t viewStride = m.bufferViews[static_cast<size_t>(a.bufferView)].byteStride;
  const size_t stride = viewStride ? viewStride : elem;
  if (stride < elem) return name + ": byteStride smaller than an element";
  if (a.count > 0) {
    const uint64_t need =
        uint64_t{a.byteOffset} + uint64_t{a.count - 1} * stride + static_cast<uint64_t>(elem);
    if (a.count > (uint64_t{1} << 32) || a.byteOffset > size || need > size)
      return name + ": its elements run past the end of their bufferView";
  }
  out->data = data + a.byteOffset;
  out->count = a.count;
  out->stride = stride;
  out->componentType = a.componentType;
  out->components = components;
  out->normalized = a.normalized;
  return "";
}

// A node's local transform: its matrix, or translation * rotation * scale.
glm::dmat4 LocalTransform(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    glm::dmat4 m(1.0);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = n.matrix[static_cast<size_t>(4 * c + r)];
    return m;
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (n.translation.size() == 3)
    t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
  if (n.rotation.size() == 4) {
    const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    r[0] = glm::dvec4(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w), 0);
    r[1] = glm::dvec4(2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w), 0);
    r[2] = glm::dvec4(2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y), 0);
  }
  if (n.scale.size() == 3) {
    s[0][0] = n.scale[0];
    s[1][1] = n.scale[1];
    s[2][2] = n.scale[2];
  }
  return t * r * s;
}

// What vismask cannot use, counted by what holds it, for one warning.
class Unused {
 public:
  void Add(const std::string& field, const char* one, const char* many) {
    for (Entry& e : entries_)
      if (e.field == field) {
        ++e.count;
        return;
      }
    entries_.push_back({field, one, many, 1});
  }
  std::string Line(const std::string& path) const {
    if (entries_.empty()) return "";
    std::string list;
    for (const Entry& e : entries_)
      list += (list.empty() ? "" : ", ") + e.field + " (" + objload::Count(e.count, e.one, e.many) +
              ")";
    return path +
           ": warning: glTF fields vismask cannot use (it renders diffuse light only), "
           "ignored: " +
           list;
  }

 private:
  struct Entry {
    std::string field;
    const char* one;
    const char* many;
    size_t count;
  };
  std::vector<Entry> entries_;
};

// %XX escapes of a URI decoded (image file names).
std::string UriDecode(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    auto hex = [](char c) {
      return c >= '0' && c <= '9'   ? c - '0'
             : c >= 'a' && c <= 'f' ? c - 'a' + 10
             : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                    : -1;
    };
    if (uri[i] == '%' && i + 2 < uri.size() && hex(uri[i + 1]) >= 0 && hex(uri[i + 2]) >= 0) {
      out += static_cast<char>(hex(uri[i + 1]) * 16 + hex(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// The materials: Kd, Ke, the base colour texture, two-sidedness.
Status MakeMaterials(const std::string& path, const tinygltf::Model& m, Unused* unused,
                     std::vector<Material>* out) {
  const std::string where = path;  // "file" for messages (no line in a glTF)
  for (size_t i = 0; i < m.materials.size(); ++i) {
    const tinygltf::Material& g = m.materials[i];
    Material mat;
    mat.name = g.name.empty() ? "material_" + std::to_string(i) : g.name;
    for (size_t j = 0; j < i; ++j)
      if ((*out)[j].name == mat.name) mat.name += "_" + std::to_string(i);
    mat.where = where;
    const std::string what = "material " + Quote(mat.name) + ": ";
    const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
    std::vector<double> base = pbr.baseColorFactor;
    if (base.size() != 4) base = {1.0, 1.0, 1.0, 1.0};
    for (int c = 0; c < 3; ++c) {
      if (!(base[c] >= 0.0 && base[c] <= 1.0))
        return Status::At(path, 0, what + "baseColorFactor " + Num(base[c]) + " is not in [0, 1]");
      mat.kd[c] = static_cast<float>(base[c]);
    }
    if (base[3] < 1.0) unused->Add("baseColorFactor alpha", "material", "materials");
    double strength = 1.0;
    for (const auto& [name, value] : g.extensions) {
      if (name == "KHR_materials_emissive_strength" && value.Has("emissiveStrength") &&
          value.Get("emissiveStrength").IsNumber()) {
        strength = value.Get("emissiveStrength").GetNumberAsDouble();
      } else {
        unused->Add(name, "material", "materials");
      }
    }
    std::vector<double> emissive = g.emissiveFactor;
    if (emissive.size() != 3) emissive = {0.0, 0.0, 0.0};
    for (int c = 0; c < 3; ++c) {
      // glTF's emission is the radiance the surface sends (times the
      // strength, in nits); vismask's Ke is a diffuse emitter's exitance,
      // pi times its radiance (image.pfm shows Ke / pi on the emitter).
      const double ke = M_PI * emissive[c] * strength;
      if (!(ke >= 0.0 && ke <= objload::kMaxRadiosity))
        return Status::At(path, 0,
                          what + "emissiveFactor " + Num(emissive[c]) + " x emissiveStrength " +
                              Num(strength) + " is not a finite emission >= 0");
      mat.ke[c] = static_cast<float>(ke);
    }
    mat.twoSided = g.doubleSided;
    if (pbr.metallicFactor > 0.0) unused->Add("metallicFactor", "material", "materials");
    if (pbr.roughnessFactor != 1.0) unused->Add("roughnessFactor", "material", "materials");
    if (pbr.metallicRoughnessTexture.index >= 0)
      unused->Add("metallicRoughnessTexture", "material", "materials");
    if (g.normalTexture.index >= 0) unused->Add("normalTexture", "material", "materials");
    if (g.occlusionTexture.index >= 0) unused->Add("occlusionTexture", "material", "materials");
    if (g.emissiveTexture.index >= 0) unused->Add("emissiveTexture", "material", "materials");
    if (g.alphaMode != "OPAQUE") unused->Add("alphaMode " + g.alphaMode, "material", "materials");
    const int t = pbr.baseColorTexture.index;
    if (t >= 0) {
      if (static_cast<size_t>(t) >= m.textures.size())
        return Status::At(path, 0,
                          what + "baseColorTexture " + std::to_string(t) + " does not exist");
      if (pbr.baseColorTexture.texCoord != 0)
        unused->Add("baseColorTexture texCoord other than 0 (TEXCOORD_0 used)", "material",
                    "materials");
      if (!pbr.baseColorTexture.extensions.empty())
        unused->Add("baseColorTexture extensions", "material", "materials");
      const tinygltf::Texture& tex = m.textures[static_cast<size_t>(t)];
      if (tex.sampler >= 0 && static_cast<size_t>(tex.sampler) < m.samplers.size()) {
        const tinygltf::Sampler& s = m.samplers[static_cast<size_t>(tex.sampler)];
        if (s.wrapS != TINYGLTF_TEXTURE_WRAP_REPEAT || s.wrapT != TINYGLTF_TEXTURE_WRAP_REPEAT)
          unused->Add("sampler wrap modes other than repeat", "texture", "textures");
      }
      if (tex.source < 0 || static_cast<size_t>(tex.source) >= m.images.size())
        return Status::At(path, 0,
                          what + "texture " + std::to_string(t) + ": image " +
                              std::to_string(tex.source) + " does not exist");
      const tinygltf::Image& img = m.images[static_cast<size_t>(tex.source)];
      const std::string inFile = path + "#images[" + std::to_string(tex.source) + "]";
      mat.mapKdWhere = where;
      mat.mapIsColour = true;
      if (img.bufferView >= 0) {
        const unsigned char* data = nullptr;
        size_t size = 0;
        std::string err = ViewBytes(m, img.bufferView, &data, &size);
        if (!err.empty())
          return Status::At(path, 0, "image " + std::to_string(tex.source) + ": " + err);
        mat.mapKd = inFile;
        mat.mapKdBytes =
            std::make_shared<const std::string>(reinterpret_cast<const char*>(data), size);
      } else if (!img.image.empty()) {  // a data: URI
        mat.mapKd = inFile;
        mat.mapKdBytes = std::make_shared<const std::string>(img.image.begin(), img.image.end());
      } else if (!img.uri.empty()) {
        mat.mapKd = objload::Beside(path, UriDecode(img.uri));
      }
    }
    out->push_back(std::move(mat));
  }
  return Status::Ok();
}

}  // namespace

Status LoadGltf(const std::string& path, const LoadOptions& options, Scene* scene,
                std::vector<std::string>* warnings) {
  using namespace objload;
  std::string bytes;
  std::string err = ReadBytes(path, &bytes);
  if (!err.empty()) return Status::At(path, 0, err);
  tinygltf::TinyGLTF reader;
  reader.SetFsCallbacks({FsExists, FsExpand, FsRead, FsWrite, nullptr});
  reader.SetImageLoader(KeepImageBytes, nullptr);
  tinygltf::Model m;
  std::string gerr, gwarn;
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  if (bytes.size() > 0xffffffffu) return Status::At(path, 0, "a glTF file of 4 GiB or more");
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  const bool ok =
      binary ? reader.LoadBinaryFromMemory(&m, &gerr, &gwarn,
                                           reinterpret_cast<const unsigned char*>(bytes.data()),
                                           static_cast<unsigned>(bytes.size()), dir)
             : reader.LoadASCIIFromString(&m, &gerr, &gwarn, bytes.data(),
                                          static_cast<unsigned>(bytes.size()), dir);
  if (!ok) {
    std::string why = gerr.empty() ? "not a glTF 2.0 file" : gerr;
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    for (char& c : why)
      if (c == '\n') c = ';';
    return Status::At(path, 0, "cannot read glTF: " + why);
  }
  bytes.clear();
  bytes.shrink_to_fit();

  Scene result;
  result.objPath = path;
  Unused unused;
  Status s = MakeMaterials(path, m, &unused, &result.materials);
  if (!s.ok()) return s;
  for (const auto& [name, value] : m.extensions) unused.Add(name, "file", "files");
  if (!m.animations.empty()) unused.Add("animations", "animation", "animations");
  if (!m.skins.empty()) unused.Add("skins", "skin", "skins");
  uint32_t defaultMaterial = kNoMaterial;
  size_t defaultFaces = 0;

  // The default scene's nodes, depth first, each with its world transform.
  std::vector<std::pair<int, glm::dmat4>> stack;
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
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
  size_t visited = 0;
  FaceTally degenerate;
  std::vector<Polygon> pieces;
  while (!stack.empty()) {
    auto [index, parent] = stack.back();
    stack.pop_back();
    if (index < 0 || static_cast<size_t>(index) >= m.nodes.size())
      return Status::At(path, 0, "node " + std::to_string(index) + " does not exist");
    if (++visited > 4 * m.nodes.size() + 4)
      return Status::At(path, 0, "the node hierarchy has a cycle");
    const tinygltf::Node& node = m.nodes[static_cast<size_t>(index)];
    const glm::dmat4 world = parent * LocalTransform(node);
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
      stack.emplace_back(*c, world);
    const std::string nodeName =
        "node " + (node.name.empty() ? std::to_string(index) : Quote(node.name));
    if (node.camera >= 0 && !result.camera.has) {
      if (static_cast<size_t>(node.camera) >= m.cameras.size())
        return Status::At(path, 0,
                          nodeName + ": camera " + std::to_string(node.camera) + " does not exist");
      const tinygltf::Camera& cam = m.cameras[static_cast<size_t>(node.camera)];
      if (cam.type == "perspective" && cam.perspective.yfov > 0.0 && cam.perspective.yfov < M_PI) {
        // A glTF camera looks down its local -z, up +y.
        const glm::dvec3 eye(world * glm::dvec4(0, 0, 0, 1));
        const glm::dvec3 ahead = glm::normalize(glm::dvec3(world * glm::dvec4(0, 0, -1, 0)));
        const glm::dvec3 up = glm::normalize(glm::dvec3(world * glm::dvec4(0, 1, 0, 0)));
        result.camera.has = true;
        result.camera.eye = glm::vec3(eye);
        result.camera.target = glm::vec3(eye + ahead);
        result.camera.up = glm::vec3(up);
        result.camera.fovyDeg = static_cast<float>(cam.perspective.yfov * 180.0 / M_PI);
      } else {
        unused.Add("camera not perspective", "camera", "cameras");
      }
    }
    if (node.mesh < 0) continue;
    if (static_cast<size_t>(node.mesh) >= m.meshes.size())
      return Status::At(path, 0,
                        nodeName + ": mesh " + std::to_string(node.mesh) + " does not exist");
    if (node.skin >= 0) unused.Add("skinned meshes (drawn unskinned)", "node", "nodes");
    const glm::dmat3 linear(world);
    const bool flip = glm::determinant(linear) < 0.0;
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
    const tinygltf::Mesh& mesh = m.meshes[static_cast<size_t>(node.mesh)];
    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& prim = mesh.primitives[pi];
      const std::string where = nodeName + " mesh " +
                                (mesh.name.empty() ? std::to_string(node.mesh) : Quote(mesh.name)) +
                                " primitive " + std::to_string(pi) + ": ";
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          prim.mode != TINYGLTF_MODE_TRIANGLE_FAN && prim.mode != -1) {
        unused.Add("points and lines", "primitive", "primitives");
        continue;
      }
      if (!prim.targets.empty()) unused.Add("morph targets", "primitive", "primitives");
      auto attr = [&](const char* name) {
        auto it = prim.attributes.find(name);
        return it == prim.attributes.end() ? -1 : it->second;
      };
      Elements pos, uv, nrm, idx;
      if (attr("POSITION") < 0) return Status::At(path, 0, where + "no POSITION");
      err = Access(m, attr("POSITION"), "POSITION", {TINYGLTF_COMPONENT_TYPE_FLOAT}, 3, &pos);
      if (!err.empty()) return Status::At(path, 0, where + err);
      const bool hasUv = attr("TEXCOORD_0") >= 0, hasNormal = attr("NORMAL") >= 0;
      if (hasUv) {
        err = Access(m, attr("TEXCOORD_0"), "TEXCOORD_0",
                     {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                     2, &uv);
        if (!err.empty()) return Status::At(path, 0, where + err);
        if (uv.count != pos.count) return Status::At(path, 0, where + "TEXCOORD_0 count differs");
      }
      if (hasNormal) {
        err = Access(m, attr("NORMAL"), "NORMAL", {TINYGLTF_COMPONENT_TYPE_FLOAT}, 3, &nrm);
        if (!err.empty()) return Status::At(path, 0, where + err);
        if (nrm.count != pos.count) return Status::At(path, 0, where + "NORMAL count differs");
      }
      size_t numIndices = pos.count;
      if (prim.indices >= 0) {
        err = Access(m, prim.indices, "indices",
                     {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                     1, &idx);
        if (!err.empty()) return Status::At(path, 0, where + err);
        numIndices = idx.count;
      }
      auto vertexAt = [&](size_t k, size_t* v) {
        *v = prim.indices >= 0 ? static_cast<size_t>(idx.Get(k, 0)) : k;
        return *v < pos.count;
      };
      uint32_t material = 0;
      if (prim.material >= 0) {
        if (static_cast<size_t>(prim.material) >= result.materials.size())
          return Status::At(
              path, 0, where + "material " + std::to_string(prim.material) + " does not exist");
        material = static_cast<uint32_t>(prim.material);
      } else {
        if (defaultMaterial == kNoMaterial) {
          Material d;
          d.name = kDefaultMaterial;
          d.kd = glm::vec3(kDefaultKd);
          d.where = path;
          defaultMaterial = static_cast<uint32_t>(result.materials.size());
          result.materials.push_back(std::move(d));
        }
        material = defaultMaterial;
      }
      // The triangles' index triples.
      size_t numTriangles = 0;
      if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP || prim.mode == TINYGLTF_MODE_TRIANGLE_FAN)
        numTriangles = numIndices >= 3 ? numIndices - 2 : 0;
      else
        numTriangles = numIndices / 3;
      for (size_t t = 0; t < numTriangles; ++t) {
        size_t k[3];
        if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
          k[0] = t;
          k[1] = t % 2 ? t + 2 : t + 1;
          k[2] = t % 2 ? t + 1 : t + 2;
        } else if (prim.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
          k[0] = t + 1;
          k[1] = t + 2;
          k[2] = 0;
        } else {
          k[0] = 3 * t;
          k[1] = 3 * t + 1;
          k[2] = 3 * t + 2;
        }
        if (flip) std::swap(k[1], k[2]);
        Polygon p;
        p.material = material;
        p.line = 0;
        for (int c = 0; c < 3; ++c) {
          size_t v = 0;
          if (!vertexAt(k[c], &v))
            return Status::At(path, 0, where + "index " + std::to_string(v) + " is out of range");
          const glm::dvec4 x = world * glm::dvec4(pos.Get(v, 0), pos.Get(v, 1), pos.Get(v, 2), 1.0);
          for (int a = 0; a < 3; ++a)
            if (!(std::fabs(x[a]) <= kMaxCoordinate))
              return Status::At(path, 0, where + CoordinateError(x[a]));
          p.corners.emplace_back(static_cast<float>(x.x), static_cast<float>(x.y),
                                 static_cast<float>(x.z));
          // glTF's v runs down the image, vismask's (OBJ's) up.
          if (hasUv)
            p.uv.emplace_back(static_cast<float>(uv.Get(v, 0)),
                              static_cast<float>(1.0 - uv.Get(v, 1)));
          if (hasNormal) {
            glm::dvec3 n = normalMatrix * glm::dvec3(nrm.Get(v, 0), nrm.Get(v, 1), nrm.Get(v, 2));
            const double len = glm::length(n);
            p.vn.push_back(len > 0.0 && std::isfinite(len) ? glm::vec3(n / len) : glm::vec3(0.0f));
          }
        }
        for (const glm::vec2& u : p.uv)
          if (!std::isfinite(u.x) || !std::isfinite(u.y))
            return Status::At(path, 0, where + "TEXCOORD_0 is not finite");
        if (material == defaultMaterial) ++defaultFaces;
        pieces.clear();
        FaceResult r = ShapeFace(p, options.strict, &pieces);
        if (r.fate == FaceResult::kRefused)
          return Status::At(path, 0, where + "triangle " + std::to_string(t) + ": " + r.error);
        if (r.fate == FaceResult::kDegenerate || r.fate == FaceResult::kSelfIntersecting)
          degenerate.Add(0);
        for (Polygon& piece : pieces) result.polygons.push_back(std::move(piece));
      }
    }
  }

  // --emit and the scene-wide checks, as for an OBJ.
  std::vector<std::string> replaced;
  std::string replacedWhere;
  s = ApplyEmitOverrides(path, options.emit, &result.materials, &replaced, &replacedWhere);
  if (!s.ok()) return s;
  SceneTally tally;
  for (const Polygon& p : result.polygons) tally.Add(path, result.materials.size(), p);
  bool perfect[3] = {false, false, false};
  s = tally.Check(path, result.materials, perfect, options.outsideLight);
  if (!s.ok()) return s;
  for (int c = 0; c < 3; ++c)
    if (perfect[c] && ClosedFacingIn(result.polygons)) return CannotLosePower(path, c);
  result.bounds = tally.bounds;

  std::vector<std::string> w;
  if (degenerate.faces)
    w.push_back(path + ": warning: " +
                Count(degenerate.faces, "degenerate triangle", "degenerate triangles") +
                " dropped (zero area: repeated or collinear vertices)");
  if (defaultFaces)
    w.push_back(path + ": warning: " + Count(defaultFaces, "triangle", "triangles") +
                " with no material: the default grey material '" + kDefaultMaterial + "' (Kd 0.5)");
  const std::string line = unused.Line(path);
  if (!line.empty()) w.push_back(line);
  if (!replaced.empty()) {
    std::string list;
    for (const std::string& r : replaced) list += (list.empty() ? "" : ", ") + r;
    w.push_back(path + ": warning: --emit replaces the file's emission of " + list);
  }
  warnings->insert(warnings->end(), w.begin(), w.end());
  *scene = std::move(result);
  return Status::Ok();
}

}  // namespace vismask
