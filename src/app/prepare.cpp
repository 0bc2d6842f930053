// Init's scene work (run.h): the OBJ read in passes (scene_stream.h), cut into environments of
// which this rank keeps its own (their meshing and init's peak: src/app/prepare_envs.cpp).
#include "run.h"

namespace vismask::run {

Status CountScene(const Options& o, Prepared* p) {
  const double t0 = os::Seconds();
  Status s = CountObj(o.scene, &p->info);
  p->clock.Done("reading the scene", os::Seconds() - t0);
  return s;
}

std::string InitStageLine(const char* what, double seconds, const std::string& detail) {
  if (!(seconds > 1.0)) return "";
  char line[256];
  std::snprintf(line, sizeof line, "vismask: init: %s took %.1f s%s%s%s", what, seconds,
                detail.empty() ? "" : " (", detail.c_str(), detail.empty() ? "" : ")");
  return line;
}

void InitClock::Done(const char* what, double seconds, const std::string& detail) {
  auto it =
      std::find_if(stages.begin(), stages.end(), [&](const auto& s) { return s.first == what; });
  if (it == stages.end())
    stages.emplace_back(what, seconds);
  else
    it->second += seconds;
  const std::string line = InitStageLine(what, seconds, detail);
  if (report && !line.empty()) os::PrintErr("%s\n", line.c_str());
}

namespace {

// The heap a polygon holds (its vectors, with malloc's 16 bytes each).
uint64_t PolygonBytes(const Polygon& poly) {
  return sizeof(Polygon) + 16 * 3 + poly.corners.capacity() * sizeof(glm::vec3) +
         poly.uv.capacity() * sizeof(glm::vec2) + poly.vn.capacity() * sizeof(glm::vec3);
}

// Whether material m emits once --emit has been applied (pass 1 sees the
// MTL's Ke; ScanObj applies --emit at its end).
glm::vec3 KeAfterOverrides(const Material& m, const LoadOptions& load) {
  glm::vec3 ke = m.ke;
  for (const EmitOverride& e : load.emit)
    if (e.material == m.name) ke = e.fromKa ? m.ka : e.ke;
  return ke;
}

bool EmitsAfterOverrides(const Material& m, const LoadOptions& load) {
  const glm::vec3 ke = KeAfterOverrides(m, load);
  return ke.x > 0.0f || ke.y > 0.0f || ke.z > 0.0f;
}

// Keeps *lights the kViewLights most powerful emitting polygons, by power
// (ties to the one seen first).
void KeepBrightest(const Polygon& poly, glm::vec3 ke, std::vector<ViewLight>* lights) {
  ViewLight l;
  for (const glm::vec3& c : poly.corners) l.centre += c;
  l.centre /= static_cast<float>(poly.corners.size());
  l.normal = poly.normal;
  l.power = (double(ke.x) + ke.y + ke.z) / 3.0 * poly.area;
  auto at = std::find_if(lights->begin(), lights->end(),
                         [&](const ViewLight& m) { return l.power > m.power; });
  if (at - lights->begin() < kViewLights) lights->insert(at, l);
  if (lights->size() > static_cast<size_t>(kViewLights)) lights->pop_back();
}

bool Emits(const Material& m) {
  return m.ke.x > 0.0f || m.ke.y > 0.0f || m.ke.z > 0.0f;
}

// A piece of the scene this rank keeps: its environment and its polygon.
struct OwnPiece {
  uint32_t env, source;  // source: in p->scene.polygons
  Polygon polygon;
};

// Pass 1: parse, mend and check; keep the emitting polygons for the
// emitter check (rank 0), nothing else of the polygons. Then the textures,
// and the scene's materials, bounds and camera.
// With chooseSide, *lights gets the brightest emitting polygons
// (kViewLights, by power; ties to the first in the file), on every rank:
// the inside views' light estimate.
Status ReadScene(const Options& o, Prepared* p, bool root, bool chooseSide,
                 std::vector<std::pair<uint32_t, Polygon>>* emitters,
                 std::vector<ViewLight>* lights) {
  SceneInfo& info = p->info;
  size_t numEmitters = 0;
  double t0 = os::Seconds();
  // Each polygon, as mended, with its corners, area and material: where a
  // work-balanced split (an accumulator fed one polygon at a time) takes
  // them, its planes then set p->grid before pass 2 clips with it.
  Status s = ScanObj(
      o.scene, o.load,
      [&](uint32_t i, const Polygon& poly) {
        if (!EmitsAfterOverrides(info.materials[poly.material], o.load)) return;
        ++numEmitters;
        if (chooseSide)
          KeepBrightest(poly, KeAfterOverrides(info.materials[poly.material], o.load), lights);
        if (root) emitters->emplace_back(i, poly);
      },
      &info);
  if (!s.ok()) return s;
  p->clock.Done("reading the scene", os::Seconds() - t0,
                std::to_string(info.numPolygons) + " polygons");
  // Rank 0's emitter check (the same figure on every rank, for footprint).
  p->checkBytes =
      EmitterCheck::HeapBytes(numEmitters, std::min<size_t>(kEmitterCheckChunk, info.numPolygons)) +
      numEmitters * 256;
  // Every rank prints the loader's warnings, as LoadScene did.
  if (!o.initAgain)
    for (const std::string& w : info.warnings) os::PrintErr("%s\n", w.c_str());
  // The textures are decoded within what the budget leaves beside what
  // init holds already (at least a byte: a budget already spent refuses any).
  const uint64_t heldNow = p->held + kInitBaseBytes;
  const uint64_t textureBudget =
      p->budget == 0 ? 0 : (p->budget > heldNow ? p->budget - heldNow : 1);
  t0 = os::Seconds();
  s = LoadMaterialTextures(o.scene, &info.materials, info.usedMaterials, info.noUvLine,
                           &p->textures, textureBudget, o.load.strict);
  if (!s.ok()) return s;
  p->clock.Done("textures", os::Seconds() - t0,
                std::to_string(p->textures.images.size()) + " images decoded");
  for (const TextureImage& t : p->textures.images)
    p->textureBytes += uint64_t{t.width} * t.height * 4 + t.pyramid.texels.size() * sizeof(float);
  // --sky FILE.hdr: the map, within what the budget leaves beside the
  // textures; every copy of the options made from here on shares it.
  p->outside = o.outside;
  if (!p->outside.skyFile.empty()) {
    auto map = std::make_shared<SkyMap>();
    const uint64_t left = textureBudget == 0                ? 0
                          : textureBudget > p->textureBytes ? textureBudget - p->textureBytes
                                                            : 1;
    s = ReadSkyMap(p->outside.skyFile, map.get(), left);
    if (!s.ok()) return s;
    p->textureBytes += map->staged.size() * sizeof(float);
    p->outside.skyMap = std::move(map);
  }
  p->scene.objPath = o.scene;
  p->scene.materials = info.materials;
  p->scene.bounds = info.bounds;
  p->scene.camera = info.camera;
  return Status::Ok();
}

// The patch size and the environments' grid: uniform, or --envs auto's.
Status PlanGrid(const Options& o, Prepared* p) {
  const SceneInfo& info = p->info;
  glm::vec3 extent = info.bounds.hi - info.bounds.lo;
  float maxExtent = std::fmax(extent.x, std::fmax(extent.y, extent.z));
  p->patchSize = o.patchSize > 0.0f ? o.patchSize : maxExtent / kAutoPatchDivisions;
  const float r = maxExtent / kAutoPatchDivisions / p->patchSize;  // (env_options.h)
  p->envOptions.filterPatchScale = std::isfinite(r) && r > 0.0f ? double(r) * r : 1.0;
  p->tolerance = 1e-5f * maxExtent;
  p->smooth = o.smooth;
  for (int a = 0; a < 3; ++a) p->grid.n[a] = o.envs[a];
  p->grid.box = info.bounds;
  if (!o.envsAuto) return Status::Ok();
  // --envs auto:N: the shape with the least cut area, planes where the
  // estimated patches divide evenly. Pass 1b feeds the splitter polygon
  // by polygon in file order (the weights need the patch size, known
  // only once pass 1 has the bounds); it holds kBins weights an axis.
  if (!ChooseEnvShape(o.envsAutoCount, extent, p->grid.n))
    return Status::Error("vismask: --envs: auto:" + std::to_string(o.envsAutoCount) +
                         ": no grid of that many environments fits the scene (each axis "
                         "1..64, none split where the scene is flat)");
  WorkSplitter splitter;
  Status s = StreamObj(info, o.load, [&](uint32_t, const Polygon& poly) {
    const int n = static_cast<int>(poly.corners.size());
    splitter.Add(poly.corners.data(), n, poly.area,
                 EstimatedPatches(poly.corners.data(), n, p->patchSize));
  });
  if (!s.ok()) return s;
  splitter.Planes(&p->grid);
  return Status::Ok();
}

// Pass 2: every polygon clipped into the environments; this rank keeps
// the pieces of its own and counts the patches of every environment (ids
// are global, environment-major). The camera's side and the emitter
// check take their polygons here too.
struct CutPass {
  CutPass(const Options& options, Prepared* prepared, uint32_t firstEnv, uint32_t endEnv,
          uint64_t held)
      : o(options), p(prepared), first(firstEnv), end(endEnv), passBytes(held) {}

