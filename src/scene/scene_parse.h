// The OBJ + MTL parser's pieces (internal to src/): text helpers, the lines
// of a file one at a time, the Loader (OBJ statements in src/scene/obj_loader.cpp,
// MTL in src/scene/mtl_loader.cpp) that hands each polygon, as mended, to a
// visitor instead of keeping it, and the per-scene checks as reductions over
// that stream (src/scene/scene.cpp). The whole-file loader (LoadScene) and the
// streaming passes (scene_stream.h) are the same code.
#pragma once
#include <cstdint>
#include <functional>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "vismask/core/os.h"
#include "vismask/core/status.h"
#include "vismask/scene/scene.h"

namespace vismask::objload {

// The largest OBJ or MTL file read.
constexpr uintmax_t kMaxFileBytes = uintmax_t{4} << 30;
// The longest line a scene file (OBJ) may have: the reader's line buffer is
// bounded by it (a face of some 100,000 corners fits).
constexpr size_t kMaxLineBytes = size_t{1} << 20;
// A NUL byte in a file's first kTextProbeBytes makes it binary, refused.
constexpr size_t kTextProbeBytes = 1024;

// What float geometry and float images can carry (docs/STABILITY.md). Ray
// tests multiply coordinates and square lengths in float (max 3.4e38, least
// normal 1.2e-38), so coordinates stay within 1e15 and faces above 1e-15 in
// size; radiosity is bounded by max Ke / (1 - max Kd) (when max Kd < 1), and the image holds it
// in float, so that bound stays within 1e36, and above 1e-30 so that the
// image is not all denormals.
constexpr double kMaxCoordinate = 1e15;
// A scene far from the origin for its size: its float coordinates step by
// more than this share of its extent: past it, the rounding of patch
// corners and ray hits shows in the image (tests/scene_text_test.cpp).
constexpr double kMaxStepShare = 2.5e-4;
constexpr double kMinFaceSize = 1e-15;
constexpr double kMaxRadiosity = 1e36;
constexpr double kMinRadiosity = 1e-30;

using Tokens = std::vector<std::string>;

std::string Num(double x);
std::string Str(size_t n);
std::string CoordinateError(double x);
// Splits a line at whitespace; '#' starts a comment, a CR (CRLF files) is space.
Tokens Tokenize(const std::string& line);
// The file name of a texture map statement ('map_Kd [options] name'), as
// written on `line` (tokens `t`): what follows the known options, spaces
// inside it kept. *hadOptions: some option was given. "" if no name.
std::string MapName(const std::string& line, const Tokens& t, bool* hadOptions);
// A piece of the input quoted in a message (at most 32 bytes, escaped).
std::string Quote(const std::string& s);
// Appends byte c to *out: as it is if it is printable ASCII other than a
// backslash, else as \xNN (Quote's and the texture decoders' messages).
void AppendEscaped(std::string* out, unsigned char c);
// Whether an unknown MTL key may be named in a warning.
bool LooksLikeKey(const std::string& s);
// Reads a whole file (regular files only, at most kMaxFileBytes); returns an
// error message, empty on success.
std::string ReadText(const std::string& path, std::string* text);
// The same for a binary file (a .glb, a glTF's buffers): no text check.
std::string ReadBytes(const std::string& path, std::string* bytes);
// Checks that `path` is a regular file a loader may read (as ReadText does,
// without reading it); returns an error message, empty on success.
std::string CheckReadable(const std::string& path);
// Why the first bytes of a file (their first kTextProbeBytes) show it is
// not text (a NUL byte), or "".
std::string NotText(const char* bytes, size_t n);
// A file named inside another: relative to the naming file's directory.
std::string Beside(const std::string& namingFile, const std::string& name);
// Parses tokens[first..first+count) as finite floats into out[].
std::string ParseFloats(const Tokens& tokens, size_t first, size_t count, float* out);
bool IsInteger(const std::string& s);
// "1 face", "3 faces".
std::string Count(size_t n, const char* one, const char* many);

// A face corner's indices, 0-based; kNone where the corner gives none.
constexpr size_t kNone = static_cast<size_t>(-1);
struct CornerIndex {
  size_t v = kNone, vt = kNone, vn = kNone;
};
// Resolves a face corner "i", "i/t", "i/t/n" or "i//n".
std::string ParseCorner(const std::string& s, size_t numVertices, size_t numUvs, size_t numNormals,
                        CornerIndex* out);

// A kind of mended face, counted: how many, the first one's line, and the
// farthest corner off the plane (non-planar faces).
struct FaceTally {
  size_t faces = 0;
  size_t corners = 0;  // corners removed
  int line = 0;
  double off = 0.0;
  void Add(int at) {
    if (faces++ == 0) line = at;
  }
};

// What makes a material more than diffuse: kept per material while its MTL
// is read, for one warning after loading.
struct Finish {
  int illum = -1;   // -1: not given
  bool ks = false;  // some Ks channel > 0
  bool tf = false;  // some Tf channel < 1
  double d = 1.0;   // dissolve (1 - Tr)
};
// MTL keys read silently (see mtl_loader.cpp).
bool IsSilentMtlKey(const std::string& key);
// Why a material is not purely diffuse, or "" if it is.
std::string NotDiffuse(const Finish& f);
// Parses "a b c" (or one number) leniently, for keys only read to warn.
bool LenientFloats(const Tokens& t, size_t count, double* out);

// One statement of an OBJ or MTL file (LineSource::NextStatement).
struct Statement {
  std::string text;  // the line as read
  int line = 0;      // its number
  Tokens tokens;
  std::string key;  // tokens[0]
  size_t args = 0;  // tokens after the key
};

// The lines of a text, one at a time: split at LF, CR LF or a lone CR (old
// Mac files), the last line kept even without one, no empty line after a
// final line end; a leading UTF-8 byte-order mark dropped.
class LineSource {
 public:
  virtual ~LineSource() = default;
  // The next line into *line; false at the end (or on a read error: error()).
  virtual bool Next(std::string* line) = 0;
  // The next line that is not blank or only a comment into *s: its text,
  // tokens, key (the first token) and argument count, s->line advanced
  // past every line read (the line numbers of the caller's messages);
  // false at the end.
  bool NextStatement(Statement* s) {
    while (Next(&s->text)) {
      ++s->line;
      s->tokens = Tokenize(s->text);
      if (s->tokens.empty()) continue;
      s->key = s->tokens[0];
      s->args = s->tokens.size() - 1;
      return true;
    }
    return false;
  }
  // An error met on the way ("cannot read (...)", a line too long, a binary
  // file), empty if none, and the line it is at (0: the file as a whole).
  virtual std::string error() const { return ""; }
  virtual int errorLine() const { return 0; }
};

// Lines of text held in memory by the caller.
class TextLines : public LineSource {
 public:
  explicit TextLines(const std::string& text);
  bool Next(std::string* line) override;

