// The no-heap-after-init property: the global allocation functions are
// replaced by counters, and a whole render (init, solve, output writing) must
// perform no allocation while the phase is kSolve or kOutput.
#include <gtest/gtest.h>
#include <malloc.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>

#include "direct_test_util.h"
#include "test_util.h"
#include "vismask/app/options.h"
#include "vismask/core/phase.h"

#if defined(__SANITIZE_ADDRESS__)
#define VISMASK_ALLOC_HOOKS 0  // ASan owns malloc; the test is skipped there
#else
#define VISMASK_ALLOC_HOOKS 1
#endif

namespace {
std::atomic<long> gAfterInit{0};
std::atomic<bool> gArmed{false};
pid_t gTestPid = 0;  // the gtest process; forked pipe ranks have other pids

// Live heap bytes (malloc_usable_size) while armed, and their peak while the
// phase is kInit: the init-peak test's measure.
std::atomic<long long> gLive{0};
std::atomic<long long> gInitPeak{0};
inline void Grow(void* p) {
  if (!p || !gArmed.load(std::memory_order_relaxed)) return;
  long long live = gLive.fetch_add(static_cast<long long>(malloc_usable_size(p))) +
                   static_cast<long long>(malloc_usable_size(p));
  if (vismask::CurrentPhase() == vismask::Phase::kInit) {
    long long peak = gInitPeak.load();
    while (live > peak && !gInitPeak.compare_exchange_weak(peak, live)) {
    }
  }
}
inline void Shrink(void* p) {
  if (!p || !gArmed.load(std::memory_order_relaxed)) return;
  gLive.fetch_sub(static_cast<long long>(malloc_usable_size(p)));
}

inline void Count() {
  if (!gArmed.load(std::memory_order_relaxed)) return;
  vismask::Phase p = vismask::CurrentPhase();
  if (p == vismask::Phase::kSolve || p == vismask::Phase::kOutput) {
    gAfterInit.fetch_add(1);
    // A forked rank cannot report through our counter: it dies instead, and
    // rank 0 then fails the run (exit 3) as for any lost rank.
    if (getpid() != gTestPid) {
      static const char kMsg[] = "alloc_test: heap allocation after init in a forked rank\n";
      if (write(2, kMsg, sizeof kMsg - 1) < 0) _exit(97);
      _exit(97);
    }
  }
}
}  // namespace

#if VISMASK_ALLOC_HOOKS
// glibc's own entry points; every C++ operator new ends in malloc.
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);

void* malloc(size_t n) {
  Count();
  void* q = __libc_malloc(n);
  Grow(q);
  return q;
}
void* calloc(size_t a, size_t b) {
  Count();
  void* q = __libc_calloc(a, b);
  Grow(q);
  return q;
}
void* realloc(void* p, size_t n) {
  Count();
  Shrink(p);
  void* q = __libc_realloc(p, n);
  Grow(q ? q : (n == 0 ? nullptr : p));
  return q;
}
void* aligned_alloc(size_t align, size_t n) {
  Count();
  void* q = __libc_memalign(align, n);
  Grow(q);
  return q;
}
void* memalign(size_t align, size_t n) {
  Count();
  void* q = __libc_memalign(align, n);
  Grow(q);
  return q;
}
int posix_memalign(void** out, size_t align, size_t n) {
  Count();
  void* p = __libc_memalign(align, n);
  if (!p) return 12;  // ENOMEM
  Grow(p);
  *out = p;
  return 0;
}
void free(void* p) {
  Shrink(p);
  __libc_free(p);
}
}
#endif

