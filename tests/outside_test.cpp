// Light from outside (--sky, --sun; outside.h): against analytic irradiance.
// A horizontal plane under a uniform sky of radiance L receives pi * L; under
// a sun of irradiance E at elevation theta, E * sin(theta); the floor of a
// room with black walls and a square skylight receives pi * L times the form
// factor from the floor to the opening (and the sun's E * sin(theta) on the
// opening's area, all of which lands on the floor). The energy ledger closes
// with the sky's and sun's power in it.
#include "vismask/solve/outside.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/scene/texture.h"
#include "vismask/solve/partition.h"

namespace vismask {
namespace {

using test::ReadCsv;
using test::RunMain;
using test::TempDir;
using test::Words;
using test::WriteFile;

constexpr double kPi = 3.141592653589793;

// The area-weighted mean of b per channel over patches.csv's rows whose
// normal's y is above 0.5 (floors facing up).
void FloorMean(const std::string& csv, double mean[3]) {
  auto rows = ReadCsv(csv);
  ASSERT_GT(rows.size(), 1u);
  const auto& head = rows[0];
  auto col = [&](const char* name) {
    for (size_t k = 0; k < head.size(); ++k)
      if (head[k] == name) return k;
    ADD_FAILURE() << "no column " << name;
    return size_t(0);
  };
  const size_t area = col("area"), ny = col("ny"), b[3] = {col("b_r"), col("b_g"), col("b_b")};
  double sum[3] = {0, 0, 0}, total = 0.0;
  for (size_t r = 1; r < rows.size(); ++r) {
    if (std::atof(rows[r][ny].c_str()) < 0.5) continue;
    const double a = std::atof(rows[r][area].c_str());
    total += a;
    for (int c = 0; c < 3; ++c) sum[c] += a * std::atof(rows[r][b[c]].c_str());
  }
  ASSERT_GT(total, 0.0);
  for (int c = 0; c < 3; ++c) mean[c] = sum[c] / total;
}

void Render(const std::string& scene, const std::string& out, const std::string& flags) {
  std::vector<std::string> args = {"render", scene, "--out", out, "--quiet"};
  for (const std::string& w : Words(flags)) args.push_back(w);
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << flags << ": " << r.err;
}

// A 2 x 2 plane at y = 0 facing up, Kd 0.5; nothing emits.
std::string WritePlane(const TempDir& dir) {
  WriteFile(dir.File("plane.mtl"), "newmtl grey\nKd 0.5 0.5 0.5\n");
  WriteFile(dir.File("plane.obj"),
            "mtllib plane.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nusemtl grey\nf 1 4 3 2\n");
  return dir.File("plane.obj");
}

TEST(OutsideTest, SkyOnAPlaneGivesPiTimesItsRadiance) {
  TempDir dir;
  const std::string plane = WritePlane(dir);
  const double sky[3] = {0.2, 0.4, 0.8};
  for (const char* how : {"", "--envs 2x1x2 --mask-method B", "--envs 2x1x2 --mask-method R"}) {
    SCOPED_TRACE(how);
    Render(plane, dir.File("out"),
           std::string("--sky 0.2,0.4,0.8 --stop-unshot 1e-4 --emitted-rays 400000 ") + how);
    double mean[3];
    ASSERT_NO_FATAL_FAILURE(FloorMean(dir.File("out/patches.csv"), mean));
    for (int c = 0; c < 3; ++c) {
      const double want = 0.5 * kPi * sky[c];
      EXPECT_NEAR(mean[c], want, 2e-3 * want) << "channel " << c;
    }
  }
}

TEST(OutsideTest, SunOnAPlaneGivesItsIrradianceTimesTheSineOfItsElevation) {
  TempDir dir;
  const std::string plane = WritePlane(dir);
  const double sun[3] = {2.0, 1.0, 0.5};
  for (const char* elevation : {"30", "70"}) {
    const double theta = std::atof(elevation) * kPi / 180.0;
    const std::string toward =
        "0," + std::to_string(std::sin(theta)) + "," + std::to_string(std::cos(theta));
    Render(plane, dir.File("out"),
           "--sun " + toward + ",2,1,0.5 --stop-unshot 1e-4 --emitted-rays 400000 --envs 2");
    double mean[3];
    ASSERT_NO_FATAL_FAILURE(FloorMean(dir.File("out/patches.csv"), mean));
    for (int c = 0; c < 3; ++c) {
      const double want = 0.5 * sun[c] * std::sin(theta);
      EXPECT_NEAR(mean[c], want, 2e-3 * want) << elevation << " degrees, channel " << c;
    }
  }
}

// The form factor from a point to a rectangle in a parallel plane at height
// h, the point below one corner, the sides a and b (Howell's catalogue, C-11).
double CornerFactor(double a, double b, double h) {
  if (a == 0.0 || b == 0.0) return 0.0;
  const double sign = (a < 0.0) != (b < 0.0) ? -1.0 : 1.0;
  const double x = std::fabs(a) / h, y = std::fabs(b) / h;
  const double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
  return sign / (2.0 * kPi) * (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy));
}

// The mean over the floor [0, w]^2 of the form factor to the opening
// [lo, hi]^2 at height h (corner decomposition, midpoint rule).
double FloorToOpening(double w, double lo, double hi, double h) {
  const int n = 200;
  double sum = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = (i + 0.5) * w / n, z = (j + 0.5) * w / n;
      sum += CornerFactor(hi - x, hi - z, h) - CornerFactor(lo - x, hi - z, h) -
             CornerFactor(hi - x, lo - z, h) + CornerFactor(lo - x, lo - z, h);
    }
  return sum / (n * n);
}

