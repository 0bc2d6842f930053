// Scene: the polygons and materials of a Wavefront OBJ + MTL file, as loaded
// and validated at init (see ../shared/cornell/README.md for the conventions).
// Init-time data: it lives on the heap and is dropped once the environments
// have taken their patches.
#pragma once
#include <cstdint>
#include <functional>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "vismask/core/status.h"

namespace vismask {

struct Bounds {
  glm::vec3 lo{0.0f};
  glm::vec3 hi{0.0f};
};

struct Material {
  std::string name;
  glm::vec3 kd{0.0f};  // diffuse reflectance, each channel in [0, 1] (1: a perfect reflector)
  glm::vec3 ke{0.0f};  // emitted exitance, each channel >= 0 (--emit may replace it)
  glm::vec3 ka{0.0f};  // ambient colour as written (read for --emit NAME=ka)
  std::string mapKd;   // map_Kd: the texture's path (relative to the cwd), "" if none
  std::string where;   // "file:line" of its 'newmtl'
  std::string mapKdWhere = "";  // "file:line" of its 'map_Kd' ("" if none)
  // A glTF texture held in the file (a .glb's buffer or a data: URI): its
  // encoded bytes (mapKd then names it, "FILE#images[i]"); null otherwise.
  std::shared_ptr<const std::string> mapKdBytes = nullptr;
  // glTF: the map is the colour and Kd only its factor (1 by default), so a
  // map that is not found leaves Kd times 0.5, a mid-grey stand-in (an OBJ's
  // Kd stays as written, 0 becoming 0.5).
  bool mapIsColour = false;
  // Both sides of its faces are surfaces (glTF doubleSided): each patch
  // gets a twin (mesh.h, AddTwins), and an emitter's twin emits too.
  bool twoSided = false;
};

// A camera a scene file gives (glTF: the first camera a node of the scene
// holds), as --camera takes it.
struct SceneCamera {
  bool has = false;
  glm::vec3 eye{0.0f}, target{0.0f, 0.0f, 1.0f}, up{0.0f, 1.0f, 0.0f};
  float fovyDeg = 39.3f;
};

// A planar simple polygon with 3 or more corners, counter-clockwise seen from
// its front side: an OBJ face, or a piece of one the loader mended (a
// triangle of a non-planar face; the face less degenerate corners).
struct Polygon {
  std::vector<glm::vec3> corners;
  std::vector<glm::vec2> uv;  // texture coordinates, one per corner ('vt'), or empty
  std::vector<glm::vec3> vn;  // vertex normals as written, one per corner ('vn'), or empty
  uint32_t smoothing = 0;     // smoothing group ('s N'); 0: none ('s off', 's 0' or no 's')
  glm::vec3 normal{0.0f};     // unit, front side (Newell's method)
  double area = 0.0;
  uint32_t material = 0;  // index into Scene::materials
  int line = 0;           // line of the 'f' statement in Scene::objPath (shared by its pieces)
};

struct Scene {
  std::string objPath;  // the scene file (OBJ or glTF)
  std::vector<Material> materials;
  std::vector<Polygon> polygons;
  Bounds bounds;       // of all polygon corners
  SceneCamera camera;  // glTF: its first camera
};

// What the loader is told besides the files (the command line's --strict
// and --emit).
struct EmitOverride {
  std::string material;  // a material's name
  bool fromKa = false;   // NAME=ka: Ke = the material's Ka
  glm::vec3 ke{0.0f};    // NAME=R,G,B: Ke = (R, G, B), each >= 0
};
struct LoadOptions {
  // Refuse a face that is degenerate, non-planar or self-intersecting, with
  // the messages of the loader before issue 16, instead of mending it.
  bool strict = false;
  // Materials made emitters (or not): each replaces its material's Ke, in
  // order (the last for a name wins).
  std::vector<EmitOverride> emit;
  // --sky or --sun: the light comes from outside, so a scene need not emit.
  bool outsideLight = false;
};

// Loads and validates `objPath` and the MTL files it names (relative to the
// OBJ's directory). On malformed input returns an error naming file and line,
// leaving *scene untouched: a missing or unreadable file, an unknown statement
// or wrong argument count, a bad or out-of-range index, a number that does not
// parse or is not finite, a face with no material, Kd outside [0, 1], negative
// Ke or Ka, a duplicate material, an --emit naming no material (no file),
// no emitter at all, or a scene that cannot lose power (line 0: in some
// channel every face has Kd 1 and the faces close space with their fronts
// facing in). Faces that are degenerate, non-planar or self-intersecting are
// refused with `options.strict`; otherwise mended or dropped (ShapeFace,
// face.h), and each kind is counted in one warning line at its first face.
// Warnings, after loading and only when it succeeds, one line per kind at its
// first file:line: MTL keys that neither matter to diffuse radiosity nor are
// known (one line for all), materials rendered as diffuse although specular
// or transparent (illum 3-9, Ks with a highlight, Tf or d below 1, Tr above
// 0; one line naming those faces use), an --emit replacing a nonzero Ke.
// Read and kept for later stages: 'vt' and 'vn' per face corner (kept only
// when every corner of the face gives them; a face that gives them for some
// corners warns once), 's' smoothing groups, 'Ka' and 'map_Kd' (the last
// token; options before it are ignored with a warning).
Status LoadScene(const std::string& objPath, Scene* scene,
                 const LoadOptions& options = LoadOptions());

// Whether `path` is a glTF 2.0 file by its extension (.gltf or .glb, any
// letter case): LoadScene and the streaming passes read it with LoadGltf.
bool IsGltfPath(const std::string& path);

// Loads a glTF 2.0 file (.gltf with its buffers and images beside it, or
// .glb) into *scene (src/scene/gltf_scene.cpp, tinygltf): the triangles of the
// default scene's meshes (strips and fans too) with their nodes' transforms,
// as polygons in node order (each triangle mended or dropped as an OBJ face
// is, ShapeFace); per material Kd = baseColorFactor and the
// baseColorTexture as map_Kd, Ke = pi * emissiveFactor *
// KHR_materials_emissive_strength (glTF gives the radiance a surface emits,
// vismask the exitance of a diffuse emitter: pi times it), doubleSided;
// the first camera a node holds. Then --emit and the scene-wide checks, as
// for an OBJ. Errors name the file (line 0) and the element; what vismask
// cannot use (metallic, roughness, normal maps, transmission, other
// extensions, lines and points, ...) is named in one warning in *warnings.
// Init-time: the file is parsed whole (a glTF is not a stream of lines).
Status LoadGltf(const std::string& path, const LoadOptions& options, Scene* scene,
                std::vector<std::string>* warnings);

// Reads the file at `path` into *text; returns an error message ("cannot
// open", ...), empty on success.
using SceneFileReader = std::function<std::string(const std::string& path, std::string* text)>;

// LoadScene on text already in memory: `objText` is the OBJ named `objPath`
// (the name errors carry; MTL paths are relative to its directory), and
// `readMtl` supplies each MTL file it names. The same parser and checks as
// LoadScene, which is this with the file's text and a file reader (the
// fuzz target, tests/fuzz/, feeds it arbitrary bytes). Warnings go to
// `warnings` when given, else to stderr.
Status LoadSceneFromText(const std::string& objPath, const std::string& objText,
                         const SceneFileReader& readMtl, Scene* scene,
                         std::vector<std::string>* warnings = nullptr,
                         const LoadOptions& options = LoadOptions());

}  // namespace vismask
