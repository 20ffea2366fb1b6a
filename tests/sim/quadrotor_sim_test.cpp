#include "timeopt/sim/quadrotor_sim.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "timeopt/curve/interpolation.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;

// With the three poles at -w, an error that starts as e(0) = e0, e'(0) = e''(0) = 0 evolves as
//   e(t) = e0 (1 + x + x^2 / 2) exp(-x),  e'(t) = -e0 w x^2 / 2 exp(-x),  x = w t,
// and one that starts as e''(0) = D (a jump D of the reference acceleration, which the vehicle cannot
// follow) with e(0) = e'(0) = 0 as e(t) = D t^2 / 2 exp(-x), so that
//   e'(t) = (D / w) (x - x^2 / 2) exp(-x),  e''(t) = D (1 - 2 x + x^2 / 2) exp(-x).
// The extrema used below: e''/D has its minimum -0.2060 at x = 3 - sqrt 3, e' its maximum at
// x = 2 - sqrt 2, and |e'| in the first case at x = 2.
double JumpAccelerationOvershoot() {  // -min e''/D
  const double x = 3.0 - std::sqrt(3.0);
  return -(1.0 - 2.0 * x + 0.5 * x * x) * std::exp(-x);
}
double JumpVelocityOvershoot(double w) {  // max e'/D
  const double x = 2.0 - std::sqrt(2.0);
  return (x - 0.5 * x * x) * std::exp(-x) / w;
}

TemporalLimits Limits(double vmax, double amax) {
  TemporalLimits limits;
  limits.max_velocity.setConstant(vmax);
  limits.max_acceleration.setConstant(amax);
  return limits;
}

// The controller holds u over each step of dt: the discrete loop lags the continuous one by about
// dt / 2, so values along the flight differ from the closed forms by about w dt / 2 relative (here
// 5e-4; measured 1e-4 to 5e-4 depending on where a jump falls between updates). The tolerances are
// twice that. (The triple pole itself splits by about (w dt / 2)^(1/3), which matters only for the
// exponential tail, see the first test.)
constexpr double kW = 10.0, kDt = 1e-4, kZohTolerance = 1e-3;

QuadrotorSimOptions Options() {
  QuadrotorSimOptions o;
  o.bandwidth = kW;
  o.time_step = kDt;
  o.settle_time = 0.0;
  return o;
}

TEST(QuadrotorSim, InitialErrorDecaysAsTheTriplePole) {
  QuadrotorSimOptions o = Options();
  o.initial_position_error = Eigen::Vector3d(0.1, 0.0, 0.0);
  o.record_states = true;
  const FeasibilityReport report =
      QuadrotorSim(o).Run([](double t) { return TrajectoryState{t}; }, 2.0, Limits(1.0, 10.0));
  ASSERT_EQ(report.states.size(), 20001u);
  double worst = 0.0;
  for (const SimState& s : report.states) {
    const double x = kW * s.t;
    worst = std::max(worst, std::abs(s.position.x() - 0.1 * (1.0 + x + 0.5 * x * x) * std::exp(-x)));
    EXPECT_EQ(s.position.y(), 0.0);
  }
  EXPECT_LT(worst, kZohTolerance * 0.1);
  // Peak speed 0.1 w 2 exp(-2) = 0.2707 m/s at t = 2 / w; vmax = 1.
  EXPECT_NEAR(report.max_velocity_ratio, 0.1 * kW * 2.0 * std::exp(-2.0), kZohTolerance * 0.2707);
  EXPECT_NEAR(report.max_velocity_time, 2.0 / kW, 2e-3);
  EXPECT_TRUE(report.feasible) << report.message;
  EXPECT_NEAR(report.max_position_error, 0.1, 1e-12);
  // At t = 2 s (x = 20) the error is 4.6e-8 m. The held command splits the triple pole (to -1.09 w
  // and -0.96 w +- 0.06 w i at w dt = 1e-3), which changes this far tail by 2.4%: 5% allowed.
  const double final_error = 0.1 * (1 + 20 + 200) * std::exp(-20.0);
  EXPECT_NEAR(report.final_position_error, final_error, 0.05 * final_error);
}

