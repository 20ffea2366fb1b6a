// The whole planner (search, spatial optimizer, temporal stage) on generated maps. Collision checks
// go to the occupancy map's voxels directly, not only through the ESDF the planner used.

#include "timeopt/planner/planner.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/sim/quadrotor_sim.h"

#include "../common/map_fixtures.h"

namespace timeopt {
namespace {

using test_support::ForestFixture;
using test_support::FreePoint;
using test_support::WalledBox;

// Smallest distance from `p` to the cubes of the occupied voxels within `reach` of it, by asking
// the OcTree about every voxel of the surrounding block (brute force, independent of the ESDF).
double TrueClearance(const OccupancyMap& map, const Eigen::Vector3d& p, double reach) {
  const double r = map.resolution();
  const Eigen::Vector3i lo = ((p.array() - reach) / r).floor().cast<int>();
  const Eigen::Vector3i hi = ((p.array() + reach) / r).floor().cast<int>();
  double best = reach;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3d corner = Eigen::Vector3d(x, y, z) * r;
        const Eigen::Vector3d centre = corner + Eigen::Vector3d::Constant(0.5 * r);
        if (!map.IsOccupied(centre)) continue;
        const Eigen::Vector3d nearest = p.cwiseMax(corner).cwiseMin(corner + Eigen::Vector3d::Constant(r));
        best = std::min(best, (p - nearest).norm());
      }
    }
  }
  return best;
}

TEST(Planner, ForestPlansKeepTheRobotRadiusAgainstTheOctreeVoxels) {
  std::mt19937 rng(7);
  int successes = 0, trials = 0;
  for (uint64_t seed : {1, 2, 3}) {
    const ForestFixture f(seed);
    Planner planner(*f.esdf);
    for (int pair = 0; pair < 4; ++pair) {
      PlannerOptions options;
      options.robot_radius = 0.3;
      // The iteration limit alone: the same curve on every machine, also under the sanitizers
      // (the default time guard of 10 s is far from binding there).
      options.spatial.max_solver_time_seconds = 60.0;
      Eigen::Vector3d start = FreePoint(*f.esdf, &rng, 0.5, 0.5, 3.0);
      Eigen::Vector3d goal = FreePoint(*f.esdf, &rng, 0.5, 7.0, 9.5);
      const PlanResult plan = planner.Plan(start, goal, options);
      ++trials;
      ASSERT_TRUE(plan.is_success()) << "seed " << seed << " pair " << pair << ": " << ToString(plan.status) << ": "
                                     << plan.message;
      ++successes;
      // The planner's promise: the radius plus half a check step at the samples (a start or goal
      // closer than that lowers it to its own clearance, which these free points exceed).
      EXPECT_GE(plan.min_clearance, options.robot_radius + 0.5 * options.clearance_check_step / 8.0);
      // Dense check of the curve against the occupied voxels' cubes, 0.01 m steps in s-chords:
      // between samples the robot centre moves at most 0.005 m, the tolerance below.
      double smallest = 1e9;
      for (int i = 0; i < plan.curve.num_pieces(); ++i) {
        const double chord = (plan.curve.Evaluate(i, 1.0) - plan.curve.Evaluate(i, 0.0)).norm();
        const int n = std::max(20, static_cast<int>(std::ceil(2.0 * chord / 0.01)));
        for (int k = 0; k <= n; ++k) {
          smallest = std::min(smallest, TrueClearance(f.map, plan.curve.Evaluate(i, double(k) / n), 1.0));
        }
      }
      EXPECT_GE(smallest, options.robot_radius - 0.005) << "seed " << seed << " pair " << pair;
      // End points are the requested ones (the optimizer keeps start and goal fixed), to round-off.
      EXPECT_LT((plan.curve.Evaluate(0, 0.0) - start).norm(), 1e-9);
      EXPECT_LT((plan.curve.Evaluate(plan.curve.num_pieces() - 1, 1.0) - goal).norm(), 1e-9);
      // Certified temporal rows: the limits hold on the dense check, up to the SOCP tolerance.
      EXPECT_LE(plan.temporal.max_velocity_ratio, 1.0 + 1e-6);
      EXPECT_LE(plan.temporal.max_acceleration_ratio, 1.0 + 1e-6);
      EXPECT_GT(plan.temporal.total_time, 0.0);
    }
  }
  EXPECT_EQ(successes, trials);
}

