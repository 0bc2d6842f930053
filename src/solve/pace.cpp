// --max-seconds's pacing (pace.h).
#include "vismask/solve/pace.h"

#include <algorithm>
#include <cmath>

#include "vismask/solve/environment.h"

namespace vismask {

namespace {

// Re-planned every kIntervals-th of the time to the target end; the rate is
// the rays over the last intervals, each weighing kRecent, since the shots
// shrink as the solve goes and their rays cost more each.
constexpr double kIntervals = 64.0;
constexpr double kRecent = 0.5;
// A re-plan moves the quantum by at most this factor either way.
constexpr double kMostStep = 2.0;
// The shots' own reflectance once they have shot this share of the emitted power.
constexpr double kMeasuredRho = 0.05;

}  // namespace

double Pacer::Quantum(double worth, double rate, double seconds) {
  if (!(worth > 0.0) || !(rate > 0.0) || !(seconds > 0.0)) return 0.0;
  return worth / (rate * seconds);
}

double Pacer::WorthLeft(double unshot, double emission, double f, double rho, double stop) {
  const double reflected = std::fmax(unshot - emission + rho * emission - stop, 0.0);
  return f * emission + reflected / (1.0 - rho);
}

void Pacer::AfterRound(const RoundTotals& t, Span<Environment* const> envs) {
  if (envs.empty()) return;
  const Environment* env = envs[0];
  const double step = in_.endSeconds / kIntervals;
  if (t.elapsed < lastSeconds_ + step) return;
  const double seconds = t.elapsed - lastSeconds_;
  const double rate = static_cast<double>(t.rays - lastRays_) / seconds;
  rate_ = rate_ > 0.0 ? (1.0 - kRecent) * rate_ + kRecent * rate : rate;
  lastSeconds_ = t.elapsed;
  lastRays_ = t.rays;
  if (q0_ == 0.0) q0_ = env->rayQuantum();
  // The time the quantum spends: what the tail leaves (near the end, none:
  // the quantum stays).
  const double left = in_.endSeconds - t.elapsed - in_.tailRays / rate_;
  if (!(left > step) || !(t.emitted > 0.0)) return;
  const double e = t.emission;
  // What comes back of the power shot so far (the open sides of a scene
  // lose light that the mean kd does not know of).
  const double shot = t.radiosity - t.unshot, reflected = t.radiosity - t.emitted;
  const double rho = shot > kMeasuredRho * t.emitted && reflected >= 0.0
                         ? std::fmin(reflected / shot, 0.95)
                         : in_.rho;
  const double worth = WorthLeft(t.unshot, e, env->emissionRays(), rho, in_.stopUnshot * t.emitted);
  const double q = Quantum(worth, rate_, left);
  if (!(q > 0.0)) return;
  const double now = env->rayQuantum();
  const double next = std::clamp(q, now / kMostStep, now * kMostStep);
  for (Environment* each : envs) each->SetRayQuantum(next);
  scale_ = next / q0_;
  ++updates_;
}

}  // namespace vismask