// The reference accelerates at D = 1 m/s^2 from t = 0.5 s; the vehicle's acceleration overshoots to
// 1.2060 D at t = 0.5 + (3 - sqrt 3) / w.
TEST(QuadrotorSim, AccelerationJumpOvershootsAsTheClosedForm) {
  const auto reference = [](double t) {
    TrajectoryState r{t};
    if (t >= 0.5) {
      const double tau = t - 0.5;
      r.position.x() = 0.5 * tau * tau;
      r.velocity.x() = tau;
      r.acceleration.x() = 1.0;
    }
    return r;
  };
  QuadrotorSimOptions o = Options();
  o.record_states = true;
  const FeasibilityReport report = QuadrotorSim(o).Run(reference, 1.5, Limits(10.0, 1.0));
  const double expected = 1.0 + JumpAccelerationOvershoot();
  EXPECT_NEAR(expected, 1.2060, 1e-4);
  EXPECT_NEAR(report.max_acceleration_ratio, expected, kZohTolerance * expected);
  EXPECT_NEAR(report.max_acceleration_time, 0.5 + (3.0 - std::sqrt(3.0)) / kW, 2e-3);
  EXPECT_FALSE(report.feasible);
  EXPECT_THAT(report.message, HasSubstr("|a_x| reaches 1.20"));

  // The per-step maxima are exact: sampling every step's polynomials 50 times finds nothing larger,
  // and comes within the sampling error of the reported values.
  double sampled_v = 0.0, sampled_a = 0.0;
  for (size_t k = 0; k + 1 < report.states.size(); ++k) {
    const SimState& s = report.states[k];
    for (int q = 0; q <= 50; ++q) {
      const double tau = kDt * q / 50.0;
      sampled_v =
          std::max(sampled_v, std::abs(s.velocity.x() + s.acceleration.x() * tau + 0.5 * s.jerk.x() * tau * tau));
      sampled_a = std::max(sampled_a, std::abs(s.acceleration.x() + s.jerk.x() * tau));
    }
  }
  EXPECT_LE(sampled_v / 10.0, report.max_velocity_ratio * (1 + 1e-14));
  EXPECT_NEAR(sampled_v / 10.0, report.max_velocity_ratio, 1e-12);
  EXPECT_LE(sampled_a, report.max_acceleration_ratio * (1 + 1e-14));
  EXPECT_NEAR(sampled_a, report.max_acceleration_ratio, 1e-12);
}

// The contract example (a 10 m line, vmax 2, amax 1, rest to rest): the optimal profile accelerates at
// amax for 2 m (10 cells of K = 50), cruises, and brakes at amax, so the reference acceleration
// jumps by amax where cruise begins and ends. The vehicle overshoots vmax after the first jump and
// amax after the second, by the closed forms (the first transient has decayed, exp(-30), before the
// second jump 3 s later).
TEST(QuadrotorSim, TimeOptimalLineOvershootsAtTheAccelerationJumps) {
  const TemporalProblem problem =
      ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json");
  const TemporalResult result = MakeSocpTemporalSolver()->Solve(problem);
  ASSERT_TRUE(result.is_success()) << result.message;
  ASSERT_NEAR(result.total_time, 7.0, 1e-7);
  const Trajectory trajectory(problem.curve, result.profile);
  QuadrotorSimOptions o = Options();
  o.settle_time = 1.0;
  const FeasibilityReport report = QuadrotorSim(o).Run(trajectory, problem.limits);
  const double vmax = 2.0, amax = 1.0;
  // The transients scale with amax / w (velocity) and amax (acceleration).
  EXPECT_NEAR(report.max_velocity_ratio, 1.0 + amax * JumpVelocityOvershoot(kW) / vmax,
              kZohTolerance * amax / kW / vmax);
  EXPECT_NEAR(report.max_acceleration_ratio, 1.0 + JumpAccelerationOvershoot(), kZohTolerance * amax);
  EXPECT_NEAR(report.max_acceleration_time, 5.0 + (3.0 - std::sqrt(3.0)) / kW, 2e-3);
  EXPECT_FALSE(report.feasible);
  EXPECT_THAT(report.message, HasSubstr("|v_x| reaches 1.01"));
  EXPECT_THAT(report.message, HasSubstr("|a_x| reaches 1.20"));
  // The vehicle ends at the goal: the last jump's transient decays as exp(-w t) over the settle time.
  EXPECT_LT(report.final_position_error, 1e-3);
}