namespace vismask {
namespace {

// The hooks replace malloc for the whole test binary, but only count (and
// only can) in a build without AddressSanitizer.
#define SKIP_WITHOUT_ALLOC_HOOKS() \
  if (!VISMASK_ALLOC_HOOKS) GTEST_SKIP() << "allocation hooks are off under AddressSanitizer"

// Runs vismask::Main with `args` with the counters armed and zeroed: this
// process counts, forked ranks die on an allocation after init.
test::RunResult RunArmed(const std::vector<std::string>& args) {
  gTestPid = getpid();
  gAfterInit = 0;
  gLive = 0;
  gInitPeak = 0;
  gArmed = true;
  test::RunResult r = test::RunMain(args);
  gArmed = false;
  return r;
}

// "render SCENE --out DIR FLAGS" (FLAGS split at spaces), DIR a fresh
// directory, run armed: its exit code, stderr and the heap allocations
// after init in this process.
struct CountedRender {
  CountedRender(const std::string& scene, const std::string& flags) {
    std::vector<std::string> args = {"render", scene, "--out", dir.path()};
    for (const std::string& w : test::Words(flags)) args.push_back(w);
    test::RunResult r = RunArmed(args);
    code = r.code;
    err = r.err;
    allocations = gAfterInit.load();
  }
  std::string Json() const { return test::ReadFile(dir.File("run.json")); }

  test::TempDir dir;
  int code = -1;
  std::string err;
  long allocations = -1;
};

TEST(AllocTest, CounterSeesAllocationsInSolvePhase) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // The counter itself must be able to fail: an allocation made while the
  // phase is kSolve is counted.
  gTestPid = getpid();
  gAfterInit = 0;
  gArmed = true;
  SetPhase(Phase::kSolve);
  void* volatile p = std::malloc(64);
  std::free(p);
  int* volatile q = new int(3);
  delete q;
  SetPhase(Phase::kDone);
  gArmed = false;
  EXPECT_EQ(gAfterInit.load(), 2);
}

TEST(AllocTest, CornellRenderAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  CountedRender run("scenes/cornell.obj", "--rays 512 --max-shots 3000 --width 160 --height 120");
  ASSERT_EQ(run.code, 0);
  EXPECT_TRUE(test::FileExists(run.dir.File("image.png")));
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
  // The counted solve did refine elements (and drew them).
  std::string json = run.Json();
  size_t at = json.find("\"splits\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::atol(json.c_str() + at + 10), 10) << "no element split during the counted solve";
}

TEST(AllocTest, DirectLightPerPixelAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // Per-pixel direct light (the default with one environment) in both
  // rasters, with the error measured during the solve (each measurement
  // draws the image again).
  for (const char* raster : {"on", "off"}) {
    test::TempDir refDir;
    {
      CountedRender ref("scenes/cornell.obj",
                        std::string("--max-shots 300 --width 64 --height 48 --aa ") + raster);
      ASSERT_EQ(ref.code, 0);
      EXPECT_EQ(ref.allocations, 0) << raster;
      EXPECT_NE(ref.Json().find("\"direct_samples\": " + std::to_string(kDefaultDirectSamples)),
                std::string::npos);
      test::WriteFile(refDir.File("ref.pfm"), test::ReadFile(ref.dir.File("image.pfm")));
    }
    CountedRender run("scenes/cornell.obj",
                      std::string("--max-shots 600 --width 64 --height 48 --direct-samples 8 "
                                  "--indirect-filter 4 --error-every 100 --reference ") +
                          refDir.File("ref.pfm") + " --aa " + raster);
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_EQ(run.allocations, 0) << "heap allocations after init, --aa " << raster;
    // The indirect part smoothed on the display lattice.
    EXPECT_NE(run.Json().find("\"indirect_filter_steps\": 4,"), std::string::npos);
  }
}

// The sun in the per-pixel gather (its rim rays, its samples, the solve's
// sun shots booked as direct), in both rasters, with an area emitter beside
// it (the Cornell box: the two kinds share the samples) and without one.
TEST(AllocTest, PerPixelSunAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const char* raster : {"on", "off"})
    for (const char* scene : {"scenes/skylight.obj", "scenes/cornell.obj"}) {
      for (const char* envs : {"", " --envs 2x1x2"}) {
        // Several environments: every environment's emitters and the sun
        // gathered per pixel, the other environments' parts read from
        // their transit masks and sun maps (foreign_light.h).
        CountedRender run(scene, std::string("--sun 1,4,0.5,3,3,3 --direct-samples 32 --max-shots "
                                             "300 --width 64 --height 48 --aa ") +
                                     raster + envs);
        ASSERT_EQ(run.code, 0) << scene << envs << ": " << run.err;
        EXPECT_EQ(run.allocations, 0)
            << scene << ", --aa " << raster << envs << ": heap after init";
      }
    }
}

TEST(AllocTest, PerPixelGatherOverSeveralLampsAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // Ten lamps (emitter groups), some behind a wall: the groups' shares and
  // tallies at each shaded point, alone and with the sun as one more source.
  test::TempDir scene;
  std::vector<Lamp> lamps;
  for (double x : {-0.4, 0.4, 1.8, 2.4})
    for (double z : {-0.4, 0.4}) lamps.push_back({x, x > 1.0 ? 1.2 : 0.8, z, 0.3, 10.0});
  lamps.push_back({0.0, 2.0, 0.0, 0.5, 5.0});
  lamps.push_back({2.0, 2.0, 0.0, 0.5, 5.0});
  WriteLampsScene(scene.path(), lamps);
  for (const char* raster : {"on", "off"})
    for (const char* sun : {"", "--sun 1,4,0.5,3,3,3"}) {
      CountedRender run(scene.File("s.obj"),
                        std::string("--camera 0,0.5,0,0,0,0,0,0,1,90 --direct-samples 32 "
                                    "--patch-size 2 --width 48 --height 48 --aa ") +
                            raster + " " + sun);
      ASSERT_EQ(run.code, 0) << run.err;
      EXPECT_EQ(run.allocations, 0) << "--aa " << raster << " " << sun << ": heap after init";
    }
}

TEST(AllocTest, PowerAllocationRefinementAndCutsAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // The defaults (power allocation with partial shots, Sobol' samples,
  // elements, antialiasing) on two environments, so cut vertices are shared.
  CountedRender run("scenes/cornell.obj",
                    "--envs 2 --mask-method R --emitted-rays 500000 --max-rays 2048 --width 96 "
                    "--height 96 --stop-unshot 1e-2");
  ASSERT_EQ(run.code, 0);
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
  EXPECT_EQ(run.Json().find("\"splits\": 0,"), std::string::npos) << "no element split";
}

TEST(AllocTest, PacedMaxSecondsAllocatesNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // --max-seconds's plan and its pacing (pace.h), which re-plans the ray
  // quantum between rounds.
  CountedRender run("scenes/cornell.obj", "--max-seconds 0.2 --width 32 --height 32");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.Json().find("\"emitted_rays_paced\""), std::string::npos) << "not paced";
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
}

