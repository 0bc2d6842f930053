// Random numbers that depend only on what they are for, never on the order in
// which environments or ranks run: each shot seeds its own stream from
// (run seed, shooting patch's global id, how many times that patch has shot),
// and draws a fixed number of values per ray. The stream is PCG32 (O'Neill).
#pragma once
#include <cstdint>

namespace vismask {

// SplitMix64's finaliser: a bijective 64-bit mix.
inline uint64_t Mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  Rng(uint64_t seed, uint64_t stream) : state_(0), inc_((stream << 1) | 1u) {
    NextU32();
    state_ += seed;
    NextU32();
  }
  uint32_t NextU32() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    uint32_t xorshifted = static_cast<uint32_t>(((old >> 18) ^ old) >> 27);
    uint32_t rot = static_cast<uint32_t>(old >> 59);
    return (xorshifted >> rot) | (xorshifted << ((32 - rot) & 31));
  }
  // Uniform in [0, 1), 24 random bits.
  float NextFloat() { return static_cast<float>(NextU32() >> 8) * (1.0f / 16777216.0f); }

 private:
  uint64_t state_;
  uint64_t inc_;
};

// The 64-bit key of one shot: what a packet carries so that any environment
// can regenerate the shot's rays.
inline uint64_t ShotKey(uint64_t runSeed, uint32_t patchGlobalId, uint32_t shotIndex) {
  return Mix64(Mix64(runSeed) ^ ((static_cast<uint64_t>(patchGlobalId) << 32) | shotIndex));
}

// The stream of every local shot of one patch in one environment, with
// Sobol' points: shot k takes the points after those of shots 0..k-1, so
// that the patch's rays over all its shots are one stratified prefix.
inline uint64_t PatchStream(uint64_t runSeed, uint32_t patchGlobalId) {
  return Mix64(ShotKey(runSeed, patchGlobalId, 0) ^ 0xa0761d6478bd642full);
}

// The stream of a foreign environment's rays for a shot: fresh samples, as
// in the paper, where every environment makes its own Monte Carlo estimate.
// Any environment can make another's (--centre-rays read).
inline uint64_t ForeignStream(uint64_t shotKey, uint32_t env) {
  return Mix64(shotKey ^ (0x9e3779b97f4a7c15ull * (uint64_t(env) + 1)));
}

inline Rng ShotRng(uint64_t shotKey) {
  return Rng(Mix64(shotKey), shotKey);
}

}  // namespace vismask
