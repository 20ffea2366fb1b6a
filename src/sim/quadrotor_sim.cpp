#include "timeopt/sim/quadrotor_sim.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace timeopt {
namespace {

// Longest flight, in controller steps, and longest recorded one (SimState is 128 bytes).
constexpr double kMaxSteps = 1e8;
constexpr double kMaxRecordedSteps = 1e7;

bool PositiveFinite(const Eigen::Vector3d& v) { return v.allFinite() && (v.array() > 0.0).all(); }

// Largest |v(tau)| over tau in [0, dt] for v(tau) = v0 + a0 tau + u tau^2 / 2, and the tau where it
// is reached: the ends, or the vertex tau = -a0 / u when it lies inside the step.
double MaxAbsVelocity(double v0, double a0, double u, double dt, double* at) {
  const double v1 = v0 + a0 * dt + 0.5 * u * dt * dt;
  double best = std::abs(v0);
  *at = 0.0;
  if (std::abs(v1) > best) {
    best = std::abs(v1);
    *at = dt;
  }
  if (u != 0.0) {
    const double tau = -a0 / u;
    if (tau > 0.0 && tau < dt) {
      const double vertex = std::abs(v0 + 0.5 * a0 * tau);  // v0 + a0 tau + u tau^2 / 2 at tau = -a0/u
      if (vertex > best) {
        best = vertex;
        *at = tau;
      }
    }
  }
  return best;
}

const char* AxisName(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

}  // namespace

bool QuadrotorSimOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (!(time_step > 0.0 && std::isfinite(time_step))) return fail("time_step must be positive and finite");
  if (!(bandwidth > 0.0 && std::isfinite(bandwidth))) return fail("bandwidth must be positive and finite");
  if (bandwidth * time_step > 0.1) {
    return fail(
        "bandwidth * time_step must be <= 0.1 (at least 10 controller steps per time constant "
        "1 / bandwidth)");
  }
  if (!(settle_time >= 0.0 && std::isfinite(settle_time))) return fail("settle_time must be >= 0 and finite");
  if (!(max_position_error > 0.0)) return fail("max_position_error must be positive (or infinity)");
  if (max_jerk && !PositiveFinite(*max_jerk)) return fail("max_jerk must be positive and finite on every axis");
  if (!initial_position_error.allFinite() || !initial_velocity_error.allFinite() ||
      !initial_acceleration_error.allFinite()) {
    return fail("the initial errors must be finite");
  }
  if (!(limit_tolerance >= 0.0 && std::isfinite(limit_tolerance))) {
    return fail("limit_tolerance must be >= 0 and finite");
  }
  return true;
}

QuadrotorSim::QuadrotorSim(const Options& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("QuadrotorSimOptions: " + error);
}

FeasibilityReport QuadrotorSim::Run(const Trajectory& reference, const VehicleLimits& limits) const {
  return Run([&reference](double t) { return reference.Evaluate(t); }, reference.duration(), limits);
}

FeasibilityReport QuadrotorSim::Run(const Reference& reference, double duration, const VehicleLimits& limits) const {
  if (!reference) throw std::invalid_argument("QuadrotorSim::Run: the reference is empty");
  const TrajectoryState start = reference(0.0);
  return RunFrom(reference, duration, limits, start.velocity, start.acceleration);
}

FeasibilityReport QuadrotorSim::Fly(const Trajectory& reference, const VehicleLimits& limits,
                                    const Eigen::Vector3d& start_velocity,
                                    const Eigen::Vector3d& start_acceleration) const {
  return RunFrom([&reference](double t) { return reference.Evaluate(t); }, reference.duration(), limits, start_velocity,
                 start_acceleration);
}