  const Options& o;
  Prepared* p;
  uint32_t first, end;
  uint64_t passBytes;  // what init holds before the pieces
  std::unique_ptr<ViewProbe> probe;
  std::unique_ptr<EmitterCheck> check;
  std::vector<OwnPiece> own;
  std::vector<std::pair<uint32_t, double>>
      emitted;  // (environment, emitted power) per emitting piece
  Status failed;
  Scene one;
  Partition cut;
  uint64_t pieceTotal = 0;
  // The scene's patches as the mesher will make them, about (summed over
  // whole polygons in file order, the same on every rank): the size of an
  // automatic --round-work.
  double estimated = 0.0;
  // Faces the mesher cuts in strips (mesh.h): one warning line, on rank 0.
  size_t stripFaces = 0;
  int stripLine = 0;
  size_t stripCorners = 0;
  double stripChange = 0.0;  // the largest relative change of area

  void Add(uint32_t i, const Polygon& poly, bool root) {
    const SceneInfo& info = p->info;
    estimated +=
        EstimatedPatches(poly.corners.data(), static_cast<int>(poly.corners.size()), p->patchSize);
    bool strips = false;
    double change = 0.0;
    if (root && poly.corners.size() > 4 &&
        MeshesInStrips(o.scene, poly, p->patchSize, &strips, &change).ok() && strips) {
      if (stripFaces++ == 0) stripLine = poly.line, stripCorners = poly.corners.size();
      if (std::fabs(change) > std::fabs(stripChange)) stripChange = change;
    }
    if (probe)
      probe->Add(i, poly,
                 p->twins.Twins(poly.material,
                                EmitsAfterOverrides(info.materials[poly.material], o.load)));
    if (check) check->Add(i, poly);
    if (!failed.ok()) return;
    one.polygons.assign(1, poly);
    Status st = PartitionScene(one, p->grid, &cut);
    if (!st.ok()) {
      failed = st;
      return;
    }
    Pieces(i, poly);
  }