// The shipped forest's default plan, corner to corner. With every piece 1 long in s, minimizing
// the jerk in s bent the curve sharply around the short pieces between long ones, and the
// trajectory braked to 0.31 and 0.36 m/s in open space (radius of curvature 0.12 m): the uniform
// parameterization with the old smoothness weight and search weight must still show it (so this
// test can fail). With the defaults no speed more than 1 s from either end is below 1 m/s, and T is
// no longer than the 14.573 s it was.
TEST(Planner, ChordalPiecesRemoveTheHooksOfTheDefaultPlan) {
  const OccupancyMap map = OccupancyMap::Load(std::string(TIMEOPT_SOURCE_DIR) + "/maps/forest_20x20.bt");
  const Esdf esdf =
      Esdf::FromMapRegion(map, Eigen::AlignedBox3d(Eigen::Vector3d(-9, -9, -10), Eigen::Vector3d(29, 29, 11)));
  Planner planner(esdf);
  PlannerOptions options;
  options.spatial.max_solver_time_seconds = 60.0;  // the iteration limit alone: the same curve on every machine
  const Eigen::Vector3d start(1, 1, 1.5), goal(19, 19, 1.5);
  const PlanResult chordal = planner.Plan(start, goal, options);
  ASSERT_TRUE(chordal.is_success()) << chordal.message;
  EXPECT_GE(chordal.min_interior_speed, 1.0);
  EXPECT_LE(chordal.temporal.total_time, 14.573);
  EXPECT_GE(chordal.min_clearance, options.robot_radius);
  // The old defaults: uniform pieces, smoothness weight 1, search heuristic weight 1.5.
  options.spatial.parameterization = SpatialParameterization::kUniform;
  options.spatial.smoothness_weight = 1.0;
  options.search.heuristic_weight = 1.5;
  const PlanResult uniform = planner.Plan(start, goal, options);
  ASSERT_TRUE(uniform.is_success()) << uniform.message;
  EXPECT_LT(uniform.min_interior_speed, 0.5);
  EXPECT_LT(uniform.min_curvature_radius, 0.5 * chordal.min_curvature_radius);
}

// The two of the 500 start/goal pairs of ../shared/maps/forest_gen (trials 168 and 246) whose
// plans still braked below 0.3 vmax with chordal pieces and smoothness weight 1: each bent over a
// few centimetres at a corner of the front end's path (radius of curvature 0.17 and 0.31 m). With
// the default weight (2) neither does, and with weight 1 (and the search's heuristic weight 1.5 of
// then) at least one still does (so this test can fail). Skipped when ../shared/maps is absent.
TEST(Planner, TheSmoothnessWeightRemovesTheHooksAtFrontEndCorners) {
  struct Pair {
    int map;
    Eigen::Vector3d start, goal;
  };
  const Pair pairs[] = {{1, {-2.136234, -3.691912, 1.0}, {1.012682, 0.152169, 1.0}},
                        {2, {-0.253391, 1.261093, 1.0}, {-4.200079, -0.723733, 1.0}}};
  double slowest_old = std::numeric_limits<double>::infinity();
  for (const Pair& pair : pairs) {
    const std::string path =
        std::string(TIMEOPT_SHARED_DIR) + "/maps/forest_gen/forest" + std::to_string(pair.map) + ".bt";
    if (!std::ifstream(path)) GTEST_SKIP() << "skipped: " << path << " is absent";
    const OccupancyMap map = OccupancyMap::Load(path);
    const Esdf esdf = Esdf::FromMapRegion(map, PlanRegion(pair.start, pair.goal));  // as timeopt plan
    Planner planner(esdf);
    PlannerOptions options;
    options.spatial.max_solver_time_seconds = 60.0;  // the iteration limit alone: the same curve on every machine
    const double floor = 0.3 * options.limits.max_velocity.minCoeff();
    const PlanResult plan = planner.Plan(pair.start, pair.goal, options);
    ASSERT_TRUE(plan.is_success()) << plan.message;
    EXPECT_GE(plan.min_interior_speed, floor) << "forest" << pair.map;
    EXPECT_GE(plan.min_clearance, options.robot_radius);
    options.spatial.smoothness_weight = 1.0;
    options.search.heuristic_weight = 1.5;
    const PlanResult old = planner.Plan(pair.start, pair.goal, options);
    ASSERT_TRUE(old.is_success()) << old.message;
    slowest_old = std::min(slowest_old, old.min_interior_speed);
  }
  EXPECT_LT(slowest_old, 0.3 * PlannerOptions().limits.max_velocity.minCoeff());
}

