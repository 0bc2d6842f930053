// `vismask scene-dump SCENE [scene options] --out FILE`: the scene as
// vismask loads it, written as JSON for the tools that build other
// renderers' scenes from it (tools/reference's Blender scene,
// tools/silhouette-mask, tools/renderpark-run), so that they read no OBJ,
// MTL or glTF themselves and refuse exactly what `render` refuses.
//
// The scene goes through init's own passes (CountScene, PrepareScene: the
// same parser, mending, --emit, checks and view probe as `render`); the
// camera is the one `render` would use with the same options (--camera,
// --view, the scene file's camera, or the chosen side or inside view, as
// render_init.cpp picks it). Init-time work only: the heap is free here.
//
// The format ("format": "vismask-scene 1"), every number the float vismask
// holds, as the shortest decimal that reads back as that float:
//   scene      the scene file as given
//   files      the files the scene was read from: the scene file, then for
//              an OBJ each MTL file that defines a material, in that order
//   materials  [{name, kd, ke, two_sided, texture, where}]: Kd and Ke after
//              --emit; two_sided: the faces' backs are surfaces too (glTF
//              doubleSided or --two-sided), texture: map_Kd's path or null
//   faces      [{material, line, corners: [[x, y, z], ...]}]: every polygon
//              as mended, in file order, counter-clockwise seen from its
//              front; line: of its 'f' statement (0 in a glTF)
//   bounds     {lo, hi} of every corner
//   camera     {eye, target, up, fovy, from, view, view_auto}: from is
//              "--camera", "scene" (the glTF's), "side" or "inside"; view
//              the side's name (null unless from is "side"); view_auto true
//              when vismask chose it (no --view)
//   front_camera  the front side's camera (--view front), whatever was chosen
//   sky        [r, g, b] radiance, or null;  sun {toward, irradiance,
//              degrees}, or null
//   two_sided_emitters  --two-sided-emitters
#include "run.h"