// scenes/skylight.obj with black walls and ceiling: what the floor gets
// comes straight through the opening.
std::string WriteBlackSkylight(const TempDir& dir) {
  WriteFile(dir.File("skylight.obj"), test::ReadFile("scenes/skylight.obj"));
  WriteFile(dir.File("skylight.mtl"),
            "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl wall\nKd 0 0 0\nnewmtl ceiling\nKd 0 0 0\n");
  return dir.File("skylight.obj");
}

TEST(OutsideTest, SkylightFloorGetsTheSkyTimesTheFormFactorToTheOpening) {
  TempDir dir;
  const std::string room = WriteBlackSkylight(dir);
  // The room: floor [0, 4]^2, ceiling at 3, opening [1.5, 2.5]^2.
  const double f = FloorToOpening(4.0, 1.5, 2.5, 3.0);
  ASSERT_GT(f, 0.01);
  ASSERT_LT(f, 0.06);
  for (const char* how : {"", "--envs 2x1x2 --mask-method B", "--envs 2x1x2 --mask-method R"}) {
    SCOPED_TRACE(how);
    Render(room, dir.File("out"), std::string("--sky 1,1,1 --stop-unshot 1e-4 ") + how);
    double mean[3];
    ASSERT_NO_FATAL_FAILURE(FloorMean(dir.File("out/patches.csv"), mean));
    const double want = 0.5 * kPi * f;
    EXPECT_NEAR(mean[0], want, 0.01 * want) << "form factor " << f;
  }
}

TEST(OutsideTest, SunThroughTheSkylightLandsOnTheFloor) {
  TempDir dir;
  const std::string room = WriteBlackSkylight(dir);
  // Elevation 80 degrees: the opening's light falls on the floor whole
  // (shifted by 3 / tan 80 = 0.53 m), E * sin 80 on 1 m^2 of 16.
  const double theta = 80.0 * kPi / 180.0;
  const std::string toward =
      std::to_string(std::cos(theta)) + "," + std::to_string(std::sin(theta));
  for (const char* how : {"", "--envs 2x1x2 --mask-method B", "--envs 2x1x2 --mask-method R"}) {
    SCOPED_TRACE(how);
    Render(room, dir.File("out"),
           "--sun " + toward + ",0,4,4,4 --stop-unshot 1e-4 --emitted-rays 400000 " + how);
    double mean[3];
    ASSERT_NO_FATAL_FAILURE(FloorMean(dir.File("out/patches.csv"), mean));
    const double want = 0.5 * 4.0 * std::sin(theta) / 16.0;
    EXPECT_NEAR(mean[0], want, 0.01 * want);
  }
}