TEST(AllocTest, OriginsByPowerAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // One environment: once elements split, a patch's rays leave from its
  // leaves by their power (ElementTree::SampleByPower, the default).
  CountedRender run("scenes/cornell.obj",
                    "--emitted-rays 500000 --width 32 --height 32 --stop-unshot 1e-2");
  ASSERT_EQ(run.code, 0);
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
  EXPECT_EQ(run.Json().find("\"splits\": 0,"), std::string::npos) << "no element split";
  EXPECT_NE(run.Json().find("\"origins\": \"power\""), std::string::npos);
}

// With per-pixel direct light and no smoothing, a leaf's corners show its
// quarters' indirect density (ElementTree::CornerShift, each image); one
// environment's non-emitting patches continue one Sobol' sequence across
// their shots (--sequence patch, the default).
TEST(AllocTest, CornerShiftAndPatchSequenceAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  CountedRender run("scenes/cornell.obj",
                    "--emitted-rays 300000 --width 32 --height 32 --indirect-filter 0");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
  EXPECT_NE(run.Json().find("\"indirect_filter_steps\": 0,"), std::string::npos);
  EXPECT_NE(run.Json().find("\"sequence\": \"patch\""), std::string::npos);
}

unsigned long long JsonField(const std::string& json, const std::string& key) {
  size_t at = json.find("\"" + key + "\": ");
  EXPECT_NE(at, std::string::npos) << key;
  return at == std::string::npos ? 0
                                 : std::strtoull(json.c_str() + at + key.size() + 4, nullptr, 10);
}