  // The pieces of polygon i (cut): counted for every environment, kept for
  // this rank's.
  void Pieces(uint32_t i, const Polygon& poly) {
    const Material& mat = p->info.materials[poly.material];
    uint32_t source = kNoPatch;
    for (size_t k = 0; k < cut.scene.polygons.size(); ++k) {
      const uint32_t e = cut.env[k];
      const Polygon& piece = cut.scene.polygons[k];
      double patches = 0.0;
      Status st = CountPolygonPatches(o.scene, piece, p->patchSize, &patches, &p->envVertices[e]);
      if (!st.ok()) {
        failed = Status::Error("vismask: --patch-size: " + st.ToString());
        return;
      }
      p->envPatches[e] += patches;
      if (e < first) ++p->pieceBase;
      if (p->twins.Twins(poly.material, Emits(mat))) p->envTwins[e] += patches;
      // An emitter whose twin emits (--two-sided-emitters, a doubleSided
      // glTF material) sends as much again from its back (x2 is exact).
      if (Emits(mat))
        emitted.emplace_back(e, (static_cast<double>(mat.ke.x) + mat.ke.y + mat.ke.z) * piece.area *
                                    (p->twins.TwinEmits(poly.material, true) ? 2.0 : 1.0));
      if (e < first || e >= end) continue;
      if (source == kNoPatch) {
        source = static_cast<uint32_t>(p->scene.polygons.size());
        p->scene.polygons.push_back(poly);
        p->sourceIds.push_back(i);
        p->envPieceBytes[e] += PolygonBytes(poly) + sizeof(uint32_t);
      }
      // The piece twice: in the list made here and in the partition.
      p->envPieceBytes[e] += 2 * (PolygonBytes(piece) + 3 * sizeof(uint32_t));
      pieceTotal += 2 * (PolygonBytes(piece) + 3 * sizeof(uint32_t)) + PolygonBytes(poly);
      if (p->budget > 0 && passBytes + pieceTotal > p->budget) {
        if (p->overBudget)
          p->overBudget(passBytes + pieceTotal,
                        "to hold its pieces of the scene (and more to come)");
        failed = Status::Error("");
        return;
      }
      own.push_back({e, source, piece});
    }
  }