double JsonNumberAfter(const std::string& json, const std::string& key, int index) {
  size_t at = json.find("\"" + key + "\": [");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return 0.0;
  const char* p = json.c_str() + at + key.size() + 5;
  for (int k = 0; k < index; ++k) p = std::strchr(p, ',') + 1;
  return std::strtod(p, nullptr);
}

// emitted = absorbed + escaped + unshot + in flight, with the sky's and the
// sun's power in emitted: what they send into the room and what leaves it.
TEST(OutsideTest, LedgerClosesWithTheSkyAndTheSun) {
  TempDir dir;
  for (const char* how : {"", "--envs 2x1x2 --mask-method R"}) {
    SCOPED_TRACE(how);
    Render("scenes/skylight.obj", dir.File("out"),
           std::string("--sky 0.5,0.5,0.5 --sun 1,4,0.5,3,3,3 --emitted-rays 300000 ") + how);
    const std::string json = test::ReadFile(dir.File("out/run.json"));
    const double emitted = JsonNumberAfter(json, "emitted", 0);
    // The sky's pi L on every face of the box (2 of 16 m^2, 4 of 12), and
    // the sun's E cos on the faces it enters by.
    // the sun's E cos on the faces it enters by: x = 4 (12 m^2), the top
    // (16 m^2) and z = 4 (12 m^2).
    const double cosines = (1.0 * 12.0 + 4.0 * 16.0 + 0.5 * 12.0) / std::sqrt(1.0 + 16.0 + 0.25);
    // (the direction is kept in float: 1e-7)
    EXPECT_NEAR(emitted, kPi * 0.5 * 80.0 + 3.0 * cosines, 1e-7 * emitted);
    const double escaped = JsonNumberAfter(json, "escaped", 0);
    EXPECT_GT(escaped, 0.0);
    EXPECT_LT(std::fabs(JsonNumberAfter(json, "residual", 0)), 1e-9 * emitted);
  }
}

TEST(OutsideTest, ShootersTileTheBoxFacesAnEnvironmentLiesOn) {
  EnvGrid grid;
  grid.n[0] = 2;
  grid.box.lo = glm::vec3(0.0f);
  grid.box.hi = glm::vec3(4.0f, 3.0f, 4.0f);
  OutsideLight light;
  ASSERT_TRUE(ParseSky("1,1,1", &light));
  // Environment 0 (x in [0, 2]) lies on 5 of the box's faces: 5 sky shooters.
  std::vector<OutsideShooter> s;
  OutsideShooters(grid, 0, light, 1, &s);
  EXPECT_EQ(s.size(), 5u);
  OutsideShooters(grid, 0, light, 3, &s);
  EXPECT_EQ(s.size(), 45u);
  // Over both environments, pi L times the box's surface, whatever the tiles.
  const double surface = 2.0 * (16.0 + 12.0 + 12.0);
  EXPECT_NEAR(OutsidePower(grid, light, 1), 3.0 * kPi * surface, 1e-9);
  EXPECT_NEAR(OutsidePower(grid, light, 8), 3.0 * kPi * surface, 1e-6);
  // The sun straight down enters by the top only: E times the top's area.
  OutsideLight sun;
  ASSERT_TRUE(ParseSun("0,1,0,2,2,2", &sun));
  EXPECT_NEAR(OutsidePower(grid, sun, 1), 3.0 * 2.0 * 16.0, 1e-9);
  for (const char* bad : {"1,1", "1,-1,1", "1,1,1,1", "a,1,1", "1,,1", "1e300,1,1"})
    EXPECT_FALSE(ParseSky(bad, &light)) << bad;
  for (const char* bad : {"0,0,0,1,1,1", "0,1,0,1,1", "0,1,0,1,1,-1", "0,1,0,1,1,1,91"})
    EXPECT_FALSE(ParseSun(bad, &sun)) << bad;
}