TEST(AllocTest, EightEnvironmentRenderAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  CountedRender run("scenes/cornell.obj",
                    "--envs 2x2x2 --mask-method B --mask-res 30 --rays 256 --max-shots 1500 "
                    "--width 96 --height 96 --patch-size 50 --centre-rays all");
  ASSERT_EQ(run.code, 0);
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
  // Centre masks by patch (RasterCentres), after closing the pixels that
  // lead to no neighbour (KeepExits).
  EXPECT_GT(JsonField(run.Json(), "mask_rays_by_patch"), 0u);
  EXPECT_GT(JsonField(run.Json(), "mask_pixels_no_exit"), 0u);
  EXPECT_EQ(JsonField(run.Json(), "centre_read_shots"), 0u);
}

// Method B's shots that decide only the pixels read downstream (ReadPixels,
// ReadShare, the cache of known pixels): all of them, and auto's mix.
TEST(AllocTest, CentreRaysReadAndAutoAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string how : {"read", "auto"}) {
    CountedRender run("scenes/cornell.obj",
                      "--envs 2x2x2 --mask-method B --mask-res 30 --emitted-rays 200000 "
                      "--max-rays 2048 --max-shots 800 --width 64 --height 64 --patch-size 50 "
                      "--centre-rays " +
                          how);
    ASSERT_EQ(run.code, 0) << how;
    EXPECT_EQ(run.allocations, 0) << "heap allocations after init, " << how;
    const std::string json = run.Json();
    const unsigned long long local = JsonField(json, "local_shots");
    const unsigned long long read = JsonField(json, "centre_read_shots");
    EXPECT_GT(JsonField(json, "centre_read_rays"), 0u) << how;
    if (how == "read") {
      EXPECT_EQ(read, local);
    } else {
      EXPECT_GT(read, 0u);
      EXPECT_LT(read, local);
    }
  }
}

// Issue 20: balanced environments (--envs auto) and the default rounds
// sized by grid steps, whose per-environment CPU and step accounting runs
// every round, on one process and on two.
TEST(AllocTest, BalancedEnvironmentsAndWorkRoundsAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string ranks : {"1", "2"}) {
    CountedRender run("scenes/cornell.obj",
                      "--envs auto:4 --ranks " + ranks +
                          " --emitted-rays 200000 --stop-unshot 0.05 --width 64 --height 64 "
                          "--patch-size 50");
    ASSERT_EQ(run.code, 0) << ranks;
    EXPECT_EQ(run.allocations, 0) << "heap allocations after init, ranks " << ranks;
    std::string json = run.Json();
    EXPECT_NE(json.find("\"envs_auto\": 4"), std::string::npos) << json;
    EXPECT_EQ(json.find("\"round_work\": 0,"), std::string::npos) << json;
  }
}

TEST(AllocTest, ErrorMeasurementsAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  test::TempDir dir;
  // One shot an environment a round, so that every 50 shots is a round's
  // end and the measurements number 12 (rounds by work hold many shots).
  const std::string flags =
      "--envs 2 --rays 256 --max-shots 600 --width 64 --height 64 --patch-size 60 --quiet "
      "--round-shots 1";
  ASSERT_EQ(
      test::RunMain(test::Words("render scenes/cornell.obj " + flags + " --out " + dir.File("ref")))
          .code,
      0);
  // With an --exclude mask too (its pixels left out of every measurement).
  std::string mask = "P5\n64 64\n255\n" + std::string(64 * 32, '\xff') + std::string(64 * 32, '\0');
  test::WriteFile(dir.File("mask.pgm"), mask);
  CountedRender run("scenes/cornell.obj", flags + " --reference " + dir.File("ref/image.pfm") +
                                              " --exclude " + dir.File("mask.pgm") +
                                              " --error-every 50 --seed 2");
  ASSERT_EQ(run.code, 0);
  EXPECT_NE(run.Json().find("\"error_measurements\": 12"), std::string::npos);
  EXPECT_NE(run.Json().find("\"excluded_pixels\": 2048"), std::string::npos);
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init";
}