// The two plans of experiment_convergence's 2,500 (500 per density 0.05-0.25) that still braked
// below 0.3 vmax with smoothness weight 2: test 411 at density 0.2 (0.50 m/s, radius 0.12 m: the
// front end's path left the start southwards and turned back around a tree) and test 353 at 0.25
// (0.60 m/s). Their forests are the experiment's (20 x 20 x 3 m, seeds 103 and 104). The search's
// heuristic weight 1.5 found those detours (so this test can fail); with the default 1.2 both plans
// keep above 0.3 vmax, collision-free.
TEST(Planner, TheSearchWeightRemovesTheDetoursOfDenseForests) {
  struct Case {
    double density;
    unsigned seed;
    Eigen::Vector3d start, goal;
  };
  const Case cases[] = {{0.2, 103, {18.0021, 18.3963, 1.5}, {1.26745, 2.66888, 1.5}},
                        {0.25, 104, {16.2191, 17.13, 1.5}, {3.66385, 3.44756, 1.5}}};
  double slowest_old = std::numeric_limits<double>::infinity();
  for (const Case& c : cases) {
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 20, 3));
    forest.density = c.density;
    forest.seed = c.seed;
    const OccupancyMap map = OccupancyMap::FromGrid(GenerateForest(forest));
    const Esdf esdf = Esdf::FromMapRegion(map, PlanRegion(c.start, c.goal));  // as timeopt plan
    Planner planner(esdf);
    PlannerOptions options;
    options.spatial.max_solver_time_seconds = 60.0;  // the iteration limit alone: the same curve on every machine
    const PlanResult plan = planner.Plan(c.start, c.goal, options);
    ASSERT_TRUE(plan.is_success()) << plan.message;
    EXPECT_GE(plan.min_interior_speed, 0.3 * options.limits.max_velocity.minCoeff()) << "density " << c.density;
    EXPECT_GE(plan.min_clearance, options.robot_radius);
    options.search.heuristic_weight = 1.5;
    const PlanResult old = planner.Plan(c.start, c.goal, options);
    ASSERT_TRUE(old.is_success()) << old.message;
    slowest_old = std::min(slowest_old, old.min_interior_speed);
  }
  EXPECT_LT(slowest_old, 0.3 * PlannerOptions().limits.max_velocity.minCoeff());
}

