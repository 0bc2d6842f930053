// Output stage: PNG encoding inside its reserved scratch, PFM layout, tone
// mapping, and the order-independent depth test used for compositing.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <glm/geometric.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/display/raster.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

TEST(ImageTest, PngFitsItsScratchForIncompressibleImages) {
  test::TempDir dir;
  std::mt19937 rng(1);
  for (auto [w, h] : {std::pair{1, 1}, {7, 3}, {256, 256}, {640, 480}, {1500, 20}}) {
    std::vector<uint8_t> rgb(size_t(w) * h * 3);
    for (auto& b : rgb) b = static_cast<uint8_t>(rng());  // noise: the worst case
    std::vector<uint8_t> scratch(PngScratchBytes(w, h));
    os::OutFile f;
    char why[os::kWhyBytes];
    ASSERT_TRUE(f.Open(dir.File("n.png").c_str(), why)) << why;
    ASSERT_TRUE(WritePng(&f, w, h, Span<const uint8_t>(rgb.data(), rgb.size()),
                         Span<uint8_t>(scratch.data(), scratch.size()), why))
        << w << "x" << h << ": " << why;
    ASSERT_TRUE(f.Commit(why)) << why;
    std::string png = test::ReadFile(dir.File("n.png"));
    EXPECT_EQ(png.substr(1, 3), "PNG");
    EXPECT_GT(png.size(), rgb.size());  // noise does not compress
  }
}

TEST(ImageTest, PngFailsCleanlyWhenScratchIsShort) {
  test::TempDir dir;
  std::vector<uint8_t> rgb(64 * 64 * 3, 128);
  std::vector<uint8_t> scratch(PngScratchBytes(64, 64) / 4);
  os::OutFile f;
  char why[os::kWhyBytes];
  ASSERT_TRUE(f.Open(dir.File("s.png").c_str(), why));
  EXPECT_FALSE(WritePng(&f, 64, 64, Span<const uint8_t>(rgb.data(), rgb.size()),
                        Span<uint8_t>(scratch.data(), scratch.size()), why));
  f.Discard();
  EXPECT_FALSE(test::FileExists(dir.File("s.png")));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));  // no temporary left
}

TEST(ImageTest, PfmRowsRunBottomToTop) {
  test::TempDir dir;
  std::vector<glm::vec3> px = {{1, 2, 3}, {4, 5, 6}};  // 1 x 2: top then bottom
  os::OutFile f;
  char why[os::kWhyBytes];
  ASSERT_TRUE(f.Open(dir.File("p.pfm").c_str(), why));
  ASSERT_TRUE(WritePfm(&f, 1, 2, Span<const glm::vec3>(px.data(), 2)));
  ASSERT_TRUE(f.Commit(why));
  std::string s = test::ReadFile(dir.File("p.pfm"));
  std::string head = "PF\n1 2\n-1.0\n";
  ASSERT_EQ(s.size(), head.size() + 24);
  float v[6];
  std::memcpy(v, s.data() + head.size(), 24);
  EXPECT_EQ(v[0], 4.0f);  // the bottom row first
  EXPECT_EQ(v[3], 1.0f);
}

// The image fuzz target's seeds (tests/fuzz/image-corpus, make fuzz): the
// valid ones read the same from the file and from bytes, the others are
// refused naming the file; a PFM reads the same in either byte order.
TEST(ImageTest, ImageFuzzSeedsReadOrAreRefusedWithTheName) {
  const std::string dir = "tests/fuzz/image-corpus/";
  // pfm-be-3x1-scale2: a scale other than 1 or -1 is refused (issue 42: it
  // would scale the pixels, which vismask does not).
  const std::set<std::string> goodPfm = {"pfm-le-1x1", "pfm-le-2x2", "pfm-be-2x2", "pfm-le-crlf"};
  const std::set<std::string> goodPgm = {"pgm-4x3", "pgm-1x1-maxval1", "pgm-comment-free-tabs"};
  int seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string(), path = entry.path().string();
    const std::string bytes = test::ReadFile(path);
    ++seen;
    PfmImage a, b;
    Status fromFile = ReadPfm(path, &a), fromBytes = ReadPfmFromBytes(path, bytes, &b);
    EXPECT_EQ(fromFile.ToString(), fromBytes.ToString()) << name;
    EXPECT_EQ(fromFile.ok(), goodPfm.count(name) == 1) << name << ": " << fromFile.ToString();
    if (fromFile.ok()) {
      EXPECT_EQ(a.pixels, b.pixels) << name;
      EXPECT_EQ(a.pixels.size(), size_t(a.width) * size_t(a.height) * 3) << name;
    } else {
      EXPECT_EQ(fromFile.file(), path);
    }
    PgmImage g, h;
    fromFile = ReadPgm(path, &g);
    fromBytes = ReadPgmFromBytes(path, bytes, &h);
    EXPECT_EQ(fromFile.ToString(), fromBytes.ToString()) << name;
    EXPECT_EQ(fromFile.ok(), goodPgm.count(name) == 1) << name << ": " << fromFile.ToString();
    if (fromFile.ok()) {
      EXPECT_EQ(g.pixels, h.pixels) << name;
    }
  }
  EXPECT_EQ(seen, 17);
  PfmImage le, be;
  ASSERT_TRUE(ReadPfm(dir + "pfm-le-2x2", &le).ok());
  ASSERT_TRUE(ReadPfm(dir + "pfm-be-2x2", &be).ok());
  EXPECT_EQ(le.pixels, be.pixels);
  // Row 0 is the top, the file's last row.
  std::vector<float> want = {3.5f,  7.0f, 0.125f, 1e6f, 0.75f, 0.0f,
                             0.25f, 0.5f, 1.0f,   2.0f, 0.0f,  1e-3f};
  EXPECT_EQ(le.pixels, want);
  PgmImage pgm;
  ASSERT_TRUE(ReadPgm(dir + "pgm-4x3", &pgm).ok());
  EXPECT_EQ(pgm.width, 4);
  EXPECT_EQ(pgm.height, 3);
  EXPECT_EQ(pgm.pixels[1], 255);
}