TEST(AllocTest, MethodsCAndRAllocateNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string method : {"C", "R"}) {
    CountedRender run("scenes/cornell.obj",
                      "--envs 2x2x2 --mask-method " + method +
                          " --mask-res 30 --rays 300 --max-shots 1500 --width 96 --height 96 "
                          "--patch-size 50");
    ASSERT_EQ(run.code, 0) << method;
    EXPECT_EQ(run.allocations, 0) << method << ": heap allocations after init";
    if (method == "C") {  // C's small casts walk the grid (WalkCentres), its large ones not
      std::string json = run.Json();
      EXPECT_GT(JsonField(json, "mask_rays_by_patch"), 0u);
      EXPECT_LT(JsonField(json, "mask_rays_by_patch"), JsonField(json, "mask_rays"));
    }
  }
}

// --sky and --sun: the outside shooters' shots (R with routes, B with tiles
// and their centre masks, one environment with none).
TEST(AllocTest, SkyAndSunAllocateNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string how :
       {"--mask-method R --envs 2x1x2", "--mask-method B --envs 2x1x2", "--envs 1"}) {
    CountedRender run("scenes/skylight.obj",
                      "--sky 0.3,0.4,0.5 --sun 1,4,0.5,3,3,2.5 --emitted-rays 200000 --width 64 "
                      "--height 64 --mask-res 24 " +
                          how);
    ASSERT_EQ(run.code, 0) << how << ": " << run.err;
    EXPECT_EQ(run.allocations, 0) << how << ": heap allocations after init";
  }
}

// --sky FILE.hdr: the map read into the rank's arena at init; each sky
// shot's shares summed over its rays and read ray by ray from it.
TEST(AllocTest, SkyMapAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string how :
       {"--mask-method R --envs 2x1x2", "--mask-method B --envs 2x1x2", "--envs 1"}) {
    CountedRender run("scenes/skylight.obj",
                      "--sky scenes/skies/two-colour.hdr --emitted-rays 200000 --width 64 "
                      "--height 64 --mask-res 24 " +
                          how);
    ASSERT_EQ(run.code, 0) << how << ": " << run.err;
    EXPECT_EQ(run.allocations, 0) << how << ": heap allocations after init";
  }
}

TEST(AllocTest, PipeRanksAllocateNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  // Four processes: this one (rank 0, counted) and three forked ranks, each
  // of which dies on its first allocation after init.
  CountedRender run("scenes/cornell.obj",
                    "--envs 2x1x2 --ranks 4 --mask-res 30 --rays 256 --max-shots 1500 --width 96 "
                    "--height 96 --patch-size 50 --quiet");
  EXPECT_EQ(run.code, 0) << "a rank failed (an allocation after init in a forked rank exits 97)";
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init in rank 0";
}

// Every environment gathering every emitter (--foreign-mask-res, the
// default with several): the transit maps' lookups in the gather, on both
// rasters, over pipes.
TEST(AllocTest, ForeignGatherAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const char* raster : {"on", "off"}) {
    CountedRender run("scenes/cornell.obj",
                      std::string("--envs 2x1x2 --ranks 2 --emitted-rays 200000 --max-shots 900 "
                                  "--width 64 --height 48 --quiet --aa ") +
                          raster);
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_EQ(run.allocations, 0) << "--aa " << raster << ": heap after init";
    EXPECT_NE(run.Json().find("\"foreign_mask_res\": 32"), std::string::npos);
  }
}

// Two-sided scenes: twins everywhere, both sides of the light emitting, on
// two environments and two ranks (cut vertices of both sides shared).
TEST(AllocTest, TwoSidedRenderAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string ranks : {"1", "2"}) {
    CountedRender run("scenes/miswound.obj",
                      "--envs 2 --ranks " + ranks +
                          " --mask-method R --two-sided --two-sided-emitters --emitted-rays 300000 "
                          "--max-rays 2048 --width 96 --height 96 --stop-unshot 1e-2 --quiet");
    EXPECT_EQ(run.code, 0) << "a rank failed (an allocation after init in a forked rank exits 97)";
    EXPECT_EQ(run.allocations, 0) << ranks << " ranks: heap allocations after init";
    EXPECT_NE(run.Json().find("\"twin_patches\""), std::string::npos);
  }
}