TEST(Planner, MapsSearchStatusesAndValidatesNestedOptions) {
  const Esdf esdf(WalledBox());
  const Eigen::Vector3d start(1.0, 2.0, 1.0), free_goal(4.0, 1.0, 1.0);

  // The planner maps the statuses: the goal behind the wall is unreachable.
  PlannerOptions plan_options;
  EXPECT_EQ(Plan(esdf, start, Eigen::Vector3d(8.0, 2.0, 1.0), plan_options).status, PlanStatus::kUnreachable);
  plan_options.limits.max_velocity.x() = -1.0;
  const PlanResult bad = Plan(esdf, start, free_goal, plan_options);
  EXPECT_EQ(bad.status, PlanStatus::kInvalidInput);
  EXPECT_NE(bad.message.find("max_velocity"), std::string::npos) << bad.message;

  // Nested options are validated before any stage runs: a status naming the field, never an
  // exception (Planner::Plan used to throw from the temporal solver's factory here).
  Planner planner(esdf);
  PlannerOptions nested;
  nested.socp.tolerance = -1.0;
  PlanResult r2;
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, nested));
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("options.socp.tolerance"), std::string::npos) << r2.message;
  nested = PlannerOptions();
  nested.limits.max_acceleration_change = std::numeric_limits<double>::quiet_NaN();
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, nested));
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("max_acceleration_change"), std::string::npos) << r2.message;
  // Sizes that would drive memory are refused before anything is made: 3 m at segments of 1e-9 m
  // (1e-9 / 8 by the last attempt) is about 2.4e10 pieces, above the cap of 1e4; start == goal.
  nested = PlannerOptions();
  nested.max_segment_length = 1e-9;
  r2 = planner.Plan(start, free_goal, nested);
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("max_segment_length"), std::string::npos) << r2.message;
  r2 = planner.Plan(start, start, PlannerOptions());
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("start and goal are the same point"), std::string::npos) << r2.message;
  // The same planner then plans with valid options (its solver is remade for them).
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, PlannerOptions()));
  EXPECT_TRUE(r2.is_success()) << r2.message;
}

// A start in motion (issue 21's re-planning): the plan leaves the start with the vehicle's
// velocity and acceleration (the trajectory's state at t = 0 is the given one, to the solvers'
// tolerances), and the jerk-input quadrotor flies it from that state within 1% of the limits.
TEST(Planner, AStartInMotionIsFlownFromThatState) {
  const ForestFixture forest(5, 0.08);
  Planner planner(*forest.esdf);
  std::mt19937 rng(3);
  const Eigen::Vector3d start = FreePoint(*forest.esdf, &rng, 1.0, 1.0, 2.0);
  const Eigen::Vector3d goal = FreePoint(*forest.esdf, &rng, 1.0, 8.0, 9.0);
  PlannerOptions options;  // certified rows, jerk 10 m/s^3
  options.start_velocity = 0.8 * (goal - start).normalized();
  options.start_acceleration = 0.3 * (goal - start).normalized() + Eigen::Vector3d(0.0, 0.0, 0.1);
  const PlanResult plan = planner.Plan(start, goal, options);
  ASSERT_TRUE(plan.is_success()) << plan.message;
  const Trajectory trajectory(plan.curve, plan.temporal.profile);
  const TrajectoryState first = trajectory.Evaluate(0.0);
  EXPECT_LT((first.velocity - options.start_velocity).norm(), 1e-6);
  EXPECT_LT((first.acceleration - options.start_acceleration).norm(), 1e-5);
  QuadrotorSimOptions flight;
  flight.limit_tolerance = 0.01;
  const FeasibilityReport report =
      QuadrotorSim(flight).Fly(trajectory, options.limits, options.start_velocity, options.start_acceleration);
  EXPECT_TRUE(report.feasible) << report.message;
}

// The closed re-planning loop of a vehicle in flight: plan, fly 0.5 s in the jerk-input simulator,
// re-plan from the simulated state (position, velocity, acceleration), and so on; within 2 m of the
// goal the rest is flown as planned, as receding-horizon planners do (e.g. Fast-Planner's no-replan
// threshold): the vehicle is then braking, and its state lags the reference by ~1/bandwidth, so a
// stop from the simulated state would need more than the limits. Every flown segment must keep the
// limits within 1% (the flight criterion) and the loop must end at the goal.
struct LoopOutcome {
  int plans = 0;
  int moving_starts = 0;  // plans from a state in motion
  int scaled_starts = 0;  // plans whose start state the planner had to scale (start_scale < 1)
  bool reached = false;
};

