#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "vismask/core/os.h"
#include "vismask/scene/texture.h"

// A scene's textures: map_Kd files found and loaded (once each), the
// materials resolved to them, the mesh's patches given their uv and means,
// and the texels a solve keeps (TextureSet).
namespace vismask {

std::string FindTexture(const std::string& path) {
  if (os::Exists(path.c_str())) return path;
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  std::vector<std::string> names;
  std::string why;
  if (name.empty() || !os::ListDirectory(dir.c_str(), &names, &why)) return "";
  auto lower = [](std::string s) {
    for (char& c : s)
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return s;
  };
  const std::string want = lower(name);
  // Sorted bytewise: of several names that differ only in case, the first.
  for (const std::string& n : names)
    if (lower(n) == want) return slash == std::string::npos ? n : dir + n;
  return "";
}

void ResolveTextures(std::vector<Material>* materials, const std::vector<uint8_t>& used,
                     bool strict, std::vector<std::string>* warnings) {
  std::string otherCase, otherCaseWhere, missing, missingWhere;
  size_t numOtherCase = 0, numMissing = 0;
  for (size_t m = 0; m < materials->size(); ++m) {
    Material& mat = (*materials)[m];
    if (!used[m] || mat.mapKd.empty() || mat.mapKdBytes) continue;  // held in a glTF file
    const std::string found = FindTexture(mat.mapKd);
    // --strict: the name as written, and the reader says why it cannot.
    if (found == mat.mapKd || strict) continue;
    const size_t slash = found.rfind('/');
    if (!found.empty()) {
      if (numOtherCase++ == 0) otherCaseWhere = mat.mapKdWhere;
      otherCase += (otherCase.empty() ? "'" : ", '") + mat.mapKd + "' as '" +
                   (slash == std::string::npos ? found : found.substr(slash + 1)) + "'";
      mat.mapKd = found;
      continue;
    }
    if (numMissing++ == 0) missingWhere = mat.mapKdWhere;
    missing += (missing.empty() ? "'" : ", '") + mat.mapKd + "' (" + mat.name + ")";
    mat.mapKd.clear();
    mat.mapKdWhere.clear();
    if (mat.mapIsColour)
      mat.kd *= 0.5f;
    else if (mat.kd == glm::vec3(0.0f))
      mat.kd = glm::vec3(0.5f);
  }
  if (numOtherCase > 0)
    warnings->push_back(otherCaseWhere + ": warning: " + std::to_string(numOtherCase) +
                        (numOtherCase == 1 ? " texture" : " textures") +
                        " found in another letter case (first here): " + otherCase);
  if (numMissing > 0)
    warnings->push_back(missingWhere + ": warning: " + std::to_string(numMissing) +
                        (numMissing == 1 ? " texture" : " textures") +
                        " not found, their materials untextured with their Kd (0.5 grey where "
                        "Kd is 0, a glTF base colour factor times 0.5; first here): " +
                        missing);
}

Status LoadSceneTextures(Scene* scene, SceneTextures* out, bool strict) {
  const size_t nm = scene->materials.size();
  std::vector<uint8_t> used(nm, 0);
  std::vector<int> noUv(nm, 0);
  for (const Polygon& p : scene->polygons) {
    used[p.material] = 1;
    if (p.uv.empty() && noUv[p.material] == 0) noUv[p.material] = p.line;
  }
  return LoadMaterialTextures(scene->objPath, &scene->materials, used, noUv, out, strict);
}

Status LoadMaterialTextures(const std::string& objPath, std::vector<Material>* materialsIo,
                            const std::vector<uint8_t>& used, const std::vector<int>& noUvLineOf,
                            SceneTextures* out, uint64_t budget, bool strict) {
  SceneTextures r;
  ResolveTextures(materialsIo, used, strict, &r.warnings);
  const std::vector<Material>& materials = *materialsIo;
  const size_t nm = materials.size();
  r.ofMaterial.assign(nm, kNoTexture);
  r.kdOfMaterial.resize(nm);
  int noUvLine = 0;  // the first face of a textured material without uv
  for (size_t m = 0; m < nm; ++m) r.kdOfMaterial[m] = materials[m].kd;
  std::map<std::string, uint32_t> byPath;
  std::string zeroKd;  // materials whose map stands alone
  std::string zeroKdWhere;
  for (size_t m = 0; m < nm; ++m) {
    const Material& mat = materials[m];
    if (!used[m] || mat.mapKd.empty()) continue;
    auto it = byPath.find(mat.mapKd);
    if (it == byPath.end()) {
      TextureImage img;
      // A file, or an image the scene file holds (glTF): the same checks
      // and decoder, within the budget (DecodeTexture).
      Status s = mat.mapKdBytes
                     ? DecodeTexture(*mat.mapKdBytes, mat.mapKd, mat.mapKdWhere, &img, budget)
                     : ReadTexture(mat.mapKd, mat.mapKdWhere, &img, budget);
      if (!s.ok()) return s;
      if (budget > 0) budget -= std::min(budget - 1, static_cast<uint64_t>(img.rgb.size()));
      it = byPath.emplace(mat.mapKd, static_cast<uint32_t>(r.images.size())).first;
      r.images.push_back(std::move(img));
    }
    r.ofMaterial[m] = it->second;
    if (mat.kd == glm::vec3(0.0f)) {
      // The map alone is the reflectance: white texels reflect everything,
      // as Kd 1 does (accepted; a scene that then cannot lose
      // power is the loader's to refuse).
      r.kdOfMaterial[m] = glm::vec3(1.0f);
      zeroKd += (zeroKd.empty() ? "'" : ", '") + mat.name + "'";
      if (zeroKdWhere.empty()) zeroKdWhere = mat.mapKdWhere;
    }
  }
  for (size_t m = 0; m < nm; ++m)
    if (r.ofMaterial[m] != kNoTexture && noUvLineOf[m] != 0 &&
        (noUvLine == 0 || noUvLineOf[m] < noUvLine))
      noUvLine = noUvLineOf[m];
  if (!zeroKd.empty())
    r.warnings.push_back(zeroKdWhere +
                         ": warning: Kd 0 0 0 with map_Kd: the map alone is the "
                         "reflectance (Kd taken as 1) for material" +
                         (zeroKd.find(',') == std::string::npos ? " " : "s ") + zeroKd);
  if (noUvLine != 0)
    r.warnings.push_back(objPath + ":" + std::to_string(noUvLine) +
                         ": warning: faces with a map_Kd material but no texture coordinates "
                         "('vt'): they take the texture's mean reflectance, untextured");
  *out = std::move(r);
  return Status::Ok();
}

void TextureMesh(const Scene& scene, const SceneTextures& textures, Mesh* mesh) {
  mesh->textures.clear();
  if (!textures.any()) return;
  std::vector<PatchTexture> out(mesh->patches.size());
  bool any = false;
  uint32_t fitted = kNoPatch;
  UvMap map;
  for (size_t i = 0; i < mesh->patches.size(); ++i) {
    Patch& p = mesh->patches[i];
    const Polygon& poly = scene.polygons[p.surface];
    const uint32_t t = textures.ofMaterial[poly.material];
    if (t == kNoTexture) continue;
    const TextureImage& img = textures.images[t];
    const glm::vec3 kd = textures.kdOfMaterial[poly.material];
    if (poly.uv.empty()) {  // no coordinates: the texture's mean, untextured
      for (int c = 0; c < 3; ++c) p.kd[c] = static_cast<float>(kd[c] * img.mean[c]);
      continue;
    }
    if (fitted != p.surface) {
      map = FitUvMap(poly);
      fitted = p.surface;
    }
    PatchTexture& pt = out[i];
    pt.texture = t;
    for (int k = 0; k < 4; ++k) pt.uv[k] = map.At(p.corner[k]);
    glm::dvec3 mean = PatchTextureMean(img.View(), p, pt.uv, &img.pyramid);
    for (int c = 0; c < 3; ++c) {
      p.kd[c] = static_cast<float>(kd[c] * mean[c]);
      double kdMaterial = kd[c] * img.mean[c];
      pt.scale[c] = p.kd[c] > 0.0f ? static_cast<float>(kdMaterial / p.kd[c]) : 0.0f;
    }
    any = true;
  }
  if (any) mesh->textures = std::move(out);
}

void TextureSet::Layout(Arena& arena, const SceneTextures& scene,
                        const std::vector<uint8_t>& used) {
  const size_t mark = arena.used();
  textures = arena.Alloc<Texture>(scene.images.size());
  for (size_t i = 0; i < scene.images.size(); ++i) {
    const TextureImage& img = scene.images[i];
    Span<uint8_t> texels = used[i] ? arena.Alloc<uint8_t>(img.rgb.size()) : Span<uint8_t>();
    if (arena.measuring()) continue;
    Texture t = img.View();
    t.texels = nullptr;
    if (used[i]) {
      std::copy(img.rgb.begin(), img.rgb.end(), texels.begin());
      t.texels = texels.data();
    }
    textures[i] = t;
  }
  bytes = arena.used() - mark;
}

}  // namespace vismask
