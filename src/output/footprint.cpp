// `vismask footprint`: every environment's and every rank's arena bytes, by
// part, from the same measuring layout a render uses, without solving (run.h).
#include "../app/run.h"

namespace vismask::run {

// vismask footprint: every environment's and every rank's arena bytes, by
// part, from the same measuring layout a render uses, without solving.
// The figures `footprint` reports for one way of meshing the scene.
struct FootprintFigures {
  std::vector<std::unique_ptr<Environment>> envs;
  std::vector<RunState> probes;  // per rank: its own buffers' layout
  std::vector<uint64_t> rankTotal, rankEnvBytes, rankOwn, rankInitPeak, rankCheckpoint;
  uint64_t patches = 0, twins = 0, envBytes = 0, total = 0;
  GlbMesh exportMesh;  // counts only: what --export would write
};

Status MeasureFootprint(const Options& o, const Prepared& p, FootprintFigures* f) {
  uint32_t total = static_cast<uint32_t>(p.grid.count());
  Status s = PrepareEnvs(p, 0, total, &f->envs);
  if (!s.ok()) return s;
  int ranks = o.ranks;
  f->rankTotal.assign(ranks, 0);
  f->rankEnvBytes.assign(ranks, 0);
  f->rankOwn.assign(ranks, 0);
  f->rankInitPeak.assign(ranks, 0);
  f->rankCheckpoint.assign(ranks, 0);
  f->probes = std::vector<RunState>(ranks);
  auto& envs = f->envs;
  for (int k = 0; k < ranks; ++k) {
    RunState& r = f->probes[k];
    r.options = o;
    r.rankEnvs = EnvsOfRank(total, ranks, k);
    for (int q = 0; q < ranks; ++q) {
      RankEnvs re = EnvsOfRank(total, ranks, q);
      uint64_t shared = 0;
      for (uint32_t e = re.first; e < re.first + re.count; ++e) {
        shared += envs[e]->lattice().numShared();
        r.anySmooth |= !envs[e]->lattice().smoothVertices().empty();
      }
      r.sharedCapacity = std::max(r.sharedCapacity, shared);
    }
    std::vector<EmitterRecord> emitters;
    AppendEmitters(envs, &emitters);
    r.foreignCounts = ForeignCountsOf(o, total, ranks, r.rankEnvs.perRank, &emitters);
    Arena measure = Arena::Measure();
    r.LayoutRank(measure, p.packetBytes, ranks, k == 0, p.textures,
                 TexturesUsed(p, r.rankEnvs.first, r.rankEnvs.count));
    r.LayoutSkyMap(measure, p.outside);
    f->rankOwn[k] = ArenaRoundUp(measure.used());
    for (uint32_t e = r.rankEnvs.first; e < r.rankEnvs.first + r.rankEnvs.count; ++e) {
      f->rankEnvBytes[k] += envs[e]->footprint().total;
      f->rankCheckpoint[k] += CheckpointFileBytes(envs[e]->footprint().total);
    }
    f->rankTotal[k] = f->rankEnvBytes[k] + f->rankOwn[k];
    const uint64_t held = k == 0 ? (o.reference.empty() ? 0 : uint64_t(o.width) * o.height * 12) +
                                       (o.exclude.empty() ? 0 : uint64_t(o.width) * o.height)
                                 : 0;
    f->rankInitPeak[k] = p.InitPeak(r.rankEnvs.first, r.rankEnvs.first + r.rankEnvs.count, k == 0,
                                    f->rankEnvBytes[k], f->rankOwn[k], held);
    f->total += f->rankTotal[k];
  }
  for (const auto& e : envs) {
    f->patches += e->footprint().numPatches;
    f->twins += e->numTwins();
    f->envBytes += e->footprint().total;
    f->exportMesh.vertices += e->footprint().numVertices;
    f->exportMesh.triangles += e->footprint().numTriangles;
  }
  return Status::Ok();
}

// What the footprint report prints from: the options, the prepared scene,
// its figures and their one-sided counterparts, the environments' balance.
struct FootprintReport {
  const Options& o;
  const Prepared& p;
  const FootprintFigures& fig;
  const FootprintFigures& base;  // one-sided: fig itself when nothing is two-sided
  uint32_t total;
  int ranks;
  uint64_t mostPatches;  // the most patches one environment holds
  double balance;        // mostPatches over the mean (1: even)

