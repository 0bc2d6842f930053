#include "vismask/solve/sobol.h"

#include "vismask/solve/rng.h"

namespace vismask {

namespace {

// Joe & Kuo (new-joe-kuo-6.21201), dimensions 2-5: degree s, coefficients a
// and initial m_1..m_s. Dimension 1 is van der Corput.
struct Primitive {
  int s;
  uint32_t a;
  uint32_t m[4];
};
constexpr Primitive kPrimitives[kSobolDims - 1] = {
    {1, 0, {1, 0, 0, 0}}, {2, 1, {1, 3, 0, 0}}, {3, 1, {1, 3, 1, 0}}, {3, 2, {1, 1, 1, 0}}};

struct Matrices {
  uint32_t v[kSobolDims][32];
};

constexpr Matrices MakeMatrices() {
  Matrices t{};
  for (int k = 0; k < 32; ++k) t.v[0][k] = 1u << (31 - k);
  for (int d = 1; d < kSobolDims; ++d) {
    const Primitive& p = kPrimitives[d - 1];
    for (int k = 0; k < 32; ++k) {
      if (k < p.s) {
        t.v[d][k] = p.m[k] << (31 - k);
      } else {
        uint32_t v = t.v[d][k - p.s] ^ (t.v[d][k - p.s] >> p.s);
        for (int j = 1; j < p.s; ++j)
          if ((p.a >> (p.s - 1 - j)) & 1u) v ^= t.v[d][k - j];
        t.v[d][k] = v;
      }
    }
  }
  return t;
}

constexpr Matrices kMatrices = MakeMatrices();

// The same columns bit-reversed: rev(point) is the XOR of these.
constexpr Matrices MakeReversed() {
  Matrices t = MakeMatrices();
  for (int d = 0; d < kSobolDims; ++d)
    for (int k = 0; k < 32; ++k) {
      uint32_t x = t.v[d][k], r = 0;
      for (int b = 0; b < 32; ++b) r |= ((x >> b) & 1u) << (31 - b);
      t.v[d][k] = r;
    }
  return t;
}

constexpr Matrices kReversed = MakeReversed();

inline float ToUnit(uint32_t x) {
  return static_cast<float>(x >> 8) * (1.0f / 16777216.0f);
}

}  // namespace

uint32_t SobolBits(uint32_t index, int dim) {
  uint32_t x = 0;
  const uint32_t* v = kMatrices.v[dim];
  for (int k = 0; index != 0; index >>= 1, ++k)
    if (index & 1u) x ^= v[k];
  return x;
}

ShotSampler::ShotSampler(uint64_t shotSeed) {
  for (int d = 0; d < kSobolDims; ++d) {
    seed_[d] = static_cast<uint32_t>(Mix64(shotSeed + 0x632be59bd9b4e019ull * uint64_t(d + 1)));
    state_[d] = 0;
  }
}

void ShotSampler::Emit(const uint32_t state[kSobolDims], float out[kSobolDims]) const {
  for (int d = 0; d < kSobolDims; ++d)
    out[d] = ToUnit(ReverseBits32(LaineKarras(state[d], seed_[d])));
}

void ShotSampler::Point(uint32_t ray, float out[kSobolDims]) const {
  uint32_t gray = ray ^ (ray >> 1), state[kSobolDims] = {0, 0, 0, 0, 0};
  for (int k = 0; gray != 0; gray >>= 1, ++k)
    if (gray & 1u)
      for (int d = 0; d < kSobolDims; ++d) state[d] ^= kReversed.v[d][k];
  Emit(state, out);
}

void ShotSampler::Seek(uint32_t ray, float out[kSobolDims]) {
  uint32_t diff = (ray ^ (ray >> 1)) ^ (next_ ^ (next_ >> 1));
  for (int k = 0; diff != 0; diff >>= 1, ++k)
    if (diff & 1u)
      for (int d = 0; d < kSobolDims; ++d) state_[d] ^= kReversed.v[d][k];
  next_ = ray;
  Next(out);
}

void ShotSampler::Start() {
  next_ = 0;
  for (int d = 0; d < kSobolDims; ++d) state_[d] = 0;
}

void ShotSampler::Next(float out[kSobolDims]) {
  Emit(state_, out);
  // Gray code: point r + 1 differs from point r in column ctz(r + 1).
  ++next_;
  int k = __builtin_ctz(next_);
  for (int d = 0; d < kSobolDims; ++d) state_[d] ^= kReversed.v[d][k];
}

}  // namespace vismask