namespace {

// The controller steps of a flight of `flight` seconds at time_step dt, refused above the caps.
int FlightSteps(double flight, double dt, bool record_states) {
  // 1e-6 relative slack: a flight a solver tolerance above a whole number of steps (T = 7 + 5e-9 s)
  // adds no step; at most 1e-6 of the flight (in the settle time) goes unsimulated.
  const double exact_steps = flight / dt * (1.0 - 1e-6);
  if (exact_steps > kMaxSteps || (record_states && exact_steps > kMaxRecordedSteps)) {
    std::ostringstream m;
    m << "QuadrotorSim::Run: the flight (" << flight << " s at time_step " << dt << " s) would take more than "
      << (exact_steps > kMaxSteps ? "1e8 steps" : "1e7 recorded steps (record_states)");
    throw std::invalid_argument(m.str());
  }
  return static_cast<int>(std::ceil(exact_steps));
}

// The reference at t; after its end it flies on at its final velocity.
class ExtendedReference {
 public:
  ExtendedReference(const QuadrotorSim::Reference& reference, double duration)
      : reference_(reference), duration_(duration), last_(reference(duration)) {}

  TrajectoryState operator()(double t) const {
    TrajectoryState r;
    if (t <= duration_) {
      r = reference_(t);
    } else {
      r = last_;
      r.t = t;
      r.position = last_.position + (t - duration_) * last_.velocity;
      r.acceleration.setZero();
      r.jerk.setZero();
    }
    if (!r.position.allFinite() || !r.velocity.allFinite() || !r.acceleration.allFinite() || !r.jerk.allFinite()) {
      std::ostringstream m;
      m << "QuadrotorSim::Run: the reference is not finite at t = " << t << " s";
      throw std::invalid_argument(m.str());
    }
    return r;
  }

 private:
  const QuadrotorSim::Reference& reference_;
  double duration_;
  TrajectoryState last_;
};

// The extremes of a flight, folded in one controller step at a time: each axis' velocity and
// acceleration ratios, with where and on which axis the largest is reached, and the quadrotor's
// speed, acceleration norm, thrust and tilt.
class FlightExtremes {
 public:
  FlightExtremes(const VehicleLimits& limits, FeasibilityReport* report)
      : limits_(limits), report_(*report), quadrotor_(limits.HasNormLimits()) {}

  bool quadrotor() const { return quadrotor_; }
  int velocity_axis() const { return velocity_axis_; }
  int acceleration_axis() const { return acceleration_axis_; }

  // The step from (v, a) at time t with the jerk u held for dt.
  void NoteStep(double t, const Eigen::Vector3d& v, const Eigen::Vector3d& a, const Eigen::Vector3d& u, double dt) {
    for (int i = 0; i < 3; ++i) {
      double at = 0.0;
      NoteVelocity(MaxAbsVelocity(v[i], a[i], u[i], dt, &at) / limits_.max_velocity[i], t + at, i);
      // a is linear over the step: its largest magnitude is at an end.
      const double a1 = a[i] + u[i] * dt;
      NoteAcceleration(std::max(std::abs(a[i]), std::abs(a1)) / limits_.max_acceleration[i],
                       std::abs(a1) > std::abs(a[i]) ? t + dt : t, i);
    }
    NoteQuadrotor(v, a, u, dt);
  }

  // The final state (v, a) at time t.
  void NoteFinal(double t, const Eigen::Vector3d& v, const Eigen::Vector3d& a) {
    for (int i = 0; i < 3; ++i) {
      NoteVelocity(std::abs(v[i]) / limits_.max_velocity[i], t, i);
      NoteAcceleration(std::abs(a[i]) / limits_.max_acceleration[i], t, i);
    }
    NoteQuadrotor(v, a, Eigen::Vector3d::Zero(), 0.0);
  }

  // Writes the quadrotor's ratios into the report; returns the limits they exceed beyond `bound`
  // ("" when none does).
  std::string QuadrotorRatios(double bound) {
    quadrotor_extremes_.WriteRatios(limits_, &report_);
    std::string failed;
    const auto check = [&](const std::optional<double>& ratio, const char* name) {
      if (ratio && !(*ratio <= bound)) {
        std::ostringstream m;
        m.precision(10);
        m << (failed.empty() ? "" : "; ") << name << " ratio reaches " << *ratio;
        failed += m.str();
      }
    };
    check(report_.max_speed_ratio, "max_speed");
    check(report_.max_acceleration_norm_ratio, "max_acceleration_norm");
    check(report_.max_thrust_ratio, "max_thrust");
    check(report_.min_thrust_ratio, "min_thrust");
    check(report_.max_tilt_ratio, "max_tilt");
    return failed;
  }

