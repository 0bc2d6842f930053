// Scene stream: the OBJ read in passes, never held whole (issue 20). Pass 0
// counts statements by their first word, so that what the parser will hold
// is known before it exists; pass 1 parses, mends and checks everything, as
// LoadScene does, visiting each polygon in file order without keeping it;
// later passes give the same polygons again, in the same order, for the
// stages that need the scene's extent first (clipping into environments,
// the camera's side, the emitter check). Init-time (heap).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vismask/core/status.h"
#include "vismask/scene/scene.h"

namespace vismask {

// What the passes learn of a scene, all but its polygons.
struct SceneInfo {
  std::string objPath;
  std::vector<Material> materials;  // --emit applied
  Bounds bounds;                    // of every polygon corner
  size_t numPolygons = 0;           // after mending
  // Pass 0: statements by kind.
  uint64_t lines = 0, vertices = 0, uvs = 0, normals = 0, faces = 0, faceCorners = 0;
  // Per material: whether a polygon uses it, and the line of its first
  // polygon without texture coordinates (0: none).
  std::vector<uint8_t> usedMaterials;
  std::vector<int> noUvLine;
  std::vector<std::string> warnings;  // the loader's, not yet printed
  // A glTF file (IsGltfPath) is parsed whole by pass 1 and held for the
  // later passes: its polygons, their heap bytes, its first camera.
  std::shared_ptr<const Scene> held;
  uint64_t heldBytes = 0;
  SceneCamera camera;
  // The most heap a pass holds for the parser: the vertex, uv and normal
  // arrays (12, 8 and 12 bytes each, reserved exactly from pass 0's counts),
  // or the glTF scene held.
  uint64_t ParserBytes() const { return 12 * vertices + 8 * uvs + 12 * normals + heldBytes; }
};

// A polygon of the scene, as mended, with its index in file order.
using PolygonVisit = std::function<void(uint32_t index, const Polygon& polygon)>;

// Pass 0: opens the OBJ (a missing, unreadable or non-regular file is
// `obj:0`, as LoadScene says it) and counts its statements into *info.
Status CountObj(const std::string& objPath, SceneInfo* info);

// Pass 1: parses and checks the OBJ and its MTL files exactly as LoadScene
// does (the same errors, file:line, in the same order) and visits every
// polygon. On success *info holds the materials, bounds, counts and
// warnings. The closed-scene check (every face Kd 1 in some channel) needs
// the faces together: only then does it hold every polygon, in one more pass.
Status ScanObj(const std::string& objPath, const LoadOptions& options, const PolygonVisit& visit,
               SceneInfo* info);

// A later pass over info.objPath (after ScanObj filled `info`): the same
// polygons as ScanObj's, in the same order (the file read again; an error
// only if the file changed in between).
Status StreamObj(const SceneInfo& info, const LoadOptions& options, const PolygonVisit& visit);

}  // namespace vismask
