// The MTL statements, --emit and the loader's warnings (scene_parse.h).
#include <algorithm>
#include <string>
#include <vector>

#include "scene_parse.h"

namespace vismask::objload {

Status ApplyEmitOverrides(const std::string& scenePath, const std::vector<EmitOverride>& emit,
                          std::vector<Material>* materials, std::vector<std::string>* replaced,
                          std::string* replacedWhere) {
  for (const EmitOverride& e : emit) {
    auto it = std::find_if(materials->begin(), materials->end(),
                           [&](const Material& m) { return m.name == e.material; });
    if (it == materials->end()) {
      std::string names;
      for (const Material& m : *materials) names += (names.empty() ? "" : ", ") + m.name;
      return Status::Error(
          "vismask: --emit: no material '" + e.material + "' in " + scenePath +
          (names.empty() ? " (it defines none)" : " (its materials: " + names + ")"));
    }
    Material& m = *it;
    if (m.ke != glm::vec3(0.0f)) {
      if (replaced->empty()) *replacedWhere = m.where;
      replaced->push_back(m.name + " (Ke " + Num(m.ke.x) + " " + Num(m.ke.y) + " " + Num(m.ke.z) +
                          ")");
    }
    m.ke = e.fromKa ? m.ka : e.ke;
  }
  return Status::Ok();
}

Status Loader::DroppedEmitters(const std::vector<uint8_t>& used) const {
  const std::vector<Material>& materials = *materials_;
  auto emits = [&](size_t m) {
    const glm::vec3& ke = materials[m].ke;
    return ke.x > 0.0f || ke.y > 0.0f || ke.z > 0.0f;
  };
  for (size_t m = 0; m < materials.size(); ++m)
    if (m < used.size() && used[m] && emits(m)) return Status::Ok();
  for (const auto& [m, at] : droppedFace_)
    if (m < materials.size() && emits(m))
      return Status::At(path_, at.first,
                        "no emitter left: this face of emitting material '" + materials[m].name +
                            "' " + at.second +
                            " and was dropped, and no other face emits (fix the face, or --emit "
                            "NAME=R,G,B makes another material emit)");
  return Status::Ok();
}

Status Loader::ApplyEmit() {
  return ApplyEmitOverrides(path_, options_.emit, materials_, &replacedKe_, &replacedWhere_);
}

std::string Loader::UndefinedMaterials() const {
  std::string names;
  for (const std::string& n : undefinedMaterials_) names += (names.empty() ? "" : ", ") + Quote(n);
  return names;
}

std::vector<std::string> Loader::Warnings(const std::vector<uint8_t>& used) const {
  std::vector<std::string> w = warnings_;
  auto at = [&](int line) { return path_ + ":" + std::to_string(line) + ": warning: "; };
  if (!ignoredKeys_.empty()) {
    std::string keys;
    for (const std::string& k : ignoredKeys_) keys += (keys.empty() ? "'" : ", '") + k + "'";
    w.push_back(ignoredWhere_ + ": warning: ignoring MTL key" +
                (ignoredKeys_.size() > 1 ? "s " : " ") + keys +
                (ignoredKeys_.size() > 1 ? " (first here)" : ""));
  }
  if (notMtlLines_ > 0)
    w.push_back(notMtlWhere_ + ": warning: " + std::to_string(notMtlLines_) +
                (notMtlLines_ > 1 ? " lines are" : " line is") +
                " not MTL statements: ignored (first here; is it an MTL file?)");
  // Specular or transparent materials that faces use, in material order.
  const std::vector<Material>& materials = *materials_;
  std::string named, where;
  for (size_t i = 0; i < materials.size(); ++i) {
    std::string why = used[i] ? NotDiffuse(finishes_[i]) : "";
    if (why.empty()) continue;
    if (named.empty()) where = materials[i].where;
    named += (named.empty() ? "" : ", ") + materials[i].name + " (" + why + ")";
  }
  if (!named.empty())
    w.push_back(where +
                ": warning: specular materials rendered as diffuse with their Kd: " + named);
  if (!replacedKe_.empty()) {
    std::string list;
    for (const std::string& r : replacedKe_) list += (list.empty() ? "" : ", ") + r;
    w.push_back(replacedWhere_ + ": warning: --emit replaces the MTL's Ke of " + list);
  }
  if (!undefinedMaterials_.empty()) {
    const std::string names = UndefinedMaterials();
    w.push_back(undefinedWhere_ +
                ": warning: " + Count(undefinedMaterials_.size(), "material", "materials") +
                " that no MTL defines, given the default grey (Kd 0.5; --emit NAME=R,G,B makes "
                "one an emitter; first here): " +
                names);
  }
  const FaceTally& t = triangulated_;
  if (t.faces)
    w.push_back(at(t.line) + Count(t.faces, "non-planar face", "non-planar faces") +
                " triangulated (first here; up to " + Num(t.off) + " off " +
                (t.faces == 1 ? "its" : "their") + " plane)");
  if (cornersRemoved_.faces)
    w.push_back(at(cornersRemoved_.line) +
                Count(cornersRemoved_.corners, "repeated or collinear corner",
                      "repeated or collinear corners") +
                " removed from " + Count(cornersRemoved_.faces, "face", "faces") + " (first here)");
  if (degenerate_.faces)
    w.push_back(at(degenerate_.line) +
                Count(degenerate_.faces, "degenerate face", "degenerate faces") +
                " dropped (zero area: repeated or collinear vertices; first here)");
  if (selfIntersecting_.faces)
    w.push_back(
        at(selfIntersecting_.line) +
        Count(selfIntersecting_.faces, "self-intersecting face", "self-intersecting faces") +
        " dropped (first here)");
  return w;
}

Status Loader::LoadMtl(const std::string& path, const std::string& objPath, int objLine) {
  if (!loadedMtls_.insert(path).second) return Status::Ok();
  std::string text;
  std::string err = readMtl_(path, &text);
  if (!err.empty()) {
    // Published without its MTL (no such file; one that is there but
    // cannot be read stays an error): the materials it would define get
    // the default grey where faces use them (one more warning names them).
    if (options_.strict || os::Exists(path.c_str()))
      return Status::At(objPath, objLine, "MTL file '" + path + "': " + err);
    Warn(objPath, objLine,
         "MTL file '" + path +
             "' not found: the materials it defines get the default grey "
             "(Kd 0.5)");
    return Status::Ok();
  }
  TextLines lines(text);
  std::vector<Material>& materials = *materials_;
  bool haveMaterial = false;
  Statement statement;
  while (lines.NextStatement(&statement)) {
    const auto& [lineText, line, t, key, args] = statement;
    if (key == "newmtl") {
      if (args != 1) return Status::At(path, line, "'newmtl' needs 1 name, got " + Str(args));
      std::string where = path + ":" + std::to_string(line);
      auto [it, added] = materialIndex_.emplace(
          t[1], std::make_pair(static_cast<uint32_t>(materials.size()), where));
      if (!added)
        return Status::At(
            path, line,
            "duplicate material " + Quote(t[1]) + " (first at " + it->second.second + ")");
      Material m;
      m.name = t[1];
      m.where = where;
      materials.push_back(std::move(m));
      finishes_.emplace_back();
      haveMaterial = true;
    } else if (key == "Ka") {
      if (!haveMaterial) return Status::At(path, line, "'Ka' before any 'newmtl'");
      if (args != 3) return Status::At(path, line, "'Ka' needs 3 numbers, got " + Str(args));
      float rgb[3];
      err = ParseFloats(t, 1, 3, rgb);
      if (!err.empty()) return Status::At(path, line, err);
      for (float x : rgb)
        if (x < 0.0f) return Status::At(path, line, "Ka must be >= 0, got " + Num(x));
      materials.back().ka = glm::vec3(rgb[0], rgb[1], rgb[2]);
    } else if (key == "map_Kd") {
      if (!haveMaterial) return Status::At(path, line, "'map_Kd' before any 'newmtl'");
      if (args == 0) return Status::At(path, line, "'map_Kd' needs a file name");
      // Options (-bm 1, -s 1 1 1, ...) come before the name; they are not
      // applied, and said so once. The name is the rest of the line, spaces
      // and all (Blender writes 'map_Kd my tex.png' unquoted).
      bool options = false;
      const std::string name = MapName(lineText, t, &options);
      if (name.empty()) return Status::At(path, line, "'map_Kd' needs a file name");
      if (options) Warn(path, line, "ignoring map_Kd options");
      materials.back().mapKd = Beside(path, name);
      materials.back().mapKdWhere = path + ":" + std::to_string(line);
    } else if (key == "Kd" || key == "Ke") {
      if (!haveMaterial) return Status::At(path, line, Quote(key) + " before any 'newmtl'");
      if (args != 3)
        return Status::At(path, line, Quote(key) + " needs 3 numbers, got " + Str(args));
      float rgb[3];
      err = ParseFloats(t, 1, 3, rgb);
      if (!err.empty()) return Status::At(path, line, err);
      for (float x : rgb) {
        if (key == "Kd" && !(x >= 0.0f && x <= 1.0f))
          return Status::At(path, line, "Kd must be in [0, 1], got " + Num(x));
        if (key == "Ke" && x < 0.0f)
          return Status::At(path, line, "Ke must be >= 0, got " + Num(x));
      }
      (key == "Kd" ? materials.back().kd : materials.back().ke) = glm::vec3(rgb[0], rgb[1], rgb[2]);
    } else if (IsSilentMtlKey(key)) {
      // Read only to name specular or transparent materials after loading.
      if (!haveMaterial) continue;
      Finish& f = finishes_.back();
      double v[3];
      // Models are 0 to 10: a number beyond them is none (as if not given),
      // never converted to int (outside its range that is undefined).
      if (key == "illum" && LenientFloats(t, 1, v))
        f.illum = v[0] >= 0.0 && v[0] < 11.0 ? static_cast<int>(v[0]) : -1;
      if (key == "Ks" && LenientFloats(t, 3, v)) f.ks = v[0] > 0.0 || v[1] > 0.0 || v[2] > 0.0;
      if (key == "Tf" && LenientFloats(t, 3, v)) f.tf = v[0] < 1.0 || v[1] < 1.0 || v[2] < 1.0;
      if (key == "d" && LenientFloats(t, 1, v)) f.d = v[0];
      if (key == "Tr" && LenientFloats(t, 1, v)) f.d = 1.0 - v[0];
    } else if (!LooksLikeKey(key)) {
      if (notMtlLines_++ == 0) notMtlWhere_ = path + ":" + std::to_string(line);
    } else {
      if (ignoredKeys_.empty()) ignoredWhere_ = path + ":" + std::to_string(line);
      if (std::find(ignoredKeys_.begin(), ignoredKeys_.end(), key) == ignoredKeys_.end())
        ignoredKeys_.push_back(key);
    }
  }
  return Status::Ok();
}

}  // namespace vismask::objload