 private:
  // Folds a value of |v_i| / vmax_i or |a_i| / amax_i reached at time t into the report.
  void NoteVelocity(double ratio, double t, int axis) {
    if (ratio > report_.max_velocity_ratio) {
      report_.max_velocity_ratio = ratio;
      report_.max_velocity_time = t;
      velocity_axis_ = axis;
    }
  }
  void NoteAcceleration(double ratio, double t, int axis) {
    if (ratio > report_.max_acceleration_ratio) {
      report_.max_acceleration_ratio = ratio;
      report_.max_acceleration_time = t;
      acceleration_axis_ = axis;
    }
  }
  // The quadrotor's limits over one step from (v0, a0) with jerk u0 held for h (h = 0: the point):
  // the speed at both ends and the middle, the acceleration and the thrust at both ends (they are
  // linear over the step, so their norms are largest at an end), the smallest thrust where the
  // thrust is nearest zero over the step.
  void NoteQuadrotor(const Eigen::Vector3d& v0, const Eigen::Vector3d& a0, const Eigen::Vector3d& u0, double h) {
    if (!quadrotor_) return;
    QuadrotorExtremes& e = quadrotor_extremes_;
    const Eigen::Vector3d a1 = a0 + u0 * h;
    e.speed = std::max(
        {e.speed, v0.norm(), (v0 + a0 * h + 0.5 * u0 * h * h).norm(), (v0 + 0.5 * h * a0 + 0.125 * h * h * u0).norm()});
    e.acceleration_norm = std::max({e.acceleration_norm, a0.norm(), a1.norm()});
    const Eigen::Vector3d w0 = ThrustVector(a0, limits_.gravity), w1 = ThrustVector(a1, limits_.gravity);
    e.max_thrust = std::max({e.max_thrust, w0.norm(), w1.norm()});
    const double uu = u0.squaredNorm();
    const double tau = uu > 0.0 ? std::clamp(-w0.dot(u0) / uu, 0.0, h) : 0.0;
    e.min_thrust = std::min({e.min_thrust, (w0 + u0 * tau).norm(), w1.norm()});
    e.tilt = std::max({e.tilt, Tilt(w0), Tilt(w1)});
  }

  const VehicleLimits& limits_;
  FeasibilityReport& report_;
  const bool quadrotor_;
  int velocity_axis_ = 0, acceleration_axis_ = 0;
  QuadrotorExtremes quadrotor_extremes_;
};

// The verdict of a flight whose extremes are in the report, and its message.
void FinishReport(const QuadrotorSimOptions& options, FlightExtremes* extremes, bool diverged, int steps,
                  FeasibilityReport* out) {
  FeasibilityReport& report = *out;
  report.tolerance = options.limit_tolerance;
  const double bound = 1.0 + options.limit_tolerance;
  const bool velocity_ok = report.max_velocity_ratio <= bound;
  const bool acceleration_ok = report.max_acceleration_ratio <= bound;
  std::string quadrotor_failed = extremes->QuadrotorRatios(bound);
  const bool tracked = report.max_position_error <= options.max_position_error;
  if (!tracked) {
    std::ostringstream m;
    m.precision(10);
    m << (quadrotor_failed.empty() ? "" : "; ") << "the vehicle strays " << report.max_position_error
      << " m from the reference at t = " << report.max_position_error_time << " s (max_position_error "
      << options.max_position_error << " m)";
    quadrotor_failed += m.str();
  }
  report.feasible = velocity_ok && acceleration_ok && quadrotor_failed.empty() && !diverged;
  std::ostringstream message;
  message.precision(10);
  if (diverged) {
    message << "the flight diverged (non-finite state) at t = " << report.max_velocity_time << " s";
    if (report.clipped_steps > 0) message << " after " << report.clipped_steps << " steps clipped to the jerk limit";
    report.max_velocity_ratio = report.max_acceleration_ratio = std::numeric_limits<double>::infinity();
    report.message = message.str();
    return;
  }
  if (report.feasible)
    message << (extremes->quadrotor() ? "every limit holds" : "velocity and acceleration limits hold");
  if (!quadrotor_failed.empty()) message << quadrotor_failed << (velocity_ok && acceleration_ok ? "" : "; ");
  if (!velocity_ok) {
    message << "|v_" << AxisName(extremes->velocity_axis()) << "| reaches " << report.max_velocity_ratio
            << " x max_velocity at t = " << report.max_velocity_time << " s";
  }
  if (!acceleration_ok) {
    message << (velocity_ok ? "" : "; ") << "|a_" << AxisName(extremes->acceleration_axis()) << "| reaches "
            << report.max_acceleration_ratio << " x max_acceleration at t = " << report.max_acceleration_time << " s";
  }
  if (report.clipped_steps > 0) {
    message << "; the jerk limit clipped the command in " << report.clipped_steps << " of " << steps << " steps (up to "
            << report.max_jerk_ratio << " x)";
  }
  report.message = message.str();
}

}  // namespace

