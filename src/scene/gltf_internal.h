// glTF input's pieces (internal to src/scene/gltf_scene.cpp, which parses
// the file and walks its nodes, and src/scene/gltf_model.cpp): tinygltf's
// model, an accessor's elements bounds-checked, node transforms, materials,
// and the fields vismask cannot use.
#pragma once
#include <cstdint>
#include <cstring>
#include <glm/mat4x4.hpp>
#include <initializer_list>
#include <string>
#include <vector>

#include "scene_parse.h"
#include "vismask/core/status.h"
#include "vismask/scene/scene.h"

// tinygltf's image decoding and writing and its file access are left out
// (gltf_scene.cpp compiles it, with TINYGLTF_IMPLEMENTATION).
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

namespace vismask::gltf {

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

// The bytes of buffer view `index`, checked against its buffer.
std::string ViewBytes(const tinygltf::Model& m, int index, const unsigned char** data,
                      size_t* size);

// Accessor `index` as `what` wants it: one of `types` (component types),
// `components` per element.
std::string Access(const tinygltf::Model& m, int index, const char* what,
                   std::initializer_list<int> types, int components, Elements* out);

// A node's local transform: its matrix, or translation * rotation * scale.
glm::dmat4 LocalTransform(const tinygltf::Node& n);

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

// The materials: Kd, Ke, the base colour texture, two-sidedness.
Status MakeMaterials(const std::string& path, const tinygltf::Model& m, Unused* unused,
                     std::vector<Material>* out);

}  // namespace vismask::gltf