  // The split planes of axis a (--envs auto: at work quantiles).
  std::string Planes(int a) const {
    std::string s;
    for (int k = 0; k <= p.grid.n[a]; ++k) {
      char num[32];
      std::snprintf(num, sizeof num, "%s%.9g", k ? ", " : "", p.grid.Plane(a, k));
      s += num;
    }
    return s;
  }
  // vismask footprint --json, and its tables: appended to *out.
  void Json(std::string* out) const;
  void Text(std::string* out) const;
};

using ull = unsigned long long;

// printf into *out (a line of up to 511 bytes).
template <typename... Args>
void Add(std::string* out, const char* fmt, Args... args) {
  char line[512];
  std::snprintf(line, sizeof line, fmt, args...);
  *out += line;
}

// vismask footprint --json.
void FootprintReport::Json(std::string* out) const {
  *out += "{\n  \"scene\": " + JsonQuoted(o.scene) + ",\n";
  Add(out, "  \"mask_method\": \"%s\",\n  \"packet_size_bytes\": %u,\n",
      MaskMethodName(o.maskMethod), p.packetBytes);
  if (!o.exportPath.empty())  // the .glb --export would write
    Add(out, "  \"export\": {\"vertices\": %llu, \"triangles\": %llu, \"max_file_bytes\": %llu},\n",
        (ull)fig.exportMesh.vertices, (ull)fig.exportMesh.triangles,
        (ull)GlbMaxFileBytes(fig.exportMesh));
  // What --two-sided / --two-sided-emitters cost against the one-sided
  // mesh (all patches, all ranks; total_bytes: every rank's arenas).
  Add(out,
      "  \"two_sided\": {\"two_sided\": %s, \"two_sided_emitters\": %s, \"patches\": %llu, "
      "\"twin_patches\": %llu, \"one_sided_patches\": %llu, \"environment_arena_bytes\": %llu, "
      "\"one_sided_environment_arena_bytes\": %llu, \"total_bytes\": %llu, "
      "\"one_sided_total_bytes\": %llu, \"extra_bytes\": %lld},\n",
      o.twoSided ? "true" : "false", o.twoSidedEmitters ? "true" : "false", (ull)fig.patches,
      (ull)fig.twins, (ull)base.patches, (ull)fig.envBytes, (ull)base.envBytes, (ull)fig.total,
      (ull)base.total, (long long)fig.total - (long long)base.total);
  Add(out,
      "  \"split\": {\"balanced\": %s, \"grid\": [%d, %d, %d], \"most_patches\": %llu, "
      "\"patch_balance\": %.6f, \"planes\": [[%s], [%s], [%s]]},\n",
      p.grid.balanced ? "true" : "false", p.grid.n[0], p.grid.n[1], p.grid.n[2], (ull)mostPatches,
      balance, Planes(0).c_str(), Planes(1).c_str(), Planes(2).c_str());
  *out += "  \"environments\": [\n";
  for (uint32_t e = 0; e < total; ++e) {
    const EnvFootprint& f = fig.envs[e]->footprint();
    Add(out,
        "    {\"env\": %u, \"rank\": %d, \"patches\": %llu, \"twin_patches\": %llu, "
        "\"grid_cells\": %llu, "
        "\"patch_bytes\": %llu, \"element_bytes\": %llu, \"vertex_bytes\": %llu, \"grid_bytes\": "
        "%llu, "
        "\"queue_bytes\": %llu, \"packet_bytes\": %llu, \"texcoord_bytes\": %llu, "
        "\"arena_bytes\": %llu}%s\n",
        e, RankOfEnv(e, total, ranks), (ull)f.numPatches, (ull)fig.envs[e]->numTwins(),
        (ull)f.gridCells, (ull)f.patches, (ull)f.elements, (ull)f.vertices, (ull)f.grid,
        (ull)f.queue, (ull)f.packets, (ull)f.textures, (ull)f.total, e + 1 < total ? "," : "");
  }
  *out += "  ],\n  \"ranks\": [\n";
  for (int k = 0; k < ranks; ++k) {
    const RunState& r = fig.probes[k];
    Add(out,
        "    {\"rank\": %d, \"environments\": %u, \"environment_arena_bytes\": %llu, "
        "\"exchange_bytes\": %llu, \"image_bytes\": %llu, \"output_bytes\": %llu, "
        "\"texture_bytes\": %llu, \"export_bytes\": %llu, \"rank_arena_bytes\": %llu, "
        "\"total_bytes\": %llu, \"init_peak_bytes\": %llu, \"budget_bytes\": %llu, "
        "\"checkpoint_bytes\": %llu}%s\n",
        k, r.rankEnvs.count, (ull)fig.rankEnvBytes[k], (ull)r.rankExchangeBytes,
        (ull)r.rankImageBytes, (ull)r.rankOutputBytes, (ull)r.rankTextureBytes,
        (ull)r.rankExportBytes, (ull)fig.rankOwn[k], (ull)fig.rankTotal[k],
        (ull)fig.rankInitPeak[k], (ull)std::max(fig.rankTotal[k], fig.rankInitPeak[k]),
        (ull)fig.rankCheckpoint[k], k + 1 < ranks ? "," : "");
  }
  *out += "  ]\n}\n";
}

// vismask footprint's tables.
void FootprintReport::Text(std::string* out) const {
  Add(out,
      "vismask footprint: %s, %u environment%s, %d rank%s, mask %s %s=%u (%u-byte packets), "
      "%dx%d image\n\n",
      o.scene.c_str(), total, total == 1 ? "" : "s", ranks, ranks == 1 ? "" : "s",
      MaskMethodName(o.maskMethod), o.maskMethod == MaskMethod::kR ? "N" : "R",
      o.maskMethod == MaskMethod::kR ? RayCap(o) : o.maskRes, p.packetBytes, o.width, o.height);
  Add(out, "%4s %4s %9s %10s %12s %12s %12s %12s %12s %12s %12s %13s\n", "env", "rank", "patches",
      "grid_cells", "patches_B", "elements_B", "vertices_B", "grid_B", "queue_B", "packets_B",
      "texcoord_B", "arena_B");
  for (uint32_t e = 0; e < total; ++e) {
    const EnvFootprint& f = fig.envs[e]->footprint();
    int k = RankOfEnv(e, total, ranks);
    Add(out, "%4u %4d %9llu %10llu %12llu %12llu %12llu %12llu %12llu %12llu %12llu %13llu\n", e, k,
        (ull)f.numPatches, (ull)f.gridCells, (ull)f.patches, (ull)f.elements, (ull)f.vertices,
        (ull)f.grid, (ull)f.queue, (ull)f.packets, (ull)f.textures, (ull)f.total);
  }
  Add(out, "\nsplit %dx%dx%d (%s): the most patches in one environment %llu, %.3f x the mean\n",
      p.grid.n[0], p.grid.n[1], p.grid.n[2], p.grid.balanced ? "balanced, --envs auto" : "uniform",
      (ull)mostPatches, balance);
  for (int a = 0; a < 3; ++a)
    if (p.grid.n[a] > 1) Add(out, "  %c planes: %s\n", "xyz"[a], Planes(a).c_str());
  Add(out, "\n%4s %4s %14s %12s %12s %12s %12s %13s\n", "rank", "envs", "env_arenas_B",
      "exchange_B", "image_B", "output_B", "texture_B", "total_B");
  for (int k = 0; k < ranks; ++k) {
    const RunState& r = fig.probes[k];
    Add(out, "%4d %4u %14llu %12llu %12llu %12llu %12llu %13llu\n", k, r.rankEnvs.count,
        (ull)fig.rankEnvBytes[k], (ull)r.rankExchangeBytes, (ull)r.rankImageBytes,
        (ull)r.rankOutputBytes, (ull)r.rankTextureBytes, (ull)fig.rankTotal[k]);
  }
  if (!o.exportPath.empty())
    Add(out,
        "\n--export: %llu vertices, %llu triangles, a .glb of at most %llu bytes; %llu bytes of\n"
        "buffers on rank 0%s (in total_B): counts, a %llu-byte chunk the mesh streams through,\n"
        "and rank 0's %llu-byte head of the .glb\n",
        (ull)fig.exportMesh.vertices, (ull)fig.exportMesh.triangles,
        (ull)GlbMaxFileBytes(fig.exportMesh), (ull)fig.probes[0].rankExportBytes,
        ranks > 1
            ? (", " + std::to_string(fig.probes[1].rankExportBytes) + " on each other rank").c_str()
            : "",
        (ull)kExportChunkBytes, (ull)kGlbHeadBytes);
  if (p.twins.any())
    Add(out,
        "\n%s: %llu patches, %llu of them twins (one-sided: %llu); %llu bytes in all ranks' "
        "arenas, %+lld (%+.1f%%) against one-sided\n",
        o.twoSided ? "--two-sided" : "--two-sided-emitters", (ull)fig.patches, (ull)fig.twins,
        (ull)base.patches, (ull)fig.total, (long long)fig.total - (long long)base.total,
        100.0 * (static_cast<double>(fig.total) / static_cast<double>(base.total) - 1.0));
  Add(out, "\n%4s %14s %14s %14s\n", "rank", "init_peak_B", "budget_B", "checkpoint_B");
  for (int k = 0; k < ranks; ++k)
    Add(out, "%4d %14llu %14llu %14llu\n", k, (ull)fig.rankInitPeak[k],
        (ull)std::max(fig.rankTotal[k], fig.rankInitPeak[k]), (ull)fig.rankCheckpoint[k]);
  Add(out,
      "\nbytes are arena reservations (the whole of a solve's memory after init); a rank's\n"
      "process also holds its binary and libraries (see run.json's memory section).\n"
      "init_peak_B bounds init's own peak (the scene read in passes, the meshes and\n"
      "staged copies beside the arenas); budget_B, the larger, is what --mem-budget must "
      "allow\n"
      "checkpoint_B: the disk a --checkpoint takes on the rank (its environments' files,\n"
      "written from the arenas: no memory beside them); its directory holds two (a and b)\n");
}

int Footprint(const Options& o) {
  Prepared p;
  Status s = CountScene(o, &p);
  if (!s.ok()) return Fail(s);
  s = PrepareScene(o, &p, 0, static_cast<uint32_t>(o.envs[0] * o.envs[1] * o.envs[2]), false);
  if (!s.ok()) return Fail(s);
  PrintWarnings(p.textures);
  uint32_t total = static_cast<uint32_t>(p.grid.count());
  FootprintFigures fig;
  s = MeasureFootprint(o, p, &fig);
  if (!s.ok()) return Fail(s);
  // What two-sidedness costs: the same scene measured one-sided.
  FootprintFigures one;
  if (p.twins.any()) {
    Prepared q = p;
    q.twins = TwinOptions{};
    for (size_t e = 0; e < q.envPatches.size(); ++e) {
      q.envPatches[e] -= q.envTwins[e];
      q.envTwins[e] = 0.0;
    }
    s = MeasureFootprint(o, q, &one);
    if (!s.ok()) return Fail(s);
  }
  // The balance of the environments: the most patches one holds over the
  // mean (1: even).
  uint64_t mostPatches = 0;
  for (const auto& e : fig.envs)
    mostPatches = std::max<uint64_t>(mostPatches, e->footprint().numPatches);
  const double balance =
      fig.patches > 0 ? static_cast<double>(mostPatches) * total / fig.patches : 1.0;
  // One-sided figures: the same as these when nothing is two-sided.
  const FootprintReport report{o,     p,       fig,         p.twins.any() ? one : fig,
                               total, o.ranks, mostPatches, balance};
  std::string out;
  if (o.json)
    report.Json(&out);
  else
    report.Text(&out);
  return WriteStdout(out.data(), out.size()) ? kExitOk : kExitOutput;
}

}  // namespace vismask::run