// A cubic reference has constant jerk, so the feedforward alone is exact: starting on it, the vehicle
// stays on it to rounding (any integration error, or a missing or wrong jerk feedforward, shows up
// at once: forward Euler is off by 1e-5 m here).
TEST(QuadrotorSim, FollowsACubicReferenceExactly) {
  const Eigen::Vector3d c(0.5, -0.2, 0.1);  // p = c t^3
  const auto cubic = [&c](double t) {
    TrajectoryState r{t};
    r.position = c * t * t * t;
    r.velocity = 3.0 * c * t * t;
    r.acceleration = 6.0 * c * t;
    r.jerk = 6.0 * c;
    return r;
  };
  QuadrotorSimOptions o = Options();
  o.record_states = true;
  const FeasibilityReport report = QuadrotorSim(o).Run(cubic, 2.0, Limits(100.0, 100.0));
  // |p| <= 4 m over the flight; rounding of 20,000 exact updates stays below 1e-11 m.
  EXPECT_LT(report.max_position_error, 1e-11);
  // v peaks at t = 2 on x: 3 * 0.5 * 4 = 6 m/s; a peaks at 6 * 0.5 * 2 = 6 m/s^2.
  EXPECT_NEAR(report.max_velocity_ratio, 0.06, 1e-12);
  EXPECT_NEAR(report.max_acceleration_ratio, 0.06, 1e-12);
  // Every step is the exact cubic of the previous state under its held jerk.
  for (size_t k = 0; k + 1 < report.states.size(); ++k) {
    const SimState& s0 = report.states[k];
    const SimState& s1 = report.states[k + 1];
    const double h = s1.t - s0.t;
    const Eigen::Vector3d p = s0.position + h * s0.velocity + h * h / 2 * s0.acceleration + h * h * h / 6 * s0.jerk;
    ASSERT_LT((s1.position - p).norm(), 1e-13) << "step " << k;
    ASSERT_LT((s1.velocity - (s0.velocity + h * s0.acceleration + h * h / 2 * s0.jerk)).norm(), 1e-13);
  }
}

// With a coarse step (w dt = 0.1) and an initial acceleration error, the speed peaks inside a step:
// the report must find that peak and it must exceed every step-boundary speed measurably. Dense
// sampling (spacing 1e-6 s) can only miss the peak by |u| (5e-7 s)^2 / 2 < 1e-10 (|u| < 100 m/s^3).
TEST(QuadrotorSim, FindsTheSpeedPeakInsideAStep) {
  QuadrotorSimOptions o;
  o.bandwidth = 10.0;
  o.time_step = 0.01;
  o.settle_time = 0.0;
  o.initial_acceleration_error = Eigen::Vector3d(3.0, 0.0, 0.0);
  o.record_states = true;
  const FeasibilityReport report =
      QuadrotorSim(o).Run([](double t) { return TrajectoryState{t}; }, 1.0, Limits(1.0, 10.0));
  double sampled = 0.0, at_boundaries = 0.0;
  for (size_t k = 0; k + 1 < report.states.size(); ++k) {
    const SimState& s = report.states[k];
    at_boundaries = std::max(at_boundaries, std::abs(s.velocity.x()));
    for (int q = 0; q <= 10000; ++q) {
      const double tau = 0.01 * q / 10000.0;
      sampled = std::max(sampled, std::abs(s.velocity.x() + s.acceleration.x() * tau + 0.5 * s.jerk.x() * tau * tau));
    }
  }
  EXPECT_LE(sampled, report.max_velocity_ratio * (1 + 1e-14));
  EXPECT_NEAR(report.max_velocity_ratio, sampled, 1e-10);
  EXPECT_GT(report.max_velocity_ratio - at_boundaries, 1e-4);
}

TEST(QuadrotorSim, FlyStartsFromTheProblemsBoundaryState) {
  const TemporalProblem problem =
      ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json");
  const TemporalResult result = MakeSocpTemporalSolver()->Solve(problem);
  ASSERT_TRUE(result.is_success()) << result.message;
  const Trajectory trajectory(problem.curve, result.profile);
  // Without lambda_a the profile starts at amax (its first cell); the problem starts at rest.
  ASSERT_NEAR(trajectory.Evaluate(0.0).acceleration.x(), 1.0, 1e-6);
  QuadrotorSimOptions o = Options();
  o.record_states = true;
  const FeasibilityReport flown = QuadrotorSim(o).Fly(trajectory, problem.limits, problem.boundary.start_velocity,
                                                      problem.boundary.start_acceleration);
  EXPECT_EQ(flown.states.front().acceleration, Eigen::Vector3d::Zero());
  // The jump from rest to amax at t = 0 overshoots like the others (and by the same closed form).
  EXPECT_NEAR(flown.max_acceleration_ratio, 1.0 + JumpAccelerationOvershoot(), kZohTolerance * 1.0);
}

