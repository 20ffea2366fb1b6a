#include "timeopt/io/planner_io.h"

#include <limits>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "timeopt/conic/solver.h"
#include "timeopt/core/enum_strings.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& json) {
  try {
    ParsePlannerConfigJson(json, PlannerOptions());
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

// Options with every configurable field away from its default, so that a field the writer or the
// reader forgets shows up as a difference.
PlannerOptions Unusual() {
  PlannerOptions o;
  o.robot_radius = 0.45;
  o.safety_margin = 0.125;
  o.max_segment_length = 2.75;
  o.max_attempts = 7;
  o.limits.max_velocity = Eigen::Vector3d(1.5, 2.5, 0.75);
  o.limits.max_acceleration = Eigen::Vector3d(3.0, 4.0, 1.25);
  o.limits.max_acceleration_change = 0.3;
  o.limits.max_jerk = Eigen::Vector3d(12.0, 13.5, 7.25);
  o.limits.max_speed = 3.5;
  o.limits.max_acceleration_norm = 4.5;
  o.limits.max_thrust = 15.0;
  o.limits.min_thrust = 2.0;
  o.limits.max_tilt = 0.6;
  o.limits.gravity = 9.80665;
  o.temporal_cells_per_piece = 37;
  o.rho = 0.01;
  o.constraint_mode = ConstraintMode::kPaper;
  o.spatial.formulation = SpatialFormulation::kTimeCoupled;
  o.spatial.smoothness_weight = 2.5;
  o.spatial.collision_weight = 11.0;
  o.spatial.length_weight = 0.25;
  o.spatial.penalty_decay_length = 0.3;
  o.spatial.collision_samples_per_piece = 9;
  o.spatial.max_iterations = 77;
  o.spatial.heuristic_speed = 1.75;
  o.spatial.dynamic_weight = 4.0;
  o.search.heuristic_weight = 1.25;
  o.search.clearance_cost_weight = 3.5;
  o.search.max_expanded_nodes = 123456;
  return o;
}

// Written and read back, every field is exactly what it was (doubles are written with enough
// digits to round-trip), starting from defaults so that nothing is carried over by accident.
TEST(PlannerConfigJson, RoundTripIsExact) {
  const PlannerOptions o = Unusual();
  const PlannerOptions r = ParsePlannerConfigJson(PlannerConfigToJson(o), PlannerOptions());
  EXPECT_EQ(r.robot_radius, o.robot_radius);
  EXPECT_EQ(r.safety_margin, o.safety_margin);
  EXPECT_EQ(r.max_segment_length, o.max_segment_length);
  EXPECT_EQ(r.max_attempts, o.max_attempts);
  EXPECT_EQ(r.limits.max_velocity, o.limits.max_velocity);
  EXPECT_EQ(r.limits.max_acceleration, o.limits.max_acceleration);
  EXPECT_EQ(r.limits.max_acceleration_change, o.limits.max_acceleration_change);
  EXPECT_EQ(r.limits.max_jerk, o.limits.max_jerk);
  EXPECT_EQ(r.limits.max_speed, o.limits.max_speed);
  EXPECT_EQ(r.limits.max_acceleration_norm, o.limits.max_acceleration_norm);
  EXPECT_EQ(r.limits.max_thrust, o.limits.max_thrust);
  EXPECT_EQ(r.limits.min_thrust, o.limits.min_thrust);
  EXPECT_EQ(r.limits.max_tilt, o.limits.max_tilt);
  EXPECT_EQ(r.limits.gravity, o.limits.gravity);
  EXPECT_EQ(r.temporal_cells_per_piece, o.temporal_cells_per_piece);
  EXPECT_EQ(r.rho, o.rho);
  EXPECT_EQ(r.constraint_mode, o.constraint_mode);
  EXPECT_EQ(r.spatial.formulation, o.spatial.formulation);
  EXPECT_EQ(r.spatial.smoothness_weight, o.spatial.smoothness_weight);
  EXPECT_EQ(r.spatial.collision_weight, o.spatial.collision_weight);
  EXPECT_EQ(r.spatial.length_weight, o.spatial.length_weight);
  EXPECT_EQ(r.spatial.penalty_decay_length, o.spatial.penalty_decay_length);
  EXPECT_EQ(r.spatial.collision_samples_per_piece, o.spatial.collision_samples_per_piece);
  EXPECT_EQ(r.spatial.max_iterations, o.spatial.max_iterations);
  EXPECT_EQ(r.spatial.heuristic_speed, o.spatial.heuristic_speed);
  EXPECT_EQ(r.spatial.dynamic_weight, o.spatial.dynamic_weight);
  EXPECT_EQ(r.search.heuristic_weight, o.search.heuristic_weight);
  EXPECT_EQ(r.search.clearance_cost_weight, o.search.clearance_cost_weight);
  EXPECT_EQ(r.search.max_expanded_nodes, o.search.max_expanded_nodes);
  // And a second write is the same text: nothing in the format depends on the starting options.
  EXPECT_EQ(PlannerConfigToJson(r), PlannerConfigToJson(o));
}

TEST(PlannerConfigJson, KeysNotGivenKeepTheOptionsPassedIn) {
  const PlannerOptions o = Unusual();
  const PlannerOptions r = ParsePlannerConfigJson(R"({"temporal": {"K": 12}})", o);
  EXPECT_EQ(r.temporal_cells_per_piece, 12);
  EXPECT_EQ(r.robot_radius, o.robot_radius);
  EXPECT_EQ(r.spatial.formulation, o.spatial.formulation);
  EXPECT_EQ(r.limits.max_velocity, o.limits.max_velocity);
}

// null removes a limit: a per-axis one becomes none on every axis (and round-trips as null), an
// optional one unset; gravity null leaves it. The problem file's reader is the same code.
TEST(PlannerConfigJson, NullRemovesALimitAndRoundTrips) {
  const PlannerOptions o = Unusual();
  const PlannerOptions r = ParsePlannerConfigJson(
      R"({"limits": {"max_velocity": null, "max_speed": null, "max_jerk": null, "gravity": null}})", o);
  EXPECT_TRUE(r.limits.max_velocity.array().isInf().all());
  EXPECT_FALSE(r.limits.max_speed.has_value());
  EXPECT_FALSE(r.limits.max_jerk.has_value());
  EXPECT_EQ(r.limits.gravity, o.limits.gravity);
  EXPECT_EQ(r.limits.max_tilt, o.limits.max_tilt);
  const PlannerOptions back = ParsePlannerConfigJson(PlannerConfigToJson(r), PlannerOptions());
  EXPECT_TRUE(back.limits.max_velocity.array().isInf().all());
  EXPECT_FALSE(back.limits.max_speed.has_value());
  EXPECT_EQ(PlannerConfigToJson(back), PlannerConfigToJson(r));
}

TEST(PlannerConfigJson, ErrorsNameTheJsonKey) {
  EXPECT_THAT(ErrorOf(R"({"spatial": {"colision_weight": 3}})"),
              HasSubstr("config.spatial.colision_weight: unknown key"));
  EXPECT_THAT(ErrorOf(R"({"temporal": {"constraint_mode": "exact"}})"),
              HasSubstr("config.temporal.constraint_mode: expected paper or certified"));
  EXPECT_THAT(ErrorOf(R"({"temporal": {"K": 2.5}})"), HasSubstr("config.temporal.K: expected an integer"));
  EXPECT_THAT(ErrorOf(R"({"temporal": {"K": 100001}})"), HasSubstr("config.temporal.K"));
  EXPECT_THAT(ErrorOf(R"({"limits": {"max_velocity": [1, 2]}})"), HasSubstr("config.limits.max_velocity"));
  EXPECT_THAT(ErrorOf(R"({"limits": {"max_velocity": "fast"}})"),
              HasSubstr("config.limits.max_velocity: expected an array"));
  EXPECT_THAT(ErrorOf(R"({"limits": {"max_sped": 2}})"), HasSubstr("config.limits.max_sped: unknown key"));
  EXPECT_THAT(ErrorOf(R"({"search": []})"), HasSubstr("config.search: expected an object"));
  EXPECT_THAT(ErrorOf(R"({"max_attempts": 1e30})"), HasSubstr("config.max_attempts"));
  EXPECT_THAT(ErrorOf("{"), HasSubstr("config"));
}

// FromString is ToString read backwards: every name reads back as its enumerator, names are
// distinct (two equal names would read back as the first), and anything else is refused.
template <typename Enum, std::size_t N>
void ExpectNamesRoundTrip(const std::array<Enum, N>& all) {
  std::set<std::string> names;
  for (const Enum value : all) {
    Enum back = all[(static_cast<std::size_t>(value) + 1) % N];
    ASSERT_TRUE(FromString(ToString(value), &back)) << ToString(value);
    EXPECT_EQ(back, value) << ToString(value);
    names.insert(ToString(value));
  }
  EXPECT_EQ(names.size(), N);
  Enum untouched = all[0];
  EXPECT_FALSE(FromString("no such name", &untouched));
  EXPECT_FALSE(FromString("", &untouched));
  EXPECT_EQ(untouched, all[0]);
}

TEST(EnumStrings, EveryToStringHasItsFromString) {
  ExpectNamesRoundTrip(kConstraintModes);
  ExpectNamesRoundTrip(kTemporalStatuses);
  ExpectNamesRoundTrip(kTemporalBackends);
  ExpectNamesRoundTrip(kJointTypes);
  ExpectNamesRoundTrip(kPathSearchStatuses);
  ExpectNamesRoundTrip(kSpatialFormulations);
  ExpectNamesRoundTrip(kSpatialStatuses);
  ExpectNamesRoundTrip(kPlanStatuses);
  ExpectNamesRoundTrip(kUnknownSpaces);
  ExpectNamesRoundTrip(conic::kStatuses);
  ExpectNamesRoundTrip(conic::kKktMethods);
  EXPECT_EQ(EnumChoices(kTemporalBackends), "socp or ipopt");
  EXPECT_EQ(EnumChoices(kPlanStatuses).substr(0, 23), "success, invalid_input,");
}

}  // namespace
}  // namespace timeopt