// --sky FILE.hdr -----------------------------------------------------------

// A Radiance HDR file of w x h texels (uncompressed RGBE, rows top to
// bottom), texel(i, j) its linear RGB (values RGBE holds exactly).
void WriteHdr(const std::string& path, int w, int h,
              const std::function<glm::vec3(int, int)>& texel) {
  std::string bytes = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + std::to_string(h) + " +X " +
                      std::to_string(w) + "\n";
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const glm::vec3 c = texel(i, j);
      const float v = std::fmax(c.x, std::fmax(c.y, c.z));
      if (v < 1e-32f) {
        bytes.append(4, '\0');
        continue;
      }
      int e = 0;
      const double m = std::frexp(static_cast<double>(v), &e);
      const double k = m * 256.0 / v;
      for (int ch = 0; ch < 3; ++ch) bytes += static_cast<char>(static_cast<int>(c[ch] * k));
      bytes += static_cast<char>(e + 128);
    }
  WriteFile(path, bytes);
}

// A map of four colours above the horizon, a quarter of the azimuths each
// (left to right: red, green, blue, white), and grey below, as read.
SkyMap QuarterMap() {
  SkyMap m;
  m.width = 64;
  m.height = 32;
  const glm::vec3 quarter[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (uint32_t j = 0; j < m.height; ++j)
    for (uint32_t i = 0; i < m.width; ++i) {
      const glm::vec3 c = 2 * j < m.height ? quarter[4 * i / m.width] : glm::vec3(0.25f);
      for (int ch = 0; ch < 3; ++ch) m.staged.push_back(c[ch]);
    }
  m.texels = Span<const float>(m.staged.data(), m.staged.size());
  m.Integrate();
  return m;
}

// The orientation of Blender/Cycles' default equirectangular world on a
// Y-up scene (outside.h): the centre looks along +X, the top is +Y, three
// quarters across looks along +Z. (These directions and colours are what
// Cycles renders through tools/reference's Environment Texture set-up.)
TEST(OutsideTest, SkyMapIsOrientedAsCyclesEquirectangularWorld) {
  const SkyMap m = QuarterMap();
  auto at = [&](float x, float y, float z) { return m.Radiance(glm::vec3(x, y, z)); };
  EXPECT_EQ(at(1, 0.3f, 0.5f), glm::vec3(0, 0, 1));    // just past the centre: blue
  EXPECT_EQ(at(1, 0.3f, -0.5f), glm::vec3(0, 1, 0));   // just before it: green
  EXPECT_EQ(at(-0.5f, 0.3f, 1), glm::vec3(1, 1, 1));   // past three quarters: white
  EXPECT_EQ(at(-1, 0.3f, -0.5f), glm::vec3(1, 0, 0));  // the left edge's side: red
  EXPECT_EQ(at(1, -0.3f, 0.5f), glm::vec3(0.25f));     // below the horizon
  EXPECT_EQ(at(0, 1, 0), at(0.001f, 1, 0.001f));       // straight up: the top row
}

// What crosses each face of the box: a hemisphere of the map weighted by
// the cosine, in closed form a texel. Through the top, the upper half's
// colours a quarter each of pi; through a side, the two quarters whose
// azimuths it faces, and the grey below.
TEST(OutsideTest, SkyMapCrossingIsTheCosineWeightedHemisphere) {
  const SkyMap m = QuarterMap();
  const double q = kPi / 4.0;  // a quarter of the upper hemisphere, cosine-weighted about +Y
  const glm::dvec3 red(1, 0, 0), green(0, 1, 0), blue(0, 0, 1), white(1, 1, 1), grey(0.25);
  const glm::dvec3 want[6] = {// A side's hemisphere is half above the horizon, half below (pi / 2
                              // each): -X sees the upper red and white quarters (pi / 4 each), +X
                              // green and blue; -Z red and green, +Z blue and white.
                              q * (red + white) + 0.5 * kPi * grey,
                              q * (green + blue) + 0.5 * kPi * grey,
                              kPi * grey,
                              q * (red + green + blue + white),
                              q * (red + green) + 0.5 * kPi * grey,
                              q * (blue + white) + 0.5 * kPi * grey};
  for (int f = 0; f < 6; ++f)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.crossing[f][c], want[f][c], 1e-12) << f << " " << c;
  // A uniform map crosses exactly pi times its radiance (the mean taken
  // about the first texel), as --sky R,G,B of it.
  SkyMap u;
  u.width = 7;
  u.height = 5;
  u.staged.assign(3 * 35, 0.0f);
  for (size_t k = 0; k < u.staged.size(); k += 3) {
    u.staged[k] = 0.3f;
    u.staged[k + 1] = 0.4f;
    u.staged[k + 2] = 0.7f;
  }
  u.texels = Span<const float>(u.staged.data(), u.staged.size());
  u.Integrate();
  for (int f = 0; f < 6; ++f)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(u.crossing[f][c], kPi * static_cast<double>(u.staged[c])) << f << " " << c;
}