// Smoothing's shared vertices, in one environment and across four.
TEST(AllocTest, SmoothingAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string envs : {"1", "2x2x1"}) {
    CountedRender run("scenes/smooth/sphere-s.obj",
                      "--envs " + envs + " --emitted-rays 200000 --width 64 --height 64 --quiet");
    ASSERT_EQ(run.code, 0);
    EXPECT_EQ(run.allocations, 0) << envs;
  }
}

// Textures: the per-pixel lookups, on two environments (the floor and back
// wall are cut, so textured cut vertices are shared), antialiased and point
// sampled on two ranks.
TEST(AllocTest, TexturedRenderAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string aa : {"on", "off"}) {
    CountedRender run("scenes/textured/room.obj",
                      "--envs 2 --ranks 2 --aa " + aa +
                          " --mask-method R --emitted-rays 100000 --max-rays 2048 "
                          "--stop-unshot 2e-2 --width 64 --height 64 --quiet");
    EXPECT_EQ(run.code, 0)
        << aa << ": a rank failed (an allocation after init in a forked rank exits 97)";
    EXPECT_EQ(run.allocations, 0) << aa << ": heap allocations after init in rank 0";
    EXPECT_NE(run.Json().find("checker.png"), std::string::npos);
  }
}

// The point-sampled raster and its band-wise composite (the tests above use
// the default, antialiased).
TEST(AllocTest, PointSampledRenderOnTwoRanksAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  CountedRender run("scenes/cornell.obj",
                    "--envs 2 --ranks 2 --aa off --rays 256 --max-shots 300 --width 64 "
                    "--height 40 --quiet");
  EXPECT_EQ(run.code, 0) << "a rank failed (an allocation after init in a forked rank exits 97)";
  EXPECT_EQ(run.allocations, 0) << "heap allocations after init in rank 0";
}

// --export: every rank streams its vertices and triangles through its
// chunk, and rank 0 writes the .glb (one process; 2x2 environments on two
// pipe ranks, whose forked rank dies on an allocation after init).
TEST(AllocTest, ExportAllocatesNothingAfterInit) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  for (const std::string ranks : {"1", "2"}) {
    test::TempDir glb;
    CountedRender run("scenes/cornell.obj",
                      "--envs 2x2 --ranks " + ranks +
                          " --rays 256 --max-shots 400 --width 48 --height 48 --export " +
                          glb.File("scene.glb") + " --quiet");
    ASSERT_EQ(run.code, 0) << ranks << " ranks: " << run.err
                           << " (an allocation after init in a forked rank exits 97)";
    EXPECT_EQ(run.allocations, 0) << ranks << " ranks: heap allocations after init in rank 0";
    EXPECT_GT(test::ReadFile(glb.File("scene.glb")).size(), 10000u);
  }
}

// --checkpoint at every round's end (each environment's file written from
// its arena, the manifest from init's buffer, the collectives that agree on
// them), on one process and on two pipe ranks; then a solve resumed from a
// checkpoint a killed run left: nothing allocated after init.
TEST(AllocTest, CheckpointAndResumeAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  const std::string flags =
      "--envs 2x2x1 --max-shots 120 --round-shots 4 --width 64 --height 64 --quiet";
  test::TempDir ck;
  for (const std::string ranks : {"", " --ranks 2"}) {
    CountedRender run("scenes/cornell.obj", flags + ranks + " --checkpoint-every 0 --checkpoint " +
                                                ck.File("every" + std::to_string(ranks.size())));
    ASSERT_EQ(run.code, 0) << run.err << " (an allocation after init in a forked rank exits 97)";
    EXPECT_EQ(run.allocations, 0) << ranks << ": heap allocations after init in rank 0";
    EXPECT_EQ(JsonField(run.Json(), "written"), 7u)
        << "a checkpoint at each round's end but the last";
  }
  // A checkpoint of round 2 (the run killed while writing the third's first file).
  std::string log;
  ASSERT_NE(
      test::ShellOutput("sh -c 'VISMASK_TEST_CHECKPOINT_KILL=sync:11 " + test::VismaskBin() +
                            " render scenes/cornell.obj " + flags + " --out " + ck.File("killed") +
                            " --checkpoint " + ck.File("k") + " --checkpoint-every 0'",
                        60, &log),
      0)
      << log;
  CountedRender resumed("scenes/cornell.obj", flags + " --resume " + ck.File("k"));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(resumed.allocations, 0) << "heap allocations after init in a resumed run";
  EXPECT_EQ(JsonField(resumed.Json(), "resumed_from_rounds"), 2u);
}

