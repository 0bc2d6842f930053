// Texture: map_Kd images. Decoded at init (stb_image: PNG, JPEG, BMP, TGA),
// and used twice:
//   - the solve: a patch's reflectance is Kd times the texture's mean over
//     the patch (linear, sRGB decoded), fixed at init into Patch::kd;
//   - the display: a textured patch's display value is Ke + kd_mat * E (E
//     the irradiance-like B_reflected / kd, kd_mat = Kd times the whole
//     texture's mean: the radiosity the patch would have with the material's
//     mean reflectance), and each pixel shows Ke + (texel / texture mean) *
//     (value - Ke), i.e. Ke + texel reflectance * E.
// Texture coordinates come from an affine map position -> uv fitted to a
// polygon's corners (exact for triangles, least squares for more corners),
// so clipped pieces and patches of one polygon agree.
#pragma once
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <string>
#include <vector>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/core/status.h"
#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/outside.h"
#include "vismask/solve/patch.h"

namespace vismask {

// The linear value of an 8-bit sRGB code (IEC 61966-2-1), from a table.
float SrgbToLinear(uint8_t code);

// A texture as the display and the patch means read it: a view over RGB
// 8-bit sRGB texels, rows top to bottom (the image's first row is v = 1).
struct Texture {
  uint32_t width = 0;
  uint32_t height = 0;
  const uint8_t* texels = nullptr;  // null: not held by this rank
  glm::vec3 invMean{0.0f};          // 1 / the mean linear texel, per channel (0 where it is 0)