 private:
  const std::string& text_;
  size_t pos_;
};

// Lines of a file read through a fixed 64 KiB buffer: the file is never
// held whole, nor a line longer than kMaxLineBytes (an error at its
// number), and a file with a NUL byte in its first kTextProbeBytes is
// refused there. Open checks it as ReadText does.
class FileLines : public LineSource {
 public:
  // Returns an error message (as ReadText's), empty on success.
  std::string Open(const std::string& path);
  bool Next(std::string* line) override;
  std::string error() const override { return error_; }
  int errorLine() const override { return errorLine_; }

 private:
  bool Fail(std::string error, int line);  // false, the reading ended

  os::InFile in_;
  std::unique_ptr<char[]> buf_;
  size_t begin_ = 0, end_ = 0;
  bool first_ = true, eof_ = false;
  bool pendingCr_ = false;  // the last line ended at a CR that ended the buffer
  int lines_ = 0;           // lines returned so far
  int errorLine_ = 0;
  std::string error_;
};

// Each polygon the OBJ gives, as mended (ShapeFace), in file order.
using PolygonVisitor = std::function<void(const Polygon&)>;

// How many statements of each kind an OBJ holds, counted by their first
// word only (the first pass: sizes the loader's arrays before they exist).
struct ObjCounts {
  uint64_t lines = 0, vertices = 0, uvs = 0, normals = 0, faces = 0, faceCorners = 0;
  // The heap the loader's vertex, uv and normal arrays take when reserved
  // to these counts.
  uint64_t ArrayBytes() const { return 12 * vertices + 8 * uvs + 12 * normals; }
};
ObjCounts CountStatements(LineSource& lines);

// Applies --emit (`emit`, in order) to *materials by name; an --emit naming
// no material is an error. Each that replaced a nonzero Ke is listed in
// *replaced ("name (Ke r g b)"), *replacedWhere the first one's "where".
Status ApplyEmitOverrides(const std::string& scenePath, const std::vector<EmitOverride>& emit,
                          std::vector<Material>* materials, std::vector<std::string>* replaced,
                          std::string* replacedWhere);

// The material of faces the OBJ gives none (before any 'usemtl') and the
// reflectance of every material the loader makes up (no 'usemtl', an
// undefined name, a texture not found with Kd 0): a mid grey.
inline constexpr char kDefaultMaterial[] = "default";
inline constexpr float kDefaultKd = 0.5f;

class Loader {
 public:
  Loader(std::vector<Material>* materials, const SceneFileReader& readMtl,
         const LoadOptions& options)
      : materials_(materials), readMtl_(readMtl), options_(options) {}
  // Reserves the vertex, uv and normal arrays exactly (from CountStatements).
  void Reserve(const ObjCounts& counts);
  // Parses the OBJ statement by statement; each face, as mended, goes to
  // `visit` (a face's pieces in order). Materials are read from the MTL
  // files it names into *materials.
  Status LoadObj(const std::string& path, LineSource& lines, const PolygonVisitor& visit);
  // Applies options.emit; an --emit that names no material is an error.
  Status ApplyEmit();
  // The warnings, one line per kind, in the order they first arose and the
  // aggregate ones after. `used`: per material, whether a polygon uses it.
  std::vector<std::string> Warnings(const std::vector<uint8_t>& used) const;
  // When no polygon of an emitting material is left (`used`) but faces of
  // one were dropped (no area, or edges that cross): the error at the first
  // such face, which "no emitter" would hide. Ok otherwise.
  Status DroppedEmitters(const std::vector<uint8_t>& used) const;
  // The names 'usemtl' gave that no MTL defines ("'a', 'b'"), "" if none.
  std::string UndefinedMaterials() const;