// Samples of a cubic hold its (constant) jerk between them, so the sampled reference is the cubic
// itself, shifted to start at 0: the flight matches the one on the function to rounding.
TEST(QuadrotorSim, SampledReferenceOfACubicIsTheCubic) {
  const auto cubic = [](double t) {
    TrajectoryState r{t};
    r.position = Eigen::Vector3d(0.5, -0.2, 0.1) * t * t * t + Eigen::Vector3d(1.0, 0.0, 0.0);
    r.velocity = 3.0 * Eigen::Vector3d(0.5, -0.2, 0.1) * t * t;
    r.acceleration = 6.0 * Eigen::Vector3d(0.5, -0.2, 0.1) * t;
    r.jerk = 6.0 * Eigen::Vector3d(0.5, -0.2, 0.1);
    return r;
  };
  std::vector<TrajectoryState> samples;
  for (int k = 0; k <= 20; ++k) {
    TrajectoryState s = cubic(0.1 * k);
    s.t += 3.0;  // another planner's clock
    samples.push_back(s);
  }
  const QuadrotorSim::Reference sampled = SampledReference(samples);
  for (double t : {0.0, 0.05, 0.123, 1.0, 1.999}) {
    EXPECT_LT((sampled(t).position - cubic(t).position).norm(), 1e-13) << t;
    EXPECT_LT((sampled(t).acceleration - cubic(t).acceleration).norm(), 1e-13) << t;
  }
  const QuadrotorSim sim(Options());
  const FeasibilityReport a = sim.Run(sampled, 2.0, Limits(10.0, 10.0));
  const FeasibilityReport b = sim.Run(cubic, 2.0, Limits(10.0, 10.0));
  EXPECT_NEAR(a.max_velocity_ratio, b.max_velocity_ratio, 1e-12);
  EXPECT_NEAR(a.max_acceleration_ratio, b.max_acceleration_ratio, 1e-12);
  EXPECT_LT(a.max_position_error, 1e-11);

  EXPECT_THROW(SampledReference({samples[0]}), std::invalid_argument);
  samples[3].t = samples[2].t;
  EXPECT_THROW(SampledReference(samples), std::invalid_argument);
}

// A jerk-limited profile switches its jerk inside sample intervals: on each axis the sampled
// reference switches from one sample's jerk to the next's at the time that lands on the next
// sample's acceleration, so a jerk with at most one switch per interval is reproduced exactly (the
// truth is the closed-form integral of the piecewise-constant jerk), and so is its flight.
TEST(QuadrotorSim, SampledReferenceOfAJerkLimitedProfileIsTheProfile) {
  // x: +4 until 0.12345 s, -4 until 0.37125 s, 0 after; y: -2 until 0.25055 s, +3 after; z: 0 (switches
  // off the 0.1 ms control grid, so that both flights hold a jerk across each switch alike).
  const auto exact = [](double t) {
    TrajectoryState r{t};
    const auto axis = [t](std::initializer_list<std::pair<double, double>> pieces, int i, TrajectoryState* s) {
      double p = 0.0, v = 0.0, a = 0.0, from = 0.0, j = 0.0;
      for (const auto& [until, jerk] : pieces) {
        const double d = std::max(0.0, std::min(t, until) - from);
        p += d * (v + d * (0.5 * a + d * jerk / 6.0));
        v += d * (a + 0.5 * d * jerk);
        a += d * jerk;
        if (t >= from) j = jerk;
        from = until;
      }
      s->position(i) = p;
      s->velocity(i) = v;
      s->acceleration(i) = a;
      s->jerk(i) = j;
    };
    axis({{0.12345, 4.0}, {0.37125, -4.0}, {10.0, 0.0}}, 0, &r);
    axis({{0.25055, -2.0}, {10.0, 3.0}}, 1, &r);
    return r;
  };
  std::vector<TrajectoryState> samples;
  for (int k = 0; k <= 10; ++k) samples.push_back(exact(0.1 * k));
  const QuadrotorSim::Reference sampled = SampledReference(samples);
  for (int k = 0; k <= 1000; ++k) {
    const double t = 1e-3 * k;
    ASSERT_LT((sampled(t).position - exact(t).position).norm(), 1e-14) << t;
    ASSERT_LT((sampled(t).acceleration - exact(t).acceleration).norm(), 1e-13) << t;
    ASSERT_LT((sampled(t).jerk - exact(t).jerk).norm(), 1e-12) << t;
  }
  const QuadrotorSim sim(Options());
  const FeasibilityReport a = sim.Run(sampled, 1.0, Limits(10.0, 10.0));
  const FeasibilityReport b = sim.Run(exact, 1.0, Limits(10.0, 10.0));
  EXPECT_NEAR(a.max_acceleration_ratio, b.max_acceleration_ratio, 1e-12);
  EXPECT_NEAR(a.max_position_error, b.max_position_error, 1e-12);
}