  // The linear value at `uv`: bilinear between texel centres, wrap mode
  // repeat. Non-finite coordinates read (0, 0).
  glm::vec3 Sample(glm::vec2 uv) const;
  // Sample(uv) / the texture's mean: 1 on average.
  glm::vec3 Modulation(glm::vec2 uv) const { return Sample(uv) * invMean; }
};

// A texture's box-filtered levels at init (heap), for the patch means: level
// k (1, 2, ...) is ceil(w / 2^k) x ceil(h / 2^k) linear texels, each the mean
// of the (up to) 2 x 2 texels of level k - 1 it covers, down to 1 x 1.
// Built in time proportional to the texels (a third of them written).
struct TexturePyramid {
  struct Level {
    uint32_t width = 0, height = 0;
    size_t offset = 0;  // into `texels`, 3 floats a texel, rows top to bottom
  };
  std::vector<Level> levels;  // levels[0] is level 1
  std::vector<float> texels;
  // The linear value of level k (1 ...) at uv, bilinear and repeating as
  // Texture::Sample.
  glm::vec3 Sample(size_t k, glm::vec2 uv) const;
};
// The pyramid of a texture (texture.texels must be there).
TexturePyramid BuildPyramid(const Texture& texture);

// A decoded map_Kd at init (heap).
struct TextureImage {
  std::string path;  // as resolved by the loader
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgb;  // sRGB, 3 bytes a texel
  glm::dvec3 mean{0.0};      // mean linear texel per channel
  uint8_t maxCode = 0;       // the largest code of any channel
  TexturePyramid pyramid;    // for the patch means (PatchTextureMean)
  Texture View() const;      // over `rgb`
};

// What decoding a texture holds at its peak, per texel, on top of the
// file's bytes: stb_image's inflated rows (up to 16-bit RGBA, 8 bytes), its
// 8-bit conversion (4), the RGB result (3) and TextureImage's copy (3).
constexpr uint64_t kTextureDecodeBytesPerTexel = 18;

// Reads and decodes an image file into *image. `where` ("file:line" of the
// map_Kd) prefixes the error: "where: cannot read texture 'path': reason".
// Only a regular file is read (a device or a FIFO is refused by its kind),
// of at most 2^31 - 1 bytes. With `budget` > 0, the file's bytes and then
// the decoding's (kTextureDecodeBytesPerTexel a texel, the dimensions read
// from the header first) must fit in it, or nothing more is read. Decoder
// messages quote no raw byte of the file (\xNN).
Status ReadTexture(const std::string& path, const std::string& where, TextureImage* image,
                   uint64_t budget = 0);
// ReadTexture's decoding of a file's `bytes` (in memory; `path` names it in
// messages): the dimensions judged against `budget` first, then decoded.
// The texture fuzz target's entry (tests/fuzz/texture_fuzz.cpp).
Status DecodeTexture(const std::string& bytes, const std::string& path, const std::string& where,
                     TextureImage* image, uint64_t budget = 0);

// --sky FILE.hdr: a Radiance HDR file (stb_image's reader) read and decoded
// into *map (linear RGB floats, staged on the heap; SkyMap::crossing
// integrated), with ReadTexture's checks: a regular file of at most 2^31 - 1
// bytes, its bytes and then its decoding (kSkyDecodeBytesPerTexel a texel,
// the dimensions read from the header first) within `budget` (> 0), at most
// kMaxSkyTexels texels, every texel finite and >= 0. Errors name the file.
constexpr uint64_t kSkyDecodeBytesPerTexel = 24;  // stb_image's floats and the staged copy
constexpr uint64_t kMaxSkyTexels = uint64_t{1} << 26;
Status ReadSkyMap(const std::string& path, SkyMap* map, uint64_t budget = 0);
// ReadSkyMap's decoding of a file's `bytes` (in memory; `path` names it in
// messages), with the same checks: the sky-map fuzz target's entry
// (tests/fuzz/sky_fuzz.cpp).
Status DecodeSkyMap(const std::string& bytes, const std::string& path, SkyMap* map,
                    uint64_t budget = 0);

// The affine map x -> uv = (dot(u.xyz, x) + u.w, dot(v.xyz, x) + v.w) on a
// polygon's plane, fitted to its corners' uv (least squares; exact for a
// triangle and for corners whose uv is affine). Zero for a polygon without uv.
struct UvMap {
  glm::dvec4 u{0.0};
  glm::dvec4 v{0.0};
  glm::vec2 At(const glm::vec3& x) const;
};
UvMap FitUvMap(const Polygon& polygon);

// uv at parameters `st` of a patch (bilinear for a quad, barycentric for a
// triangle, as PatchPoint).
glm::vec2 PatchUv(const PatchTexture& t, bool triangle, glm::vec2 st);

// The mean of `texture` over patch `p` whose corners have texture
// coordinates `uv`: an area-weighted grid of n x n samples (n from the
// patch's extent in texels, two a texel, 2 to 64; sub-triangle centroids
// for a triangle). Deterministic. With `pyramid`, a patch that would take
// more than kDirectSamples a side samples the level where it does not
// (level k: 2^k texels a texel), so that a patch costs at most
// kDirectSamples^2 samples whatever the texture's size: init's texture
// means take time in proportion to texels + patches, not their product.
// `samples`, when given, is added the samples taken (a counted measure).
constexpr int kDirectSamples = 32;
glm::dvec3 PatchTextureMean(const Texture& texture, const Patch& p, const glm::vec2 uv[4],
                            const TexturePyramid* pyramid = nullptr, uint64_t* samples = nullptr);

// The scene's textures at init: every distinct map_Kd of a material that
// some face uses, decoded, and which material uses which.
struct SceneTextures {
  std::vector<TextureImage> images;
  std::vector<uint32_t> ofMaterial;     // per material: index into images, or kNoTexture
  std::vector<glm::vec3> kdOfMaterial;  // per material: the Kd the map multiplies (1 for Kd 0 0 0)
  std::vector<std::string> warnings;    // one line each
  bool any() const { return !images.empty(); }
};

// The file a map_Kd path names: `path` itself if it exists, else the name
// in the same folder in another letter case (the first such, bytewise), else "".
std::string FindTexture(const std::string& path);

// The map_Kd of each used material looked up (FindTexture): one found in
// another letter case is read from there, one not found at all is dropped
// (the material untextured with its Kd, 0.5 grey where Kd is 0 0 0, a glTF
// base colour factor times 0.5: Material::mapIsColour), each
// kind in one warning line naming them all. With `strict` nothing is
// changed (the reader then refuses a name that is not found).
void ResolveTextures(std::vector<Material>* materials, const std::vector<uint8_t>& used,
                     bool strict, std::vector<std::string>* warnings);

// Loads the textures of `scene` (its materials' map_Kd resolved first, as
// ResolveTextures says). Fails on an unreadable image (at its map_Kd line).
// Materials with Kd 0 0 0 and a map make one warning naming them all (the
// map alone is the reflectance); faces of a textured material without
// texture coordinates, another (they take the texture's mean, untextured).
Status LoadSceneTextures(Scene* scene, SceneTextures* out, bool strict = false);
// The same from what the streaming loader keeps of the polygons
// (scene_stream.h): per material, whether a polygon uses it and the line of
// its first polygon without texture coordinates (0: none).
// `budget` > 0: the bytes init may still use; each image is read and
// decoded within what the ones before it left (ReadTexture). `materials`
// may be repaired (a texture found in another letter case, or dropped with
// a warning unless `strict`).
Status LoadMaterialTextures(const std::string& objPath, std::vector<Material>* materials,
                            const std::vector<uint8_t>& used, const std::vector<int>& noUvLine,
                            SceneTextures* out, uint64_t budget = 0, bool strict = false);

// Sets the reflectance of `mesh`'s textured patches (Kd times the texture's
// mean over the patch) and fills mesh->textures (one per patch, or empty
// when none is textured). `scene` is the scene the mesh was made from
// (Patch::surface indexes its polygons).
void TextureMesh(const Scene& scene, const SceneTextures& textures, Mesh* mesh);

// The textures a rank's display reads, in the rank's arena: one Texture per
// scene texture, texels only for those in `used`. Measured and laid out like
// every arena part; a real arena gets the texels copied in.
struct TextureSet {
  Span<Texture> textures;
  uint64_t bytes = 0;  // what Layout carved
  void Layout(Arena& arena, const SceneTextures& scene, const std::vector<uint8_t>& used);
};

}  // namespace vismask