// A map of one colour is the uniform sky of that colour: the same power
// through every face and, ray by ray, the same shares, so the same bytes
// on one environment and on several (Methods R and B).
TEST(OutsideTest, UniformSkyMapGivesTheBytesOfItsColour) {
  TempDir dir;
  WriteHdr(dir.File("uniform.hdr"), 16, 8, [](int, int) { return glm::vec3(0.25f, 0.375f, 0.5f); });
  for (const char* how : {"", "--envs 2x1x2 --mask-method R", "--envs 2x1x2 --mask-method B"}) {
    SCOPED_TRACE(how);
    const std::string common =
        std::string(" --emitted-rays 200000 --width 48 --height 48 --mask-res 24 ") + how;
    Render("scenes/skylight.obj", dir.File("colour"), "--sky 0.25,0.375,0.5" + common);
    Render("scenes/skylight.obj", dir.File("map"), "--sky " + dir.File("uniform.hdr") + common);
    for (const char* file : {"image.pfm", "patches.csv"})
      EXPECT_TRUE(test::ReadFile(dir.File(std::string("colour/") + file)) ==
                  test::ReadFile(dir.File(std::string("map/") + file)))
          << file << " differs";
  }
}

// Under a two-colour map the ledger closes: emitted is the map's crossing
// over the box's faces, and it all goes somewhere. (On one environment and
// with Method R, whose power in flight is summed ray by ray; B and C count
// a packet's power in flight by the share of its rays that go on, which a
// map's rays of unequal shares make an estimate: docs/DESIGN.md.)
TEST(OutsideTest, LedgerClosesUnderASkyMap) {
  TempDir dir;
  SkyMap map;
  ASSERT_TRUE(ReadSkyMap("scenes/skies/two-colour.hdr", &map).ok());
  // The box of scenes/skylight.obj: 4 x 3 x 4 (faces of 12, 16, 12 m^2).
  const double area[6] = {12, 12, 16, 16, 12, 12};
  double want = 0.0;  // the red channel's, as JsonNumberAfter reads it
  for (int f = 0; f < 6; ++f) want += map.crossing[f][0] * area[f];
  for (const char* how : {"", "--envs 2x1x2 --mask-method R"}) {
    SCOPED_TRACE(how);
    Render("scenes/skylight.obj", dir.File("out"),
           std::string("--sky scenes/skies/two-colour.hdr --emitted-rays 300000 ") + how);
    const std::string json = test::ReadFile(dir.File("out/run.json"));
    const double emitted = JsonNumberAfter(json, "emitted", 0);
    EXPECT_NEAR(emitted, want, 1e-9 * want);
    EXPECT_LT(std::fabs(JsonNumberAfter(json, "residual", 0)), 1e-9 * emitted);
    EXPECT_NE(json.find("\"sky\": {\"file\": \"scenes/skies/two-colour.hdr\"}"), std::string::npos);
  }
}