TEST(QuadrotorSim, JerkLimitClipsEveryCommand) {
  QuadrotorSimOptions o = Options();
  o.initial_position_error = Eigen::Vector3d(0.1, -0.2, 0.0);
  o.max_jerk = Eigen::Vector3d(5.0, 5.0, 5.0);
  o.record_states = true;
  const FeasibilityReport report =
      QuadrotorSim(o).Run([](double t) { return TrajectoryState{t}; }, 1.0, Limits(1.0, 10.0));
  // Unclipped, the first command would be -k_p e = w^3 (-0.1, 0.2) = (-100, 200) m/s^3 on x and y.
  ASSERT_FALSE(report.states.empty());
  EXPECT_EQ(report.states[0].jerk.x(), -5.0);
  EXPECT_EQ(report.states[0].jerk.y(), 5.0);
  EXPECT_EQ(report.states[0].jerk.z(), 0.0);
  EXPECT_GE(report.max_jerk_ratio, 200.0 / 5.0);
  EXPECT_GT(report.clipped_steps, 0);
  EXPECT_LE(report.max_jerk, 5.0);
  for (const SimState& s : report.states) EXPECT_LE(s.jerk.cwiseAbs().maxCoeff(), 5.0);
  EXPECT_THAT(report.message, HasSubstr("the jerk limit clipped the command"));
}

TEST(QuadrotorSim, RejectsBadOptionsAndInputs) {
  std::string error;
  QuadrotorSimOptions o;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.time_step = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_THAT(error, HasSubstr("time_step"));
  o = QuadrotorSimOptions();
  o.bandwidth = 200.0;  // 200 rad/s at 1 kHz
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_THAT(error, HasSubstr("bandwidth * time_step"));
  o = QuadrotorSimOptions();
  o.max_jerk = Eigen::Vector3d(1.0, -1.0, 1.0);
  EXPECT_THROW(QuadrotorSim{o}, std::invalid_argument);
  o = QuadrotorSimOptions();
  o.initial_velocity_error.x() = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_THAT(error, HasSubstr("initial errors"));

  const QuadrotorSim sim;
  const auto hover = [](double t) { return TrajectoryState{t}; };
  // A reference that turns NaN is an error, not a flight that "holds the limits".
  const auto broken = [](double t) {
    TrajectoryState r{t};
    if (t > 0.5) r.position.x() = std::nan("");
    return r;
  };
  try {
    sim.Run(broken, 1.0, Limits(1.0, 1.0));
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("the reference is not finite at t = 0.501"));
  }
  // With no step at all the initial state is still checked.
  QuadrotorSimOptions still;
  still.settle_time = 0.0;
  still.initial_velocity_error = Eigen::Vector3d(0.0, 2.0, 0.0);
  const FeasibilityReport zero = QuadrotorSim(still).Run(hover, 0.0, Limits(1.0, 1.0));
  EXPECT_EQ(zero.steps, 0);
  EXPECT_FALSE(zero.feasible);
  EXPECT_DOUBLE_EQ(zero.max_velocity_ratio, 2.0);
  EXPECT_THROW(sim.Run(hover, 1.0, Limits(-1.0, 1.0)), std::invalid_argument);
  EXPECT_THROW(sim.Run(hover, std::nan(""), Limits(1.0, 1.0)), std::invalid_argument);
  try {
    sim.Run(hover, 1e9, Limits(1.0, 1.0));
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("more than 1e8 steps"));
  }
}

