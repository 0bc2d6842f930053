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
// A re-plan moves the quantum by at most this factor either way; with shot
// costs, whose estimates move as the shots change, by a smaller one: the
// rays a unit of power gets had best not swing, for a shot at a coarse
// quantum is a noisy one (the Cornell box in 2x2 environments, Method B,
// --max-seconds 10: at 2, 1.84% from Cycles cut at 0.15% unshot; at 1.25,
// 1.34% converged in 9.6 s).
constexpr double kMostStep = 2.0;
constexpr double kMostShotStep = 1.25;
// With shot costs, the quantum only coarsens while more than this share of
// the emission is still to shoot: the emitters' shots come first, with the
// dearest masks, and the pace's estimates of the shots to come are not yet
// theirs.
constexpr double kEmissionShot = 0.01;
// The shots' own reflectance once they have shot this share of the emitted power.
constexpr double kMeasuredRho = 0.05;

// A rate over the last intervals, each weighing kRecent.
double Recent(double before, double now) {
  return before > 0.0 ? (1.0 - kRecent) * before + kRecent * now : now;
}

}  // namespace

double Pacer::Quantum(double worth, double rate, double seconds) {
  if (!(worth > 0.0) || !(rate > 0.0) || !(seconds > 0.0)) return 0.0;
  return worth / (rate * seconds);
}

double Pacer::WorthLeft(double unshot, double emission, double f, double rho, double stop) {
  const double reflected = std::fmax(unshot - emission + rho * emission - stop, 0.0);
  return f * emission + reflected / (1.0 - rho);
}

double Pacer::ShotsLeft(double tail, uint64_t shots, uint64_t foreign, double perDecade,
                        double unshot, double stop) {
  const double made = static_cast<double>(shots);
  const double local = made - static_cast<double>(foreign);
  const double byTail = local > 0.0 ? tail * made / local - made : tail;
  const double byFalls = unshot > stop && stop > 0.0 ? perDecade * std::log10(unshot / stop) : 0.0;
  return std::fmax(std::fmax(byTail, byFalls), 0.0);
}

void Pacer::MeasureShots(const RoundTotals& t, double seconds) {
  const double work = static_cast<double>(t.paceWork - lastWork_);
  const double shotWork = static_cast<double>(t.shotWork - lastShotWork_);
  const double rays = static_cast<double>(t.rays - lastRays_);
  const double shots = static_cast<double>(t.shots - lastShots_);
  workRate_ = Recent(workRate_, work / seconds);
  if (rays > 0.0) rayWork_ = Recent(rayWork_, std::fmax(work - shotWork, 0.0) / rays);
  // A shot's work: the least over an interval so far, for the first shots
  // (the emitters', their masks' casts uncached) cost the most and those to
  // come are the small ones (the 2x2 run above: from 82 000 down to 12 300).
  if (shots > 0.0)
    shotWork_ = shotWork_ > 0.0 ? std::fmin(shotWork_, shotWork / shots) : shotWork / shots;
  const double before = lastUnshot_ > 0.0 ? lastUnshot_ : t.emitted;
  if (shots > 0.0 && t.unshot > 0.0 && before > t.unshot)
    perDecade_ = Recent(perDecade_, shots / std::log10(before / t.unshot));
  lastWork_ = t.paceWork;
  lastShotWork_ = t.shotWork;
  lastShots_ = t.shots;
  lastUnshot_ = t.unshot;
}

void Pacer::AfterRound(const RoundTotals& t, Span<Environment* const> envs) {
  if (envs.empty()) return;
  const Environment* env = envs[0];
  const double step = in_.endSeconds / kIntervals;
  if (t.elapsed < lastSeconds_ + step) return;
  const double seconds = t.elapsed - lastSeconds_;
  rate_ = Recent(rate_, static_cast<double>(t.rays - lastRays_) / seconds);
  // The rays' rate, and the seconds the shots left take beside their rays.
  double rayRate = rate_, shotSeconds = 0.0;
  if (in_.shotCosts) {
    MeasureShots(t, seconds);
    if (rayWork_ > 0.0 && workRate_ > 0.0) {
      rayRate = workRate_ / rayWork_;
      shotSeconds = ShotsLeft(in_.tailShots, t.shots, t.foreignShots, perDecade_, t.unshot,
                              in_.stopUnshot * t.emitted) *
                    shotWork_ / workRate_;
    }
  }
  lastSeconds_ = t.elapsed;
  lastRays_ = t.rays;
  if (q0_ == 0.0) q0_ = env->rayQuantum();
  // The time the quantum spends: what the tail leaves (near the end, none:
  // the quantum stays). With shot costs, shots that would take all of it
  // are behind: the quantum coarsens as fast as it may.
  const double left = in_.endSeconds - t.elapsed - in_.tailRays / rayRate - shotSeconds;
  const bool behind = in_.shotCosts && !(left > step) && t.elapsed < in_.endSeconds;
  if ((!behind && !(left > step)) || !(t.emitted > 0.0)) return;
  const double e = t.emission;
  // What comes back of the power shot so far (the open sides of a scene
  // lose light that the mean kd does not know of).
  const double shot = t.radiosity - t.unshot, reflected = t.radiosity - t.emitted;
  const double rho = shot > kMeasuredRho * t.emitted && reflected >= 0.0
                         ? std::fmin(reflected / shot, 0.95)
                         : in_.rho;
  const double worth = WorthLeft(t.unshot, e, env->emissionRays(), rho, in_.stopUnshot * t.emitted);
  const double now = env->rayQuantum();
  const double most = in_.shotCosts ? kMostShotStep : kMostStep;
  const double q = behind ? now * most : Quantum(worth, rayRate, left);
  if (!(q > 0.0)) return;
  double next = std::clamp(q, now / most, now * most);
  if (in_.shotCosts && e >= kEmissionShot * t.emitted) next = std::fmax(next, now);
  for (Environment* each : envs) each->SetRayQuantum(next);
  scale_ = next / q0_;
  ++updates_;
}

}  // namespace vismask
