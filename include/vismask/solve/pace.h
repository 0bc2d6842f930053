// --max-seconds's pacing: a planned solve (one rank, power allocation,
// --emitted-rays from the plan) spends its budget by re-planning its ray
// quantum as it goes. Several environments are paced as one:
// the quantum is the same in all of them, and it is re-planned from the
// round's totals alone (rank 0's clock, the sums in environment order), so
// every rank would set the same one at the same round. The plan's rate is
// timed at init on 20 000 rays and the solve's own rate differs from it
// (its shots land, book and split elements), so a plan alone ends its
// solves anywhere from 70% to past 100% of T. The pacer measures the rate
// the solve traces at, estimates the ray worth still to shoot (the unshot
// power, the emission's at its --emission-rays share, and what the power
// reflects until --stop-unshot), and sets the quantum that spends those
// rays by the target end. Each shot stays an unbiased estimate whatever
// its ray count; only the rays per unit power move. The outputs then
// depend on the timing, as every --max-seconds run's already do through
// the plan.
#pragma once
#include <cstdint>

#include "vismask/core/span.h"
#include "vismask/solve/exchange.h"

namespace vismask {

class Environment;

struct PaceInput {
  double endSeconds = 0.0;  // the solve's clock at which it should converge
  double rho = 0.5;         // the plan's reflectance, until the shots measure theirs
  double stopUnshot = 1e-3;
  // The tail: the rays of the small shots at the end, at --min-rays each
  // whatever the quantum (plan.h's TailRays), paid from the time left first.
  double tailRays = 0.0;
  // Shot costs: the shots carry hemisphere masks (several environments,
  // Methods A, B and C), whose cost does not go as their rays. The time
  // the shots left (ShotsLeft, from tailShots: plan.h's TailShots) take at
  // the work a shot costs (Environment::shotWork) is then paid first too,
  // and the rays' rate is the work a second over the work a ray costs.
  bool shotCosts = false;
  double tailShots = 0.0;
};

class Pacer {
 public:
  explicit Pacer(const PaceInput& in) : in_(in) {}
  // After a round: re-plans the environments' ray quantum (theirs all
  // alike: `envs` are this rank's) when an interval of the solve's clock
  // has passed since the last time.
  void AfterRound(const RoundTotals& totals, Span<Environment* const> envs);
  // The quantum's last change over the plan's (1: never re-planned), and
  // how many times it was re-planned.
  double scale() const { return scale_; }
  uint32_t updates() const { return updates_; }

  // The quantum that spends `worth` (ray worth left, in power) at `rate`
  // rays a second in `seconds` (exposed for tests).
  static double Quantum(double worth, double rate, double seconds);
  // The shots a solve with shot costs still makes: `tail` local shots
  // (each with foreign ones at the ratio of `shots` made, `foreign` of
  // them) less those made, or `perDecade` for each tenfold fall from
  // `unshot` to `stop`, whichever is more.
  static double ShotsLeft(double tail, uint64_t shots, uint64_t foreign, double perDecade,
                          double unshot, double stop);
  // The power still to shoot, in ray worth: unshot power U of which E is
  // emission not yet shot (shot at share f), reflected at rho until the
  // unshot falls to `stop` of the emitted power.
  static double WorthLeft(double unshot, double emission, double f, double rho, double stop);

 private:
  // With shot costs: the work a second, a ray and a shot, and the shots a
  // tenfold fall, over the interval since the last re-plan.
  void MeasureShots(const RoundTotals& t, double seconds);

  PaceInput in_;
  double lastSeconds_ = 0.0;
  uint64_t lastRays_ = 0;
  double rate_ = 0.0;
  // With shot costs: the last re-plan's totals, and the work a second, a
  // ray and a shot, and the shots a tenfold fall, over recent intervals.
  uint64_t lastWork_ = 0, lastShotWork_ = 0, lastShots_ = 0;
  double lastUnshot_ = 0.0;
  double workRate_ = 0.0, rayWork_ = 0.0, shotWork_ = 0.0, perDecade_ = 0.0;
  double q0_ = 0.0;
  double scale_ = 1.0;
  uint32_t updates_ = 0;
};

}  // namespace vismask
