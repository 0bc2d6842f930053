// Low-discrepancy samples for a shot's rays: the first five dimensions of
// Sobol' (Joe & Kuo's direction numbers), each Owen-scrambled with a hash
// (Laine & Karras; Burley 2020, "Practical Hash-based Owen Scrambling").
// Point i of a shot depends only on (shot seed, i), so any environment can
// regenerate ray i of a shot from its key, and any prefix of a shot's points
// is stratified: the first 2^k points put one point in each of 2^k
// elementary intervals of every pair of the first two dimensions.
#pragma once
#include <cstdint>

namespace vismask {

constexpr int kSobolDims = 5;

// Unscrambled Sobol' point `index`, dimension `dim` (< kSobolDims), as a
// 32-bit fixed-point fraction.
uint32_t SobolBits(uint32_t index, int dim);

inline uint32_t ReverseBits32(uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
  return (x >> 16) | (x << 16);
}
// Laine & Karras' hash, an Owen scramble of a bit-reversed fraction.
inline uint32_t LaineKarras(uint32_t x, uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}
// Owen scrambling of a 32-bit fraction, nested uniform, keyed by `seed`.
inline uint32_t OwenScramble(uint32_t x, uint32_t seed) {
  return ReverseBits32(LaineKarras(ReverseBits32(x), seed));
}

// The scrambled points of one shot, in Gray-code order: ray r of a shot is
// Sobol' point r ^ (r >> 1), so the first 2^k rays are the first 2^k points
// and the points can be walked one XOR per dimension at a time.
class ShotSampler {
 public:
  explicit ShotSampler(uint64_t shotSeed);
  // Point `ray` (random access), dimensions 0..kSobolDims-1, in [0, 1).
  void Point(uint32_t ray, float out[kSobolDims]) const;
  // Sequential access: Start() then Next() gives points 0, 1, 2, ...
  void Start();
  void Next(float out[kSobolDims]);
  // Point `ray`, reached from the sequential state by the columns where the
  // two points' Gray codes differ (rays taken in increasing order cost a few
  // XORs each); the same bits as Point(ray). Next() then gives ray + 1.
  void Seek(uint32_t ray, float out[kSobolDims]);

 private:
  void Emit(const uint32_t state[kSobolDims], float out[kSobolDims]) const;
  uint32_t seed_[kSobolDims];
  uint32_t state_[kSobolDims];  // bit-reversed unscrambled point `next_`
  uint32_t next_ = 0;
};

}  // namespace vismask