FeasibilityReport QuadrotorSim::RunFrom(const Reference& reference, double duration, const VehicleLimits& limits,
                                        const Eigen::Vector3d& start_velocity,
                                        const Eigen::Vector3d& start_acceleration) const {
  if (!(duration >= 0.0 && std::isfinite(duration))) {
    throw std::invalid_argument("QuadrotorSim::Run: duration must be >= 0 and finite");
  }
  // Per-axis limits may be +infinity (none on that axis) when the quadrotor's norms bound the flight.
  const auto positive = [](const Eigen::Vector3d& v) { return (v.array() > 0.0).all(); };
  if (!positive(limits.max_velocity) || (!limits.max_velocity.allFinite() && !limits.max_speed)) {
    throw std::invalid_argument(
        "QuadrotorSim::Run: limits.max_velocity must be positive (and finite unless "
        "max_speed is given)");
  }
  if (!positive(limits.max_acceleration)) {
    throw std::invalid_argument("QuadrotorSim::Run: limits.max_acceleration must be positive");
  }
  const double dt = options_.time_step;
  const int steps = FlightSteps(duration + options_.settle_time, dt, options_.record_states);

  const double w = options_.bandwidth;
  const double kp = w * w * w, kv = 3.0 * w * w, ka = 3.0 * w;
  const ExtendedReference reference_at(reference, duration);

  Eigen::Vector3d p = reference_at(0.0).position + options_.initial_position_error;
  Eigen::Vector3d v = start_velocity + options_.initial_velocity_error;
  Eigen::Vector3d a = start_acceleration + options_.initial_acceleration_error;

  FeasibilityReport report;
  report.steps = steps;
  FlightExtremes extremes(limits, &report);
  bool diverged = false;
  if (options_.record_states) report.states.reserve(static_cast<size_t>(steps) + 1);
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    const TrajectoryState r = reference_at(t);
    const double error = (p - r.position).norm();
    if (error > report.max_position_error) {
      report.max_position_error = error;
      report.max_position_error_time = t;
    }
    if (!(p.allFinite() && v.allFinite() && a.allFinite())) {  // the loop diverged (jerk clipping)
      diverged = true;
      report.final_position_error = error;
      report.max_velocity_time = report.max_acceleration_time = t;
      break;
    }
    if (k == steps) {  // the final state: measured (the only state when steps = 0) and recorded
      report.final_position_error = error;
      extremes.NoteFinal(t, v, a);
      if (options_.record_states) report.states.push_back({t, p, v, a, Eigen::Vector3d::Zero(), p - r.position});
      break;
    }
    Eigen::Vector3d u = r.jerk + ka * (r.acceleration - a) + kv * (r.velocity - v) + kp * (r.position - p);
    if (options_.max_jerk) {
      const Eigen::Vector3d& jmax = *options_.max_jerk;
      bool clipped = false;
      for (int i = 0; i < 3; ++i) {
        report.max_jerk_ratio = std::max(report.max_jerk_ratio, std::abs(u[i]) / jmax[i]);
        if (std::abs(u[i]) > jmax[i]) {
          u[i] = std::copysign(jmax[i], u[i]);
          clipped = true;
        }
      }
      if (clipped) ++report.clipped_steps;
    }
    report.max_jerk = std::max(report.max_jerk, u.cwiseAbs().maxCoeff());
    if (options_.record_states) report.states.push_back({t, p, v, a, u, p - r.position});
    extremes.NoteStep(t, v, a, u, dt);
    // Exact integration of the triple integrator over the step with u held.
    p += dt * (v + dt * (0.5 * a + dt * u / 6.0));
    v += dt * (a + 0.5 * dt * u);
    a += dt * u;
  }
  FinishReport(options_, &extremes, diverged, steps, &report);
  return report;
}

