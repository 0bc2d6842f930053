// run.json: the options, the solve, the memory and the error, written by
// rank 0 without allocating (run.h).
#include "../app/run.h"

namespace vismask::run {

// The length of the valid UTF-8 sequence at s[0..n) (2 to 4 bytes; 1 for
// ASCII), or 0 if s[0] does not start one (a stray continuation byte, an
// overlong form, a surrogate, beyond U+10FFFF, or cut short).
size_t Utf8Length(const unsigned char* s, size_t n) {
  const unsigned char b = s[0];
  if (b < 0x80) return 1;
  size_t len = 0;
  unsigned lo = 0x80, hi = 0xbf;  // the second byte's range
  if (b >= 0xc2 && b <= 0xdf) {
    len = 2;
  } else if (b >= 0xe0 && b <= 0xef) {
    len = 3;
    if (b == 0xe0) lo = 0xa0;  // no overlong forms
    if (b == 0xed) hi = 0x9f;  // no surrogates
  } else if (b >= 0xf0 && b <= 0xf4) {
    len = 4;
    if (b == 0xf0) lo = 0x90;
    if (b == 0xf4) hi = 0x8f;  // at most U+10FFFF
  } else {
    return 0;
  }
  if (n < len || s[1] < lo || s[1] > hi) return 0;
  for (size_t k = 2; k < len; ++k)
    if (s[k] < 0x80 || s[k] > 0xbf) return 0;
  return len;
}

// The next piece of a JSON string's content from s[0..n) into out (at
// least 7 bytes): a valid UTF-8 sequence as it is, '"' and '\\' escaped, and
// a control character or a byte that is not valid UTF-8 as \u00XX (XX the
// byte: run.json is valid JSON whatever bytes a path holds, and \u00XX
// always stands for the byte XX, vismask verify reads it back so). Returns
// the bytes consumed and *written.
size_t JsonPiece(const char* s, size_t n, char* out, size_t* written) {
  const unsigned char ch = static_cast<unsigned char>(s[0]);
  if (ch == '"' || ch == '\\') {
    out[0] = '\\';
    out[1] = s[0];
    *written = 2;
    return 1;
  }
  const size_t len = ch < 0x20 ? 0 : Utf8Length(reinterpret_cast<const unsigned char*>(s), n);
  if (len == 0) {
    *written = static_cast<size_t>(std::snprintf(out, 7, "\\u%04x", ch));
    return 1;
  }
  std::memcpy(out, s, len);
  *written = len;
  return len;
}

void JsonString(TextWriter* w, const char* s) {
  w->Write("\"", 1);
  char esc[8];
  for (size_t n = std::strlen(s); n > 0;) {
    size_t written = 0;
    const size_t used = JsonPiece(s, n, esc, &written);
    w->Write(esc, written);
    s += used;
    n -= used;
  }
  w->Write("\"", 1);
}

// The same, for init-time text on the heap (footprint --json).
std::string JsonQuoted(const std::string& s) {
  std::string q = "\"";
  char esc[8];
  for (size_t i = 0; i < s.size();) {
    size_t written = 0;
    i += JsonPiece(s.data() + i, s.size() - i, esc, &written);
    q.append(esc, written);
  }
  return q + "\"";
}

void JsonTriple(TextWriter* w, const char* name, const double v[3], bool comma) {
  w->Printf("    \"%s\": [%.17g, %.17g, %.17g]%s\n", name, v[0], v[1], v[2], comma ? "," : "");
}

namespace {

// "counts": the scene, the environments and the ranks.
void WriteCounts(const RunState* r, TextWriter* out) {
  const Options& o = r->options;
  TextWriter& w = *out;
  size_t patches = 0, vertices = 0, cells = 0, refs = 0, subGrids = 0;
  for (const EnvSummary& e : r->summary) {
    patches += e.patches;
    vertices += e.vertices;
    cells += e.gridCells;
    refs += e.gridRefs;
    subGrids += e.gridSubGrids;
  }
  w.Printf("  \"counts\": {\n    \"polygons\": %zu,\n    \"patches\": %zu,\n", r->numPolygons,
           patches);
  if (o.twoSided || o.twoSidedEmitters)  // of `patches`, the reversed copies
    w.Printf("    \"twin_patches\": %llu,\n", static_cast<unsigned long long>(r->numTwins));
  w.Printf("    \"vertices\": %zu,\n    \"environments\": %zu,\n", vertices, r->summary.size());
  w.Printf("    \"ranks\": %d,\n    \"transport\": \"%s\",\n", r->transport->size(),
           r->transport->name());
  w.Printf("    \"grid_cells\": %zu,\n    \"grid_refs\": %zu,\n    \"grid_sub_grids\": %zu", cells,
           refs, subGrids);
  if (!o.exportPath.empty())  // the .glb: its vertices, triangles and bytes
    w.Printf(",\n    \"export\": {\"vertices\": %llu, \"triangles\": %llu, \"bytes\": %llu}",
             static_cast<unsigned long long>(r->exportWhole.vertices),
             static_cast<unsigned long long>(r->exportWhole.triangles),
             static_cast<unsigned long long>(r->exportBytes));
  w.Printf("\n  },\n");
}

// "result" up to the per-environment lists: the stop, the shots, rays,
// packets, times and work.
void WriteResultTotals(const RunState* r, const SolveResult& res, TextWriter* out) {
  TextWriter& w = *out;
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
  w.Printf("    \"total_cpu_seconds\": %.6f,\n", res.totalComputeSeconds);
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
  // Per environment, in environment order: where the shots, rays and work
  // went (the busiest environment bounds the critical path).
  auto perEnv = [&](const char* name, auto field) {
    w.Printf("    \"%s\": [", name);
    for (size_t i = 0; i < r->summary.size(); ++i)
      w.Printf("%s%llu", i ? ", " : "", static_cast<unsigned long long>(field(r->summary[i])));
    w.Printf("],\n");
  };
  perEnv("environment_local_shots", [](const EnvSummary& e) { return e.stats.shots; });
  perEnv("environment_foreign_shots", [](const EnvSummary& e) { return e.stats.foreignShots; });
  perEnv("environment_rays", [](const EnvSummary& e) { return e.stats.rays; });
  perEnv("environment_work", [](const EnvSummary& e) { return e.work; });
  w.Printf("    \"unshot_fraction\": %.17g,\n", res.unshotFraction);
}

// The rest of "result": the elements and the stated error.
void WriteResultError(const RunState* r, const SolveResult& res, TextWriter* out) {
  const Options& o = r->options;
  TextWriter& w = *out;
  // Sub-patch elements: the pool (roots included), what was used, the
  // leaves drawn, and whether refinement stopped for want of elements.
  uint64_t used = 0, capacity = 0, leaves = 0, depth = 0, splits = 0, refused = 0, filter = 0;
  for (const EnvSummary& e : r->summary) {
    filter = e.filterSteps > filter ? e.filterSteps : filter;
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
  w.Printf("    \"indirect_filter_steps\": %llu,\n", (unsigned long long)filter);
  // Against --reference (null without one): the final image's relative RMSE.
  if (o.reference.empty())
    w.Printf("    \"relative_rmse\": null,\n");
  else
    w.Printf("    \"relative_rmse\": %.17g,\n", res.relativeRmse);
  w.Printf("    \"excluded_pixels\": %zu,\n", r->excludedPixels);  // by --exclude
  w.Printf("    \"error_measurements\": %llu,\n",
           static_cast<unsigned long long>(res.errorMeasurements));
  // The images drawn: one a measurement, and the outputs' unless the last
  // measurement drew the final solution.
  w.Printf("    \"images_drawn\": %u,\n", r->imagesDrawn);
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
}

// "energy": the ledger summed over the environments.
void WriteEnergy(const RunState* r, TextWriter* out) {
  TextWriter& w = *out;
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
  w.Printf("  },\n");
}

// "checkpoint" (with --checkpoint or --resume).
void WriteCheckpoint(const RunState* r, TextWriter* out) {
  const Options& o = r->options;
  TextWriter& w = *out;
  // --checkpoint, --resume: what was written, when, and each rank's bytes.
  const Checkpoints& c = r->checkpoints;
  w.Printf("  \"checkpoint\": {\n    \"dir\": ");
  JsonString(&w, o.checkpointDir.c_str());
  w.Printf(",\n    \"every_seconds\": %.17g,\n    \"written\": %llu,\n    \"failed\": %llu,\n",
           o.checkpointEvery, static_cast<unsigned long long>(c.written()),
           static_cast<unsigned long long>(c.failed()));
  if (c.haveCheckpoint())
    w.Printf("    \"last_rounds\": %llu,\n    \"last_solve_seconds\": %.6f,\n",
             static_cast<unsigned long long>(c.checkpointRounds()), c.checkpointElapsed());
  else
    w.Printf("    \"last_rounds\": null,\n    \"last_solve_seconds\": null,\n");
  if (c.resumed())
    w.Printf("    \"resumed_from_rounds\": %llu,\n",
             static_cast<unsigned long long>(c.resumedRounds()));
  else
    w.Printf("    \"resumed_from_rounds\": null,\n");
  w.Printf("    \"rank0_write_seconds\": %.6f,\n    \"rank_bytes\": [", c.writeSeconds());
  const int ranks = r->transport->size();
  for (int k = 0; k < ranks; ++k) {
    RankEnvs re = EnvsOfRank(r->rankEnvs.total, ranks, k);
    uint64_t bytes = 0;
    for (uint32_t e = re.first; e < re.first + re.count; ++e)
      bytes += CheckpointFileBytes(r->summary[e].arenaBytes);
    w.Printf("%s%llu", k ? ", " : "", static_cast<unsigned long long>(bytes));
  }
  w.Printf("]\n  },\n");
}

// "memory": the arenas, textures, init's stages and every rank's.
void WriteMemory(const RunState* r, TextWriter* out) {
  TextWriter& w = *out;
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
  w.Printf("    \"peak_rss_bytes\": %llu\n  }", static_cast<unsigned long long>(peak));
}

// "outputs": the commit record.
void WriteOutputList(const RunState* r, TextWriter* out) {
  const Options& o = r->options;
  TextWriter& w = *out;
  // The commit record: every other output of this run, its size and CRC-32
  // (all are written by now; run.json is renamed last), so that a reader
  // (vismask verify) can tell a complete set from a mixed one.
  w.Printf(",\n  \"outputs\": [");
  int listed = 0;
  auto record = [&](const char* name, const os::OutFile& f) {
    w.Printf("%s\n    {\"file\": ", listed++ ? "," : "");
    JsonString(&w, name);
    w.Printf(", \"bytes\": %llu, \"crc32\": \"%08x\"}", static_cast<unsigned long long>(f.bytes()),
             static_cast<unsigned>(f.crc32()));
  };
  for (int f = 0; f < kNumOutputs; ++f)
    if (f != kRunJson) record(kOutputNames[f], r->files[f]);
  if (r->exportFile.isOpen()) record(o.exportPath.c_str(), r->exportFile);
  w.Printf("\n  ]\n}\n");
}

}  // namespace

void WriteRunJson(RunState* r, const SolveResult& res, float exposure, double outputSeconds) {
  const Options& o = r->options;
  TextWriter w(&r->files[kRunJson], r->textBuffer);
  w.Printf("{\n  \"vismask_version\": 1,\n  \"command\": \"render\",\n  \"scene\": ");
  JsonString(&w, o.scene.c_str());
  w.Printf(",\n  \"out\": ");
  JsonString(&w, o.outDir.c_str());
  w.Printf(",\n");
  WriteRunJsonOptions(&w, *r, exposure);
  WriteCounts(r, &w);
  WriteResultTotals(r, res, &w);
  WriteResultError(r, res, &w);
  WriteEnergy(r, &w);
  w.Printf("  \"timings\": {\n    \"init_seconds\": %.6f,\n", r->initSeconds);
  w.Printf("    \"solve_seconds\": %.6f,\n    \"error_seconds\": %.6f,\n", res.seconds,
           res.errorSeconds);
  w.Printf("    \"output_seconds\": %.6f\n  },\n", outputSeconds);
  if (!o.checkpointDir.empty()) WriteCheckpoint(r, &w);
  WriteMemory(r, &w);
  WriteOutputList(r, &w);
  w.Flush();
}

}  // namespace vismask::run