 private:
  Status LoadMtl(const std::string& path, const std::string& objPath, int objLine);
  // The index of material `name`, made the default grey (Kd 0.5) at
  // path:line if no MTL defined it.
  uint32_t DefaultMaterial(const std::string& name, const std::string& path, int line);
  // Face statement `t` at `line` (3 or more corners), shaped (ShapeFace) and
  // its pieces visited; what was mended or dropped counted for the warnings.
  Status Face(const Tokens& t, int line, uint32_t material, uint32_t smoothing,
              std::vector<Polygon>* pieces, const PolygonVisitor& visit);
  // One warning line per distinct `what`, at its first file:line.
  void Warn(const std::string& path, int line, const std::string& what) {
    if (!warnedKeys_.insert(what).second) return;
    warnings_.push_back(path + ":" + std::to_string(line) + ": warning: " + what);
  }

  std::vector<Material>* materials_;
  const SceneFileReader& readMtl_;
  const LoadOptions& options_;
  std::vector<std::string> warnings_;
  std::vector<glm::vec3> vertices_;
  std::vector<glm::vec2> uvs_;
  std::vector<glm::vec3> normals_;
  std::map<std::string, std::pair<uint32_t, std::string>> materialIndex_;  // index, "file:line"
  std::vector<Finish> finishes_;                                           // per material
  std::set<std::string> loadedMtls_;
  std::set<std::string> warnedKeys_;
  std::vector<std::string> ignoredKeys_;  // unknown MTL keys, in order of first use
  std::string ignoredWhere_;              // "file:line" of the first
  size_t notMtlLines_ = 0;                // lines whose first word is no MTL key at all
  std::string notMtlWhere_;               // "file:line" of the first
  std::string path_;                      // the OBJ
  FaceTally triangulated_, cornersRemoved_, degenerate_, selfIntersecting_;
  // Per material: the first face of it dropped whole, and why.
  std::map<uint32_t, std::pair<int, const char*>> droppedFace_;
  std::vector<std::string> undefinedMaterials_;  // named by 'usemtl', defined by no MTL
  std::string undefinedWhere_;                   // "file:line" of the first
  std::vector<std::string> replacedKe_;  // "name (Ke r g b)" of each --emit that replaced one
  std::string replacedWhere_;
};

// The scene-wide checks of the loader, as reductions over the polygon
// stream: fed every polygon in file order (Add), then judged once the
// materials are final (Check). What they keep is per material and a few
// numbers, never the polygons.
struct SceneTally {
  size_t polygons = 0;
  Bounds bounds;               // of every corner
  float largest = 0.0f;        // the largest |coordinate|
  int farLine = 0;             // the first polygon's line with it
  Status firstBad;             // the first polygon beyond float's range (coordinate, area)
  std::vector<uint8_t> used;   // per material: some polygon uses it
  std::vector<int> firstLine;  // per material: the line of its first polygon
  std::vector<int> noUvLine;   // per material: its first polygon without uv (0: none)

  void Add(const std::string& objPath, size_t numMaterials, const Polygon& p);
  // The scene-wide errors in the order the loader gives them (no emitter,
  // a face beyond float's range, far from the origin, the radiosity bound);
  // *perfect[c]: every face has Kd 1 in channel c (then the closed-scene
  // check, ClosedFacingIn, must look at the polygons).
  // `lit`: light comes from outside (--sky, --sun), so no emitter is needed.
  Status Check(const std::string& objPath, const std::vector<Material>& materials, bool perfect[3],
               bool lit = false) const;
};

// Whether the faces close space with their fronts facing in (scene.cpp).
bool ClosedFacingIn(const std::vector<Polygon>& polys);
// The error for a scene that cannot lose power in channel c.
Status CannotLosePower(const std::string& objPath, int c);

// Pass over an OBJ: parse, mend, visit every polygon, check. The one body
// of LoadSceneFromText and of the streaming passes: `lines` are the OBJ's,
// `counts` (may be null) reserve the arrays. On success *materials and
// *tally are the scene's, *warnings the loader's lines (not yet printed),
// and perfect[] says which channels need the closed-scene check.
Status ParseObj(const std::string& objPath, LineSource& lines, const ObjCounts* counts,
                const SceneFileReader& readMtl, const LoadOptions& options,
                const PolygonVisitor& visit, std::vector<Material>* materials, SceneTally* tally,
                std::vector<std::string>* warnings, bool perfect[3]);

}  // namespace vismask::objload