  // The warning for the faces meshed in strips ("" if none).
  void StripWarning(std::vector<std::string>* warnings) const {
    if (stripFaces == 0) return;
    char text[512];
    std::snprintf(text, sizeof text,
                  "%s:%d: warning: %zu convex face%s of many corners (here %zu) meshed in strips "
                  "whose outline passes within 1/64 of the patch size of the corners it skips, "
                  "not in ear-clipped slivers (their patches would not follow the area); area "
                  "changed by at most %.2g%%",
                  o.scene.c_str(), stripLine, stripFaces, stripFaces == 1 ? "" : "s", stripCorners,
                  100.0 * std::fabs(stripChange));
    warnings->push_back(text);
  }
};

// This rank's pieces, by environment (within one, in source order), into
// p->part and p->pieces.
void KeepPieces(const Options& o, Prepared* p, uint32_t total, std::vector<OwnPiece>* own) {
  std::stable_sort(own->begin(), own->end(),
                   [](const OwnPiece& a, const OwnPiece& b) { return a.env < b.env; });
  p->part.grid = p->grid;
  p->part.scene.objPath = o.scene;
  p->part.scene.materials = p->info.materials;
  p->part.scene.bounds = p->info.bounds;
  p->pieces.assign(total, {});
  for (OwnPiece& piece : *own) {
    p->pieces[piece.env].push_back(static_cast<uint32_t>(p->part.scene.polygons.size()));
    p->part.scene.polygons.push_back(std::move(piece.polygon));
    p->part.env.push_back(piece.env);
    p->part.source.push_back(piece.source);
  }
  own->clear();
  own->shrink_to_fit();
}

// The environments' options: rays, masks, elements, a ray's power, packets.
void SetEnvOptions(const Options& o, double power, uint32_t outsideTiles, Prepared* p) {
  const SceneInfo& info = p->info;
  const glm::vec3 extent = info.bounds.hi - info.bounds.lo;
  EnvOptions& e = p->envOptions;
  // 1e-6 of the scene's size, and at least 8 float steps of its largest
  // coordinate, so that the lift survives rounding far from the origin.
  glm::vec3 mag = glm::max(glm::abs(info.bounds.lo), glm::abs(info.bounds.hi));
  float largest = std::fmax(mag.x, std::fmax(mag.y, mag.z));
  e.rayEpsilon = std::fmax(1e-6f * glm::length(extent),
                           8.0f * std::numeric_limits<float>::epsilon() * largest);
  e.rays = RayCap(o);
  e.sobol = o.sobol;
  e.originsByPower = o.originsByPower;
  e.patchSequence = o.patchSequence;
  if (o.rayAlloc == Options::RayAlloc::kPower) {
    e.rayQuantum = power / static_cast<double>(o.emittedRays);
    e.minRays = o.minRays;
  }
  e.seed = o.seed;
  e.outside = p->outside;
  e.outsideTiles = outsideTiles;
  e.maskMethod = o.maskMethod;
  e.maskRes = o.maskRes;
  e.subGridRefs = o.subGrids;
  e.roundShots = o.roundShots;
  e.queueCapacity = o.queue;
  e.maskCacheBytes = uint64_t{o.maskCacheKiB} << 10;
  e.centreRays = o.centreRays;
  e.elements.perPatch = o.elementsPerPatch;
  e.elements.maxDepth = o.elementDepth;
  e.elements.threshold = o.elementSpread;
  e.elements.chi2 = o.elementChi2;
  e.indirectFilter = o.indirectFilter;
  e.directSamples = o.directSamples > 0 ? static_cast<uint32_t>(o.directSamples) : 0;
  e.emissionRays = SolveEmissionRays(o);
  e.gatherForeign = p->grid.count() > 1 && GathersForeign(o);
  p->packetBytes =
      p->grid.count() > 1 ? PacketBytes(MaskShapeOf(o.maskMethod, o.maskRes, RayCap(o))) : 0;
}

}  // namespace

Status PrepareScene(const Options& o, Prepared* p, uint32_t first, uint32_t end, bool root) {
  SceneInfo& info = p->info;
  const bool chooseSide = !o.hasCamera && !o.hasView;
  std::vector<std::pair<uint32_t, Polygon>> emitters;
  std::vector<ViewLight> lights;
  Status s = ReadScene(o, p, root, chooseSide, &emitters, &lights);
  if (!s.ok()) return s;
  s = PlanGrid(o, p);
  if (!s.ok()) return s;
  p->first = first;
  p->end = end;
  const uint32_t total = static_cast<uint32_t>(p->grid.count());
  p->envPatches.assign(total, 0.0);
  p->envTwins.assign(total, 0.0);
  p->envVertices.assign(total, 0.0);
  p->envPieceBytes.assign(total, 0);
  p->twins.all = o.twoSided;
  p->twins.emitters = o.twoSidedEmitters;
  // glTF's doubleSided materials: their patches get twins of their own.
  for (const Material& m : info.materials)
    if (m.twoSided) p->twins.materials.assign(info.materials.size(), 0);
  for (size_t m = 0; m < p->twins.materials.size(); ++m)
    p->twins.materials[m] = info.materials[m].twoSided;

  // Before pass 2 allocates: the parser's arrays, the camera's probe and
  // the emitter check against the budget; then the pieces as they come.
  const uint64_t passBytes = p->held + kInitBaseBytes + info.ParserBytes() +
                             ViewProbe::HeapBytes(p->outside) + (root ? p->checkBytes : 0);
  if (p->budget > 0 && passBytes > p->budget) {
    if (p->overBudget)
      p->overBudget(passBytes,
                    "to read the scene (the vertex arrays, the camera probe, the emitter check)");
    return Status::Error("");
  }
  CutPass pass(o, p, first, end, passBytes);
  if (chooseSide && !info.camera.has) {
    pass.probe = std::make_unique<ViewProbe>(info.bounds);
    pass.probe->SetLights(lights);
    pass.probe->SetOutside(p->outside);
  }
  if (root) {
    pass.check =
        std::make_unique<EmitterCheck>(info.bounds, info.materials, emitters, kEmitterCheckChunk);
  }
  emitters.clear();
  emitters.shrink_to_fit();
  pass.one.objPath = o.scene;
  pass.one.bounds = info.bounds;
  double t0 = os::Seconds();
  s = StreamObj(info, o.load, [&](uint32_t i, const Polygon& poly) { pass.Add(i, poly, root); });
  if (!s.ok()) return s;
  if (!pass.failed.ok()) return pass.failed;
  if (o.roundWorkAuto)
    p->roundWork = AutoRoundWork(o, pass.estimated, o.envs[0] * o.envs[1] * o.envs[2]);
  p->clock.Done("cutting the scene into environments", os::Seconds() - t0);
  if (pass.probe) {
    p->view = pass.probe->Choose();
    p->side = p->view.side;
    p->viewProbed = true;
  }
  t0 = os::Seconds();
  if (pass.check)
    p->emitterWarnings =
        EmitterWarnings(pass.check->Finish(), o.scene, info.materials, info.bounds);
  pass.StripWarning(&p->emitterWarnings);
  p->clock.Done("emitter check", os::Seconds() - t0);
  pass.probe.reset();
  pass.check.reset();
  s = CheckEnvSizes(*p, total);
  if (!s.ok()) return s;
  for (uint32_t e = 0; e < total; ++e) {
    p->envPatches[e] += p->envTwins[e];
    // A twin's lattice is a copy of its original's (at most all of them).
    if (p->envTwins[e] > 0.0) p->envVertices[e] *= 2.0;
    if (e < first) p->idBase += static_cast<uint32_t>(p->envPatches[e]);
  }
  // The power a ray carries: the emitted power (channels summed, in piece
  // order by environment, the same on every rank) over --emitted-rays.
  std::stable_sort(pass.emitted.begin(), pass.emitted.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  double power = 0.0;
  for (const auto& [e, w] : pass.emitted) power += w;
  // --sky, --sun: one shooter a face of an environment for Method R, whose
  // rays carry their own routes; tiles for the hemisphere masks, which judge
  // a shooter's rays by its centre (docs/DESIGN.md, "Light from outside").
  const uint32_t outsideTiles = o.maskMethod == MaskMethod::kR ? 1 : kMaxOutsideTiles;
  power += OutsidePower(p->grid, p->outside, outsideTiles);
  KeepPieces(o, p, total, &pass.own);
  SetEnvOptions(o, power, outsideTiles, p);
  return Status::Ok();
}

}  // namespace vismask::run