namespace vismask::run {

const char* SceneDumpHelpText() {
  return "usage: vismask scene-dump SCENE [options] --out FILE.json\n"
         "\n"
         "Writes the scene as vismask loads it, as JSON: the files read, the\n"
         "materials (Kd, Ke after --emit, two-sided, texture path), every polygon as\n"
         "mended with its material, the bounds, the camera `render` would use with\n"
         "the same options (and the front side's), and --sky and --sun. The scene\n"
         "options are render's: --strict, --emit NAME=R,G,B|ka, --two-sided,\n"
         "--two-sided-emitters, --sky R,G,B, --sun X,Y,Z,R,G,B[,DEG], --camera,\n"
         "--view, --width, --height (the camera's checks); the others are read\n"
         "and checked as render reads them, and change nothing here.\n"
         "\n"
         "Exit status: 0 written; 2 bad input or options (file:line: message on\n"
         "stderr, nothing written, as render); 1 the file could not be written.\n";
}

namespace {

// The shortest decimal that reads back as the float `f` (552.8 for the float
// of an OBJ's "552.8", not 552.799988): a reader in double precision then
// has the number the file wrote, whenever the file wrote a float's worth.
void Num(std::string* s, float f) {
  char b[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(b, sizeof b, "%.*g", digits, static_cast<double>(f));
    if (std::strtof(b, nullptr) == f) break;
  }
  *s += b;
}

void Vec(std::string* s, const glm::vec3& v) {
  *s += "[";
  Num(s, v.x);
  *s += ", ";
  Num(s, v.y);
  *s += ", ";
  Num(s, v.z);
  *s += "]";
}

void CameraJson(std::string* s, const Camera& c) {
  *s += "{\"eye\": ";
  Vec(s, c.eye);
  *s += ", \"target\": ";
  Vec(s, c.target);
  *s += ", \"up\": ";
  Vec(s, c.up);
  *s += ", \"fovy\": ";
  Num(s, c.fovyDeg);
}

// The file part of a material's "file:line".
std::string FileOf(const std::string& where) {
  const size_t colon = where.rfind(':');
  return colon == std::string::npos ? where : where.substr(0, colon);
}

}  // namespace

int SceneDump(const Options& o) {
  const std::string& out = o.outDir;
  if (out.size() < 6 || out.compare(out.size() - 5, 5, ".json") != 0)
    return Fail(
        Status::Error("vismask: scene-dump: --out FILE.json is needed (a name ending in .json; '" +
                      out + "' given or the default)"));
  Prepared p;
  Status s = CountScene(o, &p);
  if (!s.ok()) return Fail(s);
  p.clock.report = false;
  s = PrepareScene(o, &p, 0, static_cast<uint32_t>(o.envs[0] * o.envs[1] * o.envs[2]), false);
  if (!s.ok()) return Fail(s);
  // The polygons as the passes give them (every one, in file order).
  std::vector<Polygon> polygons;
  polygons.reserve(p.info.numPolygons);
  s = StreamObj(p.info, o.load, [&](uint32_t, const Polygon& poly) { polygons.push_back(poly); });
  if (!s.ok()) return Fail(s);

  // The camera render would use.
  const CameraChoice cam = ChooseCamera(o, p);
  const char* from = cam.fromScene ? "scene"
                     : cam.inside  ? "inside"
                     : cam.hasSide ? "side"
                                   : "--camera";
  View view;
  if (!MakeView(cam.camera, o.width, o.height, &view))
    return Fail(Status::Error("vismask: --camera: degenerate camera"));

  const bool gltf = IsGltfPath(o.scene);
  std::string j = "{\n  \"format\": \"vismask-scene 1\",\n  \"scene\": " + JsonQuoted(o.scene) +
                  ",\n  \"files\": [" + JsonQuoted(o.scene);
  std::vector<std::string> files{o.scene};
  for (const Material& m : p.scene.materials) {
    const std::string f = FileOf(m.where);
    if (gltf || f.empty() || std::find(files.begin(), files.end(), f) != files.end()) continue;
    files.push_back(f);
    j += ", " + JsonQuoted(f);
  }
  j += "],\n  \"materials\": [";
  for (size_t k = 0; k < p.scene.materials.size(); ++k) {
    const Material& m = p.scene.materials[k];
    j += k ? ",\n    " : "\n    ";
    j += "{\"name\": " + JsonQuoted(m.name) + ", \"kd\": ";
    Vec(&j, m.kd);
    j += ", \"ke\": ";
    Vec(&j, m.ke);
    j += std::string(", \"two_sided\": ") + (m.twoSided || o.twoSided ? "true" : "false");
    j += ", \"texture\": " + (m.mapKd.empty() ? std::string("null") : JsonQuoted(m.mapKd));
    j += ", \"where\": " + JsonQuoted(m.where) + "}";
  }
  j += "\n  ],\n  \"faces\": [";
  char b[64];
  for (size_t i = 0; i < polygons.size(); ++i) {
    const Polygon& poly = polygons[i];
    std::snprintf(b, sizeof b, "%s{\"material\": %u, \"line\": %d, \"corners\": [",
                  i ? ",\n    " : "\n    ", poly.material, poly.line);
    j += b;
    for (size_t c = 0; c < poly.corners.size(); ++c) {
      if (c) j += ", ";
      Vec(&j, poly.corners[c]);
    }
    j += "]}";
  }
  j += "\n  ],\n  \"bounds\": {\"lo\": ";
  Vec(&j, p.scene.bounds.lo);
  j += ", \"hi\": ";
  Vec(&j, p.scene.bounds.hi);
  j += "},\n  \"camera\": ";
  CameraJson(&j, cam.camera);
  j += std::string(", \"from\": \"") + from + "\", \"view\": " +
       (cam.hasSide ? std::string("\"") + ViewSideName(cam.side) + "\"" : std::string("null")) +
       ", \"view_auto\": " + (cam.hasSide && cam.sideChosen ? "true" : "false") + "},\n";
  j += "  \"front_camera\": ";
  CameraJson(&j, SideCamera(p.scene.bounds, ViewSide::kFront));
  j += "},\n  \"sky\": ";
  if (o.outside.HasSky())
    Vec(&j, o.outside.sky);
  else
    j += "null";
  j += ",\n  \"sun\": ";
  if (o.outside.HasSun()) {
    j += "{\"toward\": ";
    Vec(&j, o.outside.sunToward);
    j += ", \"irradiance\": ";
    Vec(&j, o.outside.sun);
    j += ", \"degrees\": ";
    Num(&j, o.outside.sunDegrees);
    j += "}";
  } else {
    j += "null";
  }
  j += std::string(",\n  \"two_sided_emitters\": ") + (o.twoSidedEmitters ? "true" : "false") +
       "\n}\n";

  const os::FilePart part{j.data(), j.size()};
  char why[os::kWhyBytes];
  if (!os::WriteFileAtomic(o.outDir.c_str(), &part, 1, nullptr, why)) {
    os::PrintErr("vismask: scene-dump: %s: %s\n", o.outDir.c_str(), why);
    return kExitOutput;
  }
  return kExitOk;
}

}  // namespace vismask::run