QuadrotorSim::Reference SampledReference(std::vector<TrajectoryState> samples) {
  if (samples.size() < 2) {
    throw std::invalid_argument("SampledReference: expected at least 2 samples, got " + std::to_string(samples.size()));
  }
  const double t0 = samples.front().t;
  for (size_t k = 0; k < samples.size(); ++k) {
    TrajectoryState& s = samples[k];
    if (!std::isfinite(s.t) || !s.position.allFinite() || !s.velocity.allFinite() || !s.acceleration.allFinite() ||
        !s.jerk.allFinite()) {
      throw std::invalid_argument("SampledReference: sample " + std::to_string(k) + " is not finite");
    }
    if (k > 0 && !(s.t > samples[k - 1].t)) {
      throw std::invalid_argument("SampledReference: sample times must increase strictly (sample " + std::to_string(k) +
                                  ")");
    }
  }
  for (TrajectoryState& s : samples) s.t -= t0;
  return [samples = std::move(samples)](double t) {
    // The interval [s_k, s_k+1] that holds t (the first for t < 0; the last sample after the end).
    const auto after = std::upper_bound(samples.begin(), samples.end(), t,
                                        [](double value, const TrajectoryState& s) { return value < s.t; });
    if (after == samples.end()) {
      TrajectoryState r = samples.back();
      r.t = t;
      return r;
    }
    if (after == samples.begin()) {
      TrajectoryState r = samples.front();
      r.t = t;
      return r;
    }
    // Per axis, from sample k: its jerk j0 until a switch to sample k+1's jerk j1 at the time
    // that lands on sample k+1's acceleration, a0 + j0 tau* + j1 (h - tau*) = a1, when that time
    // lies in the interval. So a trajectory whose jerk is piecewise constant with at most one
    // switch per interval on each axis (a jerk-limited profile sampled finely enough) is flown
    // exactly as it is. Otherwise (an acceleration step, as the paper's profile has) sample k's
    // jerk is held and the acceleration steps at sample k+1, as the trajectory does.
    const TrajectoryState& s0 = *(after - 1);
    const TrajectoryState& s1 = *after;
    const double h = s1.t - s0.t, tau = t - s0.t;
    TrajectoryState r;
    r.t = t;
    for (int i = 0; i < 3; ++i) {
      const double a0 = s0.acceleration(i), j0 = s0.jerk(i), j1 = s1.jerk(i);
      double p = s0.position(i), v = s0.velocity(i), acc = a0;
      double held = tau, after_switch = 0.0;
      if (j0 != j1) {
        const double at = (s1.acceleration(i) - a0 - j1 * h) / (j0 - j1);
        if (at >= 0.0 && at <= h && tau > at) {
          held = at;
          after_switch = tau - at;
        }
      }
      // Exact integration over the held part, then over the part after the switch.
      p += held * (v + held * (0.5 * acc + held * j0 / 6.0));
      v += held * (acc + 0.5 * held * j0);
      acc += held * j0;
      p += after_switch * (v + after_switch * (0.5 * acc + after_switch * j1 / 6.0));
      v += after_switch * (acc + 0.5 * after_switch * j1);
      acc += after_switch * j1;
      r.position(i) = p;
      r.velocity(i) = v;
      r.acceleration(i) = acc;
      r.jerk(i) = after_switch > 0.0 ? j1 : j0;
    }
    return r;
  };
}

}  // namespace timeopt