// The default camera's side is chosen at init; the check for a black image
// runs in the output phase, on a scene whose walls face away from the
// camera (a box closed on -z, open on +z, seen with --view front).
TEST(AllocTest, ChosenViewAndBlackImageWarningAllocateNothing) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  test::TempDir dir;
  test::WriteFile(dir.File("box.obj"),
                  "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\n"
                  "v 0 1 1\nv 0.4 0.99 0.4\nv 0.6 0.99 0.4\nv 0.6 0.99 0.6\nv 0.4 0.99 0.6\n"
                  "usemtl wall\nf 1 2 3 4\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n"
                  "usemtl light\nf 9 10 11 12\n");
  test::WriteFile(dir.File("box.mtl"),
                  "newmtl wall\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 5 5 5\n");
  for (const std::string view : {"", "front"}) {
    CountedRender run(dir.File("box.obj"), "--rays 256 --max-shots 200 --width 48 --height 48" +
                                               (view.empty() ? "" : " --view " + view));
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_EQ(run.allocations, 0) << "heap allocations after init (--view '" << view << "')";
    EXPECT_EQ(run.err.find("warning: the image is black:") != std::string::npos, !view.empty())
        << run.err;
  }
}

// Issue 20 / issue 17 item 10: init's own peak is bounded and in the
// prediction. The live heap (arenas included: they are heap blocks) is
// tracked through the same hooks, and its peak while the phase is init must
// stay within run.json's init_peak_predicted_bytes, on scenes with cuts,
// twins, textures, smoothing and many polygons. The prediction must not be
// vacuous either: the peak is at least the arenas (predicted_bytes).
long long InitPeakOf(const std::vector<std::string>& args, std::string* json) {
  test::TempDir dir;
  std::vector<std::string> a = args;
  a.insert(a.end(), {"--out", dir.path(), "--quiet", "--width", "64", "--height", "48",
                     "--max-shots", "50"});
  test::RunResult r = RunArmed(a);
  EXPECT_EQ(r.code, 0) << r.err;
  *json = test::ReadFile(dir.File("run.json"));
  return gInitPeak.load();
}

TEST(AllocTest, InitPeakHeapIsWithinThePrediction) {
  SKIP_WITHOUT_ALLOC_HOOKS();
  test::TempDir gen;
  const std::string building = gen.File("b.obj");
  ASSERT_EQ(std::system(
                ("tools/gen-building --rooms 2x2 --floors 1 --tile 0.3 --out " + building).c_str()),
            0);
  const std::vector<std::vector<std::string>> runs = {
      {"render", "scenes/cornell.obj", "--envs", "2x1x2"},
      {"render", "scenes/miswound.obj", "--two-sided", "--envs", "2"},
      {"render", "scenes/textured/room.obj", "--envs", "2"},
      {"render", "scenes/smooth/sphere-s.obj", "--envs", "2x2"},
      {"render", building, "--patch-size", "0.5", "--envs", "2x1x2"},
  };
  for (const auto& args : runs) {
    std::string json;
    long long peak = InitPeakOf(args, &json);
    unsigned long long predicted = JsonField(json, "init_peak_predicted_bytes");
    unsigned long long arenas = JsonField(json, "predicted_bytes");
    EXPECT_LE(static_cast<unsigned long long>(peak), predicted) << args[1];
    EXPECT_GE(static_cast<unsigned long long>(peak), arenas) << args[1];
    std::printf("[ init peak ] %s: measured %lld bytes, predicted %llu (arenas %llu)\n",
                args[1].c_str(), peak, predicted, arenas);
  }
}

}  // namespace
}  // namespace vismask
