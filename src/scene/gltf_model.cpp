#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gltf_internal.h"

// A glTF model's accessors, buffer views, node transforms and materials,
// each checked before it is read (LoadGltf's pieces, gltf_internal.h).
namespace vismask::gltf {

namespace {

using objload::Num;
using objload::Quote;

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

}  // namespace

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

}  // namespace vismask::gltf