// The quadrotor's limits in the report against the recorded states (an independent pass over the
// same flight): acceleration norm, largest thrust and tilt are convex or quasi-convex along a step,
// so their largest values are at step ends, exactly the recorded states' (to rounding, 1e-12); the
// smallest thrust may fall inside a step (at most the states' smallest), and the speed is checked
// at step ends and middles (at least the states' largest, within |jerk| dt^2 / 8 above it).
TEST(QuadrotorSim, QuadrotorLimitsMatchTheRecordedStates) {
  TemporalProblem p;
  p.curve = MinimumJerkSpline((Waypoints(3, 3) << 0, 3, 6, 0, 2, 0, 0, 1, 2).finished());
  p.limits.max_velocity.setConstant(std::numeric_limits<double>::infinity());
  p.limits.max_acceleration.setConstant(std::numeric_limits<double>::infinity());
  p.limits.max_speed = 2.0;
  p.limits.max_acceleration_norm = 1.5;
  p.limits.max_thrust = 11.0;
  p.limits.min_thrust = 8.5;
  p.limits.max_tilt = 0.3;
  p.cells_per_piece = 30;
  const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  QuadrotorSimOptions options;
  options.record_states = true;
  const FeasibilityReport f = QuadrotorSim(options).Fly(Trajectory(p.curve, r.profile), p.limits,
                                                        Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  ASSERT_TRUE(f.max_speed_ratio && f.max_acceleration_norm_ratio && f.max_thrust_ratio && f.min_thrust_ratio &&
              f.max_tilt_ratio);
  double speed = 0.0, acc = 0.0, thrust_max = 0.0, thrust_min = 1e300, tilt = 0.0, jerk = 0.0;
  for (const SimState& s : f.states) {
    const Eigen::Vector3d w = s.acceleration + Eigen::Vector3d(0.0, 0.0, 9.81);
    speed = std::max(speed, s.velocity.norm());
    acc = std::max(acc, s.acceleration.norm());
    thrust_max = std::max(thrust_max, w.norm());
    thrust_min = std::min(thrust_min, w.norm());
    tilt = std::max(tilt, std::atan2(w.head<2>().norm(), w(2)));
    jerk = std::max(jerk, s.jerk.norm());
  }
  EXPECT_NEAR(*f.max_acceleration_norm_ratio, acc / 1.5, 1e-12);
  EXPECT_NEAR(*f.max_thrust_ratio, thrust_max / 11.0, 1e-12);
  EXPECT_NEAR(*f.max_tilt_ratio, tilt / 0.3, 1e-12);
  EXPECT_GE(*f.min_thrust_ratio, 8.5 / thrust_min - 1e-12);
  EXPECT_GE(*f.max_speed_ratio, speed / 2.0 - 1e-12);
  EXPECT_LE(*f.max_speed_ratio, (speed + jerk * 1e-6 / 8.0) / 2.0 + 1e-12);
  // The paper's profile steps its acceleration, so the vehicle overshoots some of them a little;
  // the verdict names the ones that failed.
  if (!f.feasible) {
    EXPECT_THAT(f.message, HasSubstr("ratio reaches"));
  }
}

// A loop too slow to follow (bandwidth 1e-3 rad/s) stays within every limit while the vehicle
// ends ~10 m behind the contract line's end: not feasible, saying how far it strayed (it used to
// report feasible).
TEST(QuadrotorSim, StrayingFromTheReferenceIsNotFeasible) {
  const TemporalProblem p = ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json");
  const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  QuadrotorSimOptions slow;
  slow.bandwidth = 1e-3;
  const FeasibilityReport f = QuadrotorSim(slow).Fly(Trajectory(p.curve, r.profile), p.limits, Eigen::Vector3d::Zero(),
                                                     Eigen::Vector3d::Zero());
  EXPECT_LE(f.max_velocity_ratio, 1.0);
  EXPECT_GT(f.max_position_error, 9.0);
  EXPECT_FALSE(f.feasible);
  EXPECT_THAT(f.message, HasSubstr("strays"));
}

}  // namespace
}  // namespace timeopt
