// Patch4 (src/patch4.h) against IntersectPatch, lane by lane and bit for
// bit: random patches and rays, rays through edges and corners, rays in a
// patch's plane, and rays that end exactly at the hit.
#include "../src/patch4.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "grid_test_util.h"

namespace vismask {
namespace {

using namespace gridtest;

struct Tally {
  int groups = 0, hits = 0, misses = 0, failures = 0;
  int reordered = 0;  // hits whose t changes if denom's sum is reassociated
};

// IntersectPatch's t with denom summed in another order: the data must be
// able to tell (else a lane with its own order could pass unnoticed).
float ReorderedT(const PatchGeom& g, const Ray& ray) {
  float denom = g.n.x * ray.d.x + (g.n.y * ray.d.y + g.n.z * ray.d.z);
  float num = g.d - (g.n.x * ray.o.x + g.n.y * ray.o.y + g.n.z * ray.o.z);
  return num / denom;
}

void Check(const std::vector<PatchGeom>& geom, const uint32_t* idx, const Ray& ray, Tally* tally) {
  const PatchGeom* g[4] = {&geom[idx[0]], &geom[idx[1]], &geom[idx[2]], &geom[idx[3]]};
  float t[4];
  unsigned front = 0;
  patch4::Ray4 r4(ray);
  unsigned m = patch4::Intersect4(g, r4, t, &front);
  ++tally->groups;
  for (unsigned i = 0; i < 4; ++i) {
    float want;
    bool wantFront;
    bool hit = IntersectPatch(*g[i], ray, &want, &wantFront);
    bool got = ((m >> i) & 1) != 0;
    bool same = hit == got;
    if (hit && got) same = Bits(t[i]) == Bits(want) && (((front >> i) & 1) != 0) == wantFront;
    if (!same) {
      ++tally->failures;
      continue;
    }
    if (!hit) {
      ++tally->misses;
      continue;
    }
    ++tally->hits;
    if (Bits(ReorderedT(*g[i], ray)) != Bits(want)) ++tally->reordered;
  }
}

TEST(Patch4Test, EveryLaneMatchesIntersectPatchBitForBit) {
  std::mt19937 rng(19);
  TestScene s;
  AddRandomPatches(rng, 200, glm::vec3(0.0f), glm::vec3(1.0f), 0.02f, 0.6f, &s);
  AddBlock(glm::vec3(0.2f), glm::vec3(0.7f), 2, &s);  // axis-aligned: exact parallel rays
  size_t n = s.geom.size();
  for (size_t i = 0; i < n; ++i) s.geom.push_back(TwinGeom(s.geom[i]));
  std::vector<Patch> patches = s.patches;
  for (size_t i = 0; i < n; ++i) patches.push_back(s.patches[i]);
  std::uniform_real_distribution<float> u(-0.2f, 1.2f), unit(0.0f, 1.0f);
  std::uniform_int_distribution<uint32_t> pick(0, static_cast<uint32_t>(s.geom.size() - 1));
  Tally tally;
  int parallel = 0, grazing = 0, exactEnd = 0;
  for (int k = 0; k < 40000; ++k) {
    uint32_t idx[4] = {pick(rng), pick(rng), pick(rng), pick(rng)};
    const Patch& target = patches[idx[k % 4]];
    Ray ray;
    ray.o = glm::vec3(u(rng), u(rng), u(rng));
    ray.tMin = 0.0f;
    ray.tMax = kInf;
    glm::vec3 aim;
    switch (k % 5) {
      case 0:  // anywhere
        aim = glm::vec3(u(rng), u(rng), u(rng));
        break;
      case 1: {  // a point on one of the target's edges (a shared edge, a corner)
        uint32_t e = rng() % target.numCorners;
        const glm::vec3& a = target.corner[e];
        const glm::vec3& b = target.corner[(e + 1) % target.numCorners];
        float w = (k % 3 == 0) ? 0.0f : unit(rng);
        aim = a + w * (b - a);
        ++grazing;
        break;
      }
      case 2:  // inside the target
        aim = PointOnPatch(rng, target);
        break;
      case 3: {  // along the target's plane: denom 0 (or nearly)
        glm::vec3 n = target.normal;
        glm::vec3 t = glm::vec3(n.y - n.z, n.z - n.x, n.x - n.y);
        ray.o = PointOnPatch(rng, target) - 0.5f * t;
        aim = ray.o + t;
        ++parallel;
        break;
      }
      default: {  // axis-aligned direction (exactly parallel to the block's faces)
        aim = ray.o;
        aim[k % 3] += (k & 8) ? 1.0f : -1.0f;
        ++parallel;
        break;
      }
    }
    ray.d = aim - ray.o;
    if (k % 7 == 0) ray.d *= 1e-3f;  // tiny directions: large t
    if (k % 11 == 0) {
      // End the ray exactly at a hit, or just past: the (tMin, tMax) bounds.
      float t;
      bool front;
      if (IntersectPatch(s.geom[idx[0]], ray, &t, &front)) {
        ray.tMax = (k & 1) ? t : std::nextafter(t, kInf);
        ray.tMin = (k & 2) ? 0.0f : std::nextafter(t, -kInf);
        ++exactEnd;
      }
    }
    Check(s.geom, idx, ray, &tally);
  }
  EXPECT_EQ(tally.failures, 0) << tally.groups << " groups";
  EXPECT_GT(tally.hits, 10000);
  EXPECT_GT(tally.misses, 10000);
  EXPECT_GT(grazing, 1000);
  EXPECT_GT(parallel, 1000);
  EXPECT_GT(exactEnd, 100);
  // The comparison is sensitive to the order of operations.
  EXPECT_GT(tally.reordered, 100);
}

// The check itself can fail: a lane whose t is one ulp off is caught.
TEST(Patch4Test, ComparisonCatchesOneUlp) {
  std::mt19937 rng(7);
  TestScene s;
  AddRandomPatches(rng, 4, glm::vec3(0.4f), glm::vec3(0.6f), 0.5f, 0.6f, &s);
  Ray ray{glm::vec3(0.5f, 0.5f, -2.0f), glm::vec3(0.01f, 0.02f, 1.0f), 0.0f, kInf};
  const PatchGeom* g[4] = {&s.geom[0], &s.geom[1], &s.geom[2], &s.geom[3]};
  float t[4];
  unsigned front;
  unsigned m = patch4::Intersect4(g, patch4::Ray4(ray), t, &front);
  int hits = 0;
  for (unsigned i = 0; i < 4; ++i) {
    float want;
    bool wantFront;
    if (!IntersectPatch(*g[i], ray, &want, &wantFront)) continue;
    ++hits;
    ASSERT_TRUE((m >> i) & 1);
    EXPECT_EQ(Bits(t[i]), Bits(want));
    EXPECT_NE(Bits(std::nextafter(t[i], kInf)), Bits(want));
  }
  EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace vismask
