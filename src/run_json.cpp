// run.json: the options, the solve, the memory and the error, written by
// rank 0 without allocating (run.h).
#include "run.h"

namespace vismask::run {

// One character of a JSON string as it is written inside the quotes: into
// out (at least 7 bytes); returns the length.
size_t JsonChar(char c, char* out) {
  unsigned char ch = static_cast<unsigned char>(c);
  if (ch == '"' || ch == '\\') {
    out[0] = '\\';
    out[1] = c;
    return 2;
  }
  if (ch < 0x20) return static_cast<size_t>(std::snprintf(out, 7, "\\u%04x", ch));
  out[0] = c;
  return 1;
}

void JsonString(TextWriter* w, const char* s) {
  w->Write("\"", 1);
  char esc[8];
  for (; *s; ++s) w->Write(esc, JsonChar(*s, esc));
  w->Write("\"", 1);
}

// The same, for init-time text on the heap (footprint --json).
std::string JsonQuoted(const std::string& s) {
  std::string q = "\"";
  char esc[8];
  for (char c : s) q.append(esc, JsonChar(c, esc));
  return q + "\"";
}

void JsonTriple(TextWriter* w, const char* name, const double v[3], bool comma) {
  w->Printf("    \"%s\": [%.17g, %.17g, %.17g]%s\n", name, v[0], v[1], v[2], comma ? "," : "");
}

void WriteRunJson(RunState* r, const SolveResult& res, float exposure, double outputSeconds) {
  const Options& o = r->options;
  TextWriter w(&r->files[kRunJson], r->textBuffer);
  w.Printf("{\n  \"vismask_version\": 1,\n  \"command\": \"render\",\n  \"scene\": ");
  JsonString(&w, o.scene.c_str());
  w.Printf(",\n  \"out\": ");
  JsonString(&w, o.outDir.c_str());
  w.Printf(",\n  \"options\": {\n");
  w.Printf("    \"patch_size\": %.9g,\n    \"rays\": %u,\n    \"seed\": %llu,\n", r->patchSize,
           RayCap(o), static_cast<unsigned long long>(o.seed));
  w.Printf(
      "    \"ray_alloc\": \"%s\",\n    \"emitted_rays\": %llu,\n    \"min_rays\": %u,\n"
      "    \"max_rays\": %u,\n    \"sampler\": \"%s\",\n    \"ray_budget\": %llu,\n",
      o.rayAlloc == Options::RayAlloc::kPower ? "power" : "fixed",
      static_cast<unsigned long long>(o.emittedRays), o.minRays, o.maxRays,
      o.sobol ? "sobol" : "random", static_cast<unsigned long long>(o.rayBudget));
  w.Printf("    \"stop_unshot\": %.17g,\n    \"max_shots\": %llu,\n    \"max_seconds\": %.17g,\n",
           o.stopUnshot, static_cast<unsigned long long>(o.maxShots), o.maxSeconds);
  w.Printf("    \"width\": %d,\n    \"height\": %d,\n    \"exposure\": %.9g,\n", o.width, o.height,
           exposure);
  w.Printf("    \"exposure_auto\": %s,\n", o.hasExposure ? "false" : "true");
  const Camera& c = r->camera;  // as --camera takes it: eye, target, up, fovy
  w.Printf("    \"camera\": [%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g],\n",
           c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z,
           c.fovyDeg);
  // The side the camera frames (null with --camera), and whether it was chosen (no --view).
  if (r->hasSide)
    w.Printf("    \"view\": \"%s\",\n", ViewSideName(r->side));
  else
    w.Printf("    \"view\": null,\n");
  w.Printf("    \"view_auto\": %s,\n", r->sideChosen ? "true" : "false");
  w.Printf("    \"camera_from_scene\": %s,\n", r->cameraFromScene ? "true" : "false");
  w.Printf("    \"envs\": [%d, %d, %d],\n    \"mask_method\": \"%s\",\n", o.envs[0], o.envs[1],
           o.envs[2], MaskMethodName(o.maskMethod));
  w.Printf(
      "    \"mask_res\": %u,\n    \"centre_rays\": \"%s\",\n    \"round_shots\": %u,\n    "
      "\"round_work\": %llu,\n    \"queue\": "
      "%u,\n",
      o.maskRes, CentreChoiceName(o.centreRays), o.roundShots,
      static_cast<unsigned long long>(o.roundWork), o.queue);
  // --envs auto:N (null: --envs NXxNYxNZ) and the planes the grid was cut
  // at, per axis from the scene box's low to its high side.
  if (o.envsAuto)
    w.Printf("    \"envs_auto\": %d,\n", o.envsAutoCount);
  else
    w.Printf("    \"envs_auto\": null,\n");
  w.Printf("    \"env_planes\": [");
  for (int a = 0; a < 3; ++a) {
    w.Printf("%s[", a ? ", " : "");
    for (int k = 0; k <= r->envGrid.n[a]; ++k)
      w.Printf("%s%.9g", k ? ", " : "", r->envGrid.Plane(a, k));
    w.Printf("]");
  }
  w.Printf("],\n");
  w.Printf("    \"rank_timeout\": %.17g,\n", o.rankTimeout);
  w.Printf("    \"reference\": ");
  if (o.reference.empty())
    w.Printf("null");
  else
    JsonString(&w, o.reference.c_str());
  w.Printf(",\n    \"exclude\": ");
  if (o.exclude.empty())
    w.Printf("null");
  else
    JsonString(&w, o.exclude.c_str());
  w.Printf(",\n    \"error_every\": %llu,\n", static_cast<unsigned long long>(o.errorEvery));
  w.Printf("    \"correct_unshot\": %s,\n", o.correctUnshot ? "true" : "false");
  w.Printf("    \"aa\": %s,\n", o.aa ? "true" : "false");
  w.Printf("    \"smooth\": %s,\n    \"crease\": %.9g,\n", o.smooth ? "true" : "false",
           o.creaseDeg);
  // Only when on, so that a one-sided run.json is what it was before them.
  if (o.twoSided || o.twoSidedEmitters)
    w.Printf("    \"two_sided\": %s,\n    \"two_sided_emitters\": %s,\n",
             o.twoSided ? "true" : "false", o.twoSidedEmitters ? "true" : "false");
  // Only with --export, so that a run.json without it is what it was.
  if (!o.exportPath.empty()) {
    w.Printf("    \"export\": ");
    JsonString(&w, o.exportPath.c_str());
    w.Printf(",\n");
  }
  w.Printf("    \"stop_error\": %.17g\n  },\n", o.stopError);
  size_t patches = 0, vertices = 0, cells = 0, refs = 0;
  for (const EnvSummary& e : r->summary) {
    patches += e.patches;
    vertices += e.vertices;
    cells += e.gridCells;
    refs += e.gridRefs;
  }
  w.Printf("  \"counts\": {\n    \"polygons\": %zu,\n    \"patches\": %zu,\n", r->numPolygons,
           patches);
  if (o.twoSided || o.twoSidedEmitters)  // of `patches`, the reversed copies
    w.Printf("    \"twin_patches\": %llu,\n", static_cast<unsigned long long>(r->numTwins));
  w.Printf("    \"vertices\": %zu,\n    \"environments\": %zu,\n", vertices, r->summary.size());
  w.Printf("    \"ranks\": %d,\n    \"transport\": \"%s\",\n", r->transport->size(),
           r->transport->name());
  w.Printf("    \"grid_cells\": %zu,\n    \"grid_refs\": %zu", cells, refs);
  if (!o.exportPath.empty())  // the .glb: its vertices, triangles and bytes
    w.Printf(",\n    \"export\": {\"vertices\": %llu, \"triangles\": %llu, \"bytes\": %llu}",
             static_cast<unsigned long long>(r->exportWhole.vertices),
             static_cast<unsigned long long>(r->exportWhole.triangles),
             static_cast<unsigned long long>(r->exportBytes));
  w.Printf("\n  },\n");
  EnvStats st;
  for (const EnvSummary& e : r->summary) {
    st.shots += e.stats.shots;
    st.foreignShots += e.stats.foreignShots;
    st.rays += e.stats.rays;
    st.maskRays += e.stats.maskRays;
    st.maskRaysByPatch += e.stats.maskRaysByPatch;
    st.maskNoExit += e.stats.maskNoExit;
    st.readShots += e.stats.readShots;
    st.readRays += e.stats.readRays;
    st.hits += e.stats.hits;
    st.packetsSent += e.stats.packetsSent;
  }
  uint32_t packetBytes = r->exchange.packetBytes;  // 0 with one environment
  w.Printf("  \"result\": {\n    \"stop_reason\": \"%s\",\n    \"rounds\": %llu,\n",
           StopReasonName(res.reason), static_cast<unsigned long long>(res.rounds));
  w.Printf("    \"collectives\": %llu,\n", static_cast<unsigned long long>(res.collectives));
  w.Printf("    \"shots\": %llu,\n    \"local_shots\": %llu,\n    \"foreign_shots\": %llu,\n",
           static_cast<unsigned long long>(res.shots), static_cast<unsigned long long>(st.shots),
           static_cast<unsigned long long>(st.foreignShots));
  w.Printf("    \"rays\": %llu,\n    \"mask_rays\": %llu,\n    \"hits\": %llu,\n",
           static_cast<unsigned long long>(st.rays), static_cast<unsigned long long>(st.maskRays),
           static_cast<unsigned long long>(st.hits));
  w.Printf("    \"mask_rays_by_patch\": %llu,\n    \"mask_pixels_no_exit\": %llu,\n",
           static_cast<unsigned long long>(st.maskRaysByPatch),
           static_cast<unsigned long long>(st.maskNoExit));
  w.Printf("    \"centre_read_shots\": %llu,\n    \"centre_read_rays\": %llu,\n",
           static_cast<unsigned long long>(st.readShots),
           static_cast<unsigned long long>(st.readRays));
  w.Printf("    \"packets\": %llu,\n    \"packet_bytes\": %u,\n    \"bytes_sent\": %llu,\n",
           static_cast<unsigned long long>(st.packetsSent), packetBytes,
           static_cast<unsigned long long>(st.packetsSent * packetBytes));
  w.Printf(
      "    \"wait_seconds\": %.6f,\n    \"wait_seconds_max_rank\": %.6f,\n"
      "    \"compute_cpu_seconds\": %.6f,\n    \"critical_cpu_seconds\": %.6f,\n",
      res.waitSeconds, res.waitSecondsMax, res.computeSeconds, res.criticalSeconds);
  w.Printf("    \"critical_env_cpu_seconds\": %.6f,\n", res.criticalEnvSeconds);
  w.Printf(
      "    \"grid_steps\": %llu,\n    \"critical_env_steps\": %llu,\n    \"critical_rank_steps\": "
      "%llu,\n",
      static_cast<unsigned long long>(res.gridSteps),
      static_cast<unsigned long long>(res.criticalEnvSteps),
      static_cast<unsigned long long>(res.criticalRankSteps));
  w.Printf(
      "    \"work\": %llu,\n    \"critical_env_work\": %llu,\n    \"critical_rank_work\": %llu,\n",
      static_cast<unsigned long long>(res.work),
      static_cast<unsigned long long>(res.criticalEnvWork),
      static_cast<unsigned long long>(res.criticalRankWork));
  w.Printf("    \"unshot_fraction\": %.17g,\n", res.unshotFraction);
  // Sub-patch elements: the pool (roots included), what was used, the
  // leaves drawn, and whether refinement stopped for want of elements.
  uint64_t used = 0, capacity = 0, leaves = 0, depth = 0, splits = 0, refused = 0;
  for (const EnvSummary& e : r->summary) {
    used += e.elementsUsed;
    capacity += e.elementCapacity;
    leaves += e.leaves;
    depth = e.elementDepth > depth ? e.elementDepth : depth;
    splits += e.stats.splits;
    refused += e.stats.refusedSplits;
  }
  w.Printf(
      "    \"elements\": {\"capacity\": %llu, \"used\": %llu, \"leaves\": %llu, "
      "\"splits\": %llu, \"deepest\": %llu, \"refused_splits\": %llu, "
      "\"refinement_stopped\": %s},\n",
      (unsigned long long)capacity, (unsigned long long)used, (unsigned long long)leaves,
      (unsigned long long)splits, (unsigned long long)depth, (unsigned long long)refused,
      refused > 0 ? "true" : "false");
  // Against --reference (null without one): the final image's relative RMSE.
  if (o.reference.empty())
    w.Printf("    \"relative_rmse\": null,\n");
  else
    w.Printf("    \"relative_rmse\": %.17g,\n", res.relativeRmse);
  w.Printf("    \"excluded_pixels\": %zu,\n", r->excludedPixels);  // by --exclude
  w.Printf("    \"error_measurements\": %llu,\n",
           static_cast<unsigned long long>(res.errorMeasurements));
  // The stated error of patches.csv's b: the Monte Carlo standard error
  // relative to b (area-weighted RMS over patches and channels), and the
  // ambient term's share of the total radiosity (what the still-unshot power
  // adds: added to b with --correct-unshot on, missing from it otherwise).
  double relVarArea = 0.0, weight = 0.0, bArea = 0.0, ambientArea = 0.0;
  for (const EnvSummary& e : r->summary) {
    relVarArea += e.relVarArea;
    weight += e.weight;
    for (int c = 0; c < 3; ++c) {
      bArea += e.bArea[c];
      ambientArea += e.ambientArea[c];
    }
  }
  double radiosity = o.correctUnshot ? bArea : bArea + ambientArea;
  w.Printf("    \"ambient\": [%.17g, %.17g, %.17g],\n", r->ambientB[0], r->ambientB[1],
           r->ambientB[2]);
  w.Printf("    \"ambient_share\": %.17g,\n", radiosity > 0.0 ? ambientArea / radiosity : 0.0);
  double mc = weight > 0.0 ? std::sqrt(relVarArea / weight) : 0.0;
  w.Printf("    \"mc_relative_error\": %.17g,\n", mc);
  // The stated error: the Monte Carlo error, the bias estimate of the
  // power not yet shot (BiasEstimate) and that of the power the masks lost
  // (LossEstimate), combined in quadrature.
  w.Printf("    \"bias_estimate\": %.17g,\n", res.biasEstimate);
  w.Printf("    \"loss_estimate\": %.17g,\n", res.lossEstimate);
  w.Printf("    \"stated_error\": %.17g\n  },\n",
           std::sqrt(mc * mc + res.biasEstimate * res.biasEstimate +
                     res.lossEstimate * res.lossEstimate));
  EnergyLedger total;
  for (const EnvSummary& e : r->summary) {
    for (int c = 0; c < 3; ++c) {
      total.emitted[c] += e.ledger.emitted[c];
      total.absorbed[c] += e.ledger.absorbed[c];
      total.escaped[c] += e.ledger.escaped[c];
      total.unshot[c] += e.ledger.unshot[c];
      total.inFlight[c] += e.ledger.inFlight[c];
    }
  }
  w.Printf("  \"energy\": {\n");
  JsonTriple(&w, "emitted", total.emitted, true);
  JsonTriple(&w, "absorbed", total.absorbed, true);
  JsonTriple(&w, "escaped", total.escaped, true);
  JsonTriple(&w, "unshot", total.unshot, true);
  JsonTriple(&w, "in_flight", total.inFlight, true);
  // What the ledger cannot place: power in flight between environments
  // (except Method R's, booked in in_flight), and what masks lost (negative:
  // leaked). Zero up to rounding for one environment and for Method R.
  double residual[3];
  for (int c = 0; c < 3; ++c)
    residual[c] = total.emitted[c] - total.absorbed[c] - total.escaped[c] - total.unshot[c] -
                  total.inFlight[c];
  JsonTriple(&w, "residual", residual, false);
  w.Printf("  },\n  \"timings\": {\n    \"init_seconds\": %.6f,\n", r->initSeconds);
  w.Printf("    \"solve_seconds\": %.6f,\n    \"error_seconds\": %.6f,\n", res.seconds,
           res.errorSeconds);
  w.Printf("    \"output_seconds\": %.6f\n  },\n", outputSeconds);
  w.Printf("  \"memory\": {\n    \"environment_arena_bytes\": [");
  for (size_t i = 0; i < r->summary.size(); ++i)
    w.Printf("%s%llu", i ? ", " : "", static_cast<unsigned long long>(r->summary[i].arenaBytes));
  uint64_t highWater = ArenaRoundUp(r->rankArena.used()), arenas = r->rankArena.capacity();
  for (Environment* e : r->envPtrs) {
    highWater += ArenaRoundUp(e->arenaUsed());
    arenas += e->arenaCapacity();
  }
  uint64_t peak = os::PeakRssBytes(), files = os::FileRssBytes();
  w.Printf("],\n    \"rank0_arena_bytes\": %zu,\n", r->rankArena.capacity());
  // map_Kd textures: rank 0's texels (part of its arena), and every texture
  // of the scene with the 3 bytes a texel each rank showing it holds.
  if (!r->options.exportPath.empty())  // --export's buffers in rank 0's arena
    w.Printf("    \"rank0_export_bytes\": %llu,\n",
             static_cast<unsigned long long>(r->rankExportBytes));
  w.Printf("    \"rank0_texture_bytes\": %llu,\n    \"textures\": [",
           static_cast<unsigned long long>(r->rankTextureBytes));
  for (size_t i = 0; i < r->textureInfo.size(); ++i) {
    const RunState::TextureInfo& t = r->textureInfo[i];
    w.Printf("%s{\"path\": ", i ? ", " : "");
    JsonString(&w, t.path.c_str());
    w.Printf(", \"width\": %u, \"height\": %u, \"texel_bytes\": %llu}", t.width, t.height,
             static_cast<unsigned long long>(t.width) * t.height * 3);
  }
  w.Printf("],\n");
  w.Printf("    \"predicted_bytes\": %llu,\n    \"arena_high_water_bytes\": %llu,\n",
           static_cast<unsigned long long>(r->predictedBytes),
           static_cast<unsigned long long>(highWater));
  w.Printf("    \"init_stages\": {");
  for (size_t i = 0; i < r->initStages.size(); ++i) {
    w.Printf("%s", i ? ", " : "");
    JsonString(&w, r->initStages[i].first.c_str());
    w.Printf(": %.6f", r->initStages[i].second);
  }
  w.Printf("},\n");
  w.Printf("    \"init_peak_predicted_bytes\": %llu,\n",
           static_cast<unsigned long long>(r->initPeakBytes));
  w.Printf("    \"file_rss_bytes\": %llu,\n", static_cast<unsigned long long>(files));
  // Every rank: its arenas and init's peak as predicted, its peak resident
  // set and file-backed pages as measured when the outputs were gathered,
  // the visibility-mask bytes its environments sent.
  w.Printf("    \"ranks\": [");
  for (int k = 0; k < r->transport->size(); ++k) {
    const RunState::RankMemory& m = r->rankMemory[k];
    w.Printf(
        "%s\n      {\"rank\": %d, \"predicted_bytes\": %llu, \"init_peak_predicted_bytes\": %llu, "
        "\"peak_rss_bytes\": %llu, \"file_rss_bytes\": %llu, \"bytes_sent\": %llu}",
        k ? "," : "", k, static_cast<unsigned long long>(m.predicted),
        static_cast<unsigned long long>(m.initPeak), static_cast<unsigned long long>(m.peakRss),
        static_cast<unsigned long long>(m.fileRss), static_cast<unsigned long long>(m.bytesSent));
  }
  w.Printf("],\n");
  w.Printf("    \"peak_rss_explained\": %.4f,\n",
           peak > 0 ? static_cast<double>(arenas + files) / static_cast<double>(peak) : 0.0);
  w.Printf("    \"peak_rss_bytes\": %llu\n  }\n}\n", static_cast<unsigned long long>(peak));
  w.Flush();
}

}  // namespace vismask::run