// A device, a FIFO or a directory is refused by its kind, before anything
// is read (/dev/zero would be read until memory runs out; opening a FIFO
// waited for a writer forever, issue 42).
TEST(ImageTest, ImageReadersTakeOnlyRegularFiles) {
  test::TempDir dir;
  PfmImage pfm;
  PgmImage pgm;
  ASSERT_EQ(mkfifo(dir.File("fifo").c_str(), 0600), 0);
  const std::pair<std::string, std::string> cases[] = {{"/dev/zero", "a character device"},
                                                       {dir.path(), "a directory"},
                                                       {dir.File("fifo"), "a FIFO"}};
  for (const auto& [path, kind] : cases) {
    Status s = ReadPfm(path, &pfm);
    EXPECT_FALSE(s.ok()) << path;
    EXPECT_EQ(s.ToString(), path + ": cannot read: not a regular file (" + kind + ")");
    s = ReadPgm(path, &pgm);
    EXPECT_EQ(s.ToString(), path + ": cannot read: not a regular file (" + kind + ")");
  }
  EXPECT_EQ(ReadPfm(dir.File("none.pfm"), &pfm).ToString(), dir.File("none.pfm") + ": cannot open");
}

TEST(ImageTest, ToneMapClampsAndEncodesSrgb) {
  std::vector<glm::vec3> c = {{0, 0.5f, 2}, {-1, std::nanf(""), 0.0031308f}};
  std::vector<uint8_t> rgb(6);
  ToneMap(Span<const glm::vec3>(c.data(), 2), 1.0f, Span<uint8_t>(rgb.data(), 6));
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[1], 188);  // sRGB(0.5) = 0.7354
  EXPECT_EQ(rgb[2], 255);
  EXPECT_EQ(rgb[3], 0);
  EXPECT_EQ(rgb[4], 0);
  EXPECT_EQ(rgb[5], 10);  // 12.92 * 0.0031308 * 255
}

Patch Quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t id, uint32_t v0) {
  Patch p{};
  // Reversed, so that the quad faces -z (toward the camera below).
  p.corner[0] = a, p.corner[1] = d, p.corner[2] = c, p.corner[3] = b;
  p.numCorners = 4;
  p.normal = glm::normalize(glm::cross(p.corner[1] - a, p.corner[2] - a));
  p.globalId = id;
  for (int k = 0; k < 4; ++k) p.vertex[k] = v0 + k;
  return p;
}

TEST(RasterTest, CompositeIsIndependentOfGrouping) {
  // Three overlapping quads facing the camera, two at the same depth.
  std::vector<Patch> patches = {
      Quad({-1, -1, 5}, {1, -1, 5}, {1, 1, 5}, {-1, 1, 5}, 2, 0),
      Quad({-0.5f, -1, 5}, {1.5f, -1, 5}, {1.5f, 1, 5}, {-0.5f, 1, 5}, 1, 4),
      Quad({0, 0, 3}, {2, 0, 3}, {2, 2, 3}, {0, 2, 3}, 0, 8),
  };
  std::vector<glm::vec3> verts, rad;
  for (auto& p : patches)
    for (int k = 0; k < 4; ++k) {
      verts.push_back(p.corner[k]);
      rad.push_back(glm::vec3(float(p.globalId + 1)));
    }
  Camera cam;
  cam.eye = {0, 0, -5};
  cam.target = {0, 0, 0};
  View view;
  ASSERT_TRUE(MakeView(cam, 64, 48, &view));
  auto fbOf = [&](Arena& arena, std::vector<Patch> subset) {
    Framebuffer fb;
    fb.Layout(arena, 64, 48, false);
    fb.Clear();
    RasterPatches(view, Span<const Patch>(subset.data(), subset.size()),
                  Span<const glm::vec3>(verts.data(), verts.size()),
                  Span<const glm::vec3>(rad.data(), rad.size()), &fb);
    return fb;
  };
  Arena arena(1 << 20);
  Framebuffer all = fbOf(arena, patches);
  Framebuffer reversed = fbOf(arena, {patches[2], patches[1], patches[0]});
  Framebuffer a = fbOf(arena, {patches[0]});
  Framebuffer b = fbOf(arena, {patches[2], patches[1]});
  Composite(b, &a);
  size_t covered = 0;
  for (size_t i = 0; i < all.id.size(); ++i) {
    covered += all.id[i] != kNoPatch;
    ASSERT_EQ(all.id[i], reversed.id[i]) << i;
    ASSERT_EQ(all.id[i], a.id[i]) << i;
    ASSERT_EQ(0, std::memcmp(&all.color[i], &a.color[i], sizeof(glm::vec3))) << i;
  }
  EXPECT_GT(covered, 100u);
  EXPECT_EQ(all.id[16 * 64 + 24], 0u);  // the near quad (world +x, +y) covers the upper left
  EXPECT_GT(all.color[16 * 64 + 24].x, 0.0f);
}

}  // namespace
}  // namespace vismask