// A bad sky map is refused at init with exit 2, naming the file: missing,
// a directory, a FIFO (never opened for reading whole), not an HDR image,
// or more than --mem-budget leaves it to decode (judged from its header).
TEST(OutsideTest, BadSkyMapsExitTwoNamingTheFile) {
  TempDir dir;
  ASSERT_EQ(mkfifo(dir.File("fifo.hdr").c_str(), 0600), 0);
  WriteFile(dir.File("text.hdr"), "not an image\n");
  WriteHdr(dir.File("big.hdr"), 1024, 512, [](int, int) { return glm::vec3(1.0f); });
  struct Case {
    std::string path, flags, why;
  } cases[] = {{dir.File("missing.hdr"), "", "cannot open"},
               {dir.path() + "/", "", "not a regular file (a directory)"},
               {dir.File("fifo.hdr"), "", "not a regular file (a FIFO)"},
               {dir.File("text.hdr"), "", "not a Radiance HDR image"},
               {dir.File("big.hdr"), "--mem-budget 8000000", "--mem-budget leaves it at init"}};
  for (const Case& c : cases) {
    std::vector<std::string> args = {"render", "scenes/skylight.obj", "--sky",  c.path,
                                     "--out",  dir.File("out"),       "--quiet"};
    for (const std::string& w : Words(c.flags)) args.push_back(w);
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 2) << c.path << ": " << r.err;
    EXPECT_NE(r.err.find("--sky: cannot read sky map '" + c.path + "': "), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find(c.why), std::string::npos) << r.err;
  }
  // Without the budget the large map is read (a valid file, refused above
  // only for its size).
  SkyMap big;
  EXPECT_TRUE(ReadSkyMap(dir.File("big.hdr"), &big).ok());
  EXPECT_EQ(big.width, 1024u);
}

// A fuzz finding (tests/fuzz/sky_fuzz.cpp): run-length data that ends
// inside a scanline made stb_image read zeros past the end as a run count
// of 0 and loop for ever. It is refused before decoding; every prefix of a
// valid run-length map is refused or decoded, and none hangs.
TEST(OutsideTest, SkyMapWhoseRunsEndInsideAScanlineIsRefused) {
  SkyMap map;
  Status s = ReadSkyMap("tests/data/hdr-rle-cut.hdr", &map);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.ToString().find("corrupt HDR: its run-length data ends inside scanline 0 of 2"),
            std::string::npos)
      << s.ToString();
  // The same where the header ends at a line that starts with a NUL byte
  // (stb_image reads its lines as C strings: an empty one).
  s = ReadSkyMap("tests/data/hdr-rle-cut-nul-header.hdr", &map);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.ToString().find("corrupt HDR: its run-length data ends inside scanline"),
            std::string::npos)
      << s.ToString();
  // Two scanlines of 8 texels, each channel a literal dump or a run.
  std::string whole = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 8\n";
  for (int row = 0; row < 2; ++row) {
    whole += std::string("\x02\x02\x00\x08", 4);
    whole += '\x08';
    for (int i = 0; i < 8; ++i) whole += static_cast<char>(100 + 10 * i + row);
    whole += std::string("\x88\x40\x88\x20\x88\x81", 6);  // G, B, E as runs of 8
  }
  ASSERT_TRUE(DecodeSkyMap(whole, "whole.hdr", &map).ok());
  EXPECT_EQ(map.width, 8u);
  EXPECT_EQ(map.height, 2u);
  int refused = 0;
  for (size_t n = 0; n < whole.size(); ++n) {
    SkyMap part;
    const Status p = DecodeSkyMap(whole.substr(0, n), "part.hdr", &part);
    refused += p.ToString().find("run-length data ends inside") != std::string::npos;
  }
  // Every cut inside the two scanlines' runs (15 bytes each) but one each:
  // just before the last run's value byte, where the 0 read in its place
  // is a value and the scanline is whole.
  EXPECT_EQ(refused, 2 * 14);
}

}  // namespace
}  // namespace vismask