LoopOutcome FlyReplanningLoop(const ForestFixture& forest, int seed) {
  constexpr double kCycle = 0.5;             // s flown before each re-plan
  constexpr double kNoReplanDistance = 2.0;  // m
  Planner planner(*forest.esdf);
  std::mt19937 rng(seed);
  Eigen::Vector3d position = FreePoint(*forest.esdf, &rng, 1.0, 1.0, 2.0);
  const Eigen::Vector3d goal = FreePoint(*forest.esdf, &rng, 1.0, 8.0, 9.0);
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero(), acceleration = Eigen::Vector3d::Zero();
  PlannerOptions options;  // certified rows, jerk 10 m/s^3
  QuadrotorSimOptions flight;
  flight.limit_tolerance = 0.01;
  flight.record_states = true;
  LoopOutcome outcome;
  for (; outcome.plans < 40 && !outcome.reached;) {
    options.start_velocity = velocity;
    options.start_acceleration = acceleration;
    const PlanResult plan = planner.Plan(position, goal, options);
    ++outcome.plans;
    if (velocity.norm() > 0.1) ++outcome.moving_starts;
    if (plan.start_scale < 1.0) ++outcome.scaled_starts;
    EXPECT_TRUE(plan.is_success()) << "plan " << outcome.plans << ": " << plan.message;
    if (!plan.is_success()) return outcome;
    const Trajectory trajectory(plan.curve, plan.temporal.profile);
    const FeasibilityReport report = QuadrotorSim(flight).Fly(trajectory, options.limits, velocity, acceleration);
    const bool last =
        trajectory.duration() <= kCycle || (trajectory.Evaluate(kCycle).position - goal).norm() < kNoReplanDistance;
    const double horizon = last ? trajectory.duration() : kCycle;
    double worst_velocity = 0.0, worst_acceleration = 0.0;
    SimState at_horizon = report.states.front();
    for (const SimState& state : report.states) {
      if (!last && state.t > horizon + 1e-9) break;
      worst_velocity = std::max(worst_velocity,
                                (state.velocity.cwiseAbs().array() / options.limits.max_velocity.array()).maxCoeff());
      worst_acceleration =
          std::max(worst_acceleration,
                   (state.acceleration.cwiseAbs().array() / options.limits.max_acceleration.array()).maxCoeff());
      at_horizon = state;
    }
    EXPECT_LE(worst_velocity, 1.01) << "plan " << outcome.plans;
    EXPECT_LE(worst_acceleration, 1.01) << "plan " << outcome.plans;
    if (last) {
      EXPECT_TRUE(report.feasible) << "plan " << outcome.plans << ": " << report.message;
      EXPECT_LT((report.states.back().position - goal).norm(), 0.05);
      outcome.reached = true;
    }
    position = at_horizon.position;
    velocity = at_horizon.velocity;
    acceleration = at_horizon.acceleration;
  }
  return outcome;
}

TEST(Planner, TheReplanningLoopFromSimulatedStatesReachesTheGoalWithinTheLimits) {
  const ForestFixture forest(5, 0.08);
  for (const int seed : {11, 12, 13, 14}) {
    SCOPED_TRACE(seed);
    const LoopOutcome outcome = FlyReplanningLoop(forest, seed);
    EXPECT_TRUE(outcome.reached) << "not at the goal after " << outcome.plans << " plans";
    // Several cycles, nearly all from a state in motion (the first is from rest).
    EXPECT_GE(outcome.plans, 5);
    EXPECT_GE(outcome.moving_starts, outcome.plans - 2);
  }
}

}  // namespace
}  // namespace timeopt
