#include "timeopt/io/planner_io.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <stdexcept>
#include <vector>

#include "json_internal.h"
#include "timeopt/core/files.h"

namespace timeopt {
namespace {

using nlohmann::json;

// The configuration's numeric keys, each bound to its field, so that reading and writing share one
// table (a key is spelt once).
template <typename Options>
struct RealKey {
  const char* key;
  double Options::*field;
};
template <typename Options>
struct IntKey {
  const char* key;
  int Options::*field;
};

const std::vector<RealKey<PlannerOptions>> kTopReals = {{"robot_radius", &PlannerOptions::robot_radius},
                                                        {"safety_margin", &PlannerOptions::safety_margin},
                                                        {"max_segment_length", &PlannerOptions::max_segment_length}};
const std::vector<IntKey<PlannerOptions>> kTopInts = {{"max_attempts", &PlannerOptions::max_attempts}};
const std::vector<RealKey<SpatialOptimizerOptions>> kSpatialReals = {
    {"smoothness_weight", &SpatialOptimizerOptions::smoothness_weight},
    {"collision_weight", &SpatialOptimizerOptions::collision_weight},
    {"length_weight", &SpatialOptimizerOptions::length_weight},
    {"penalty_decay_length", &SpatialOptimizerOptions::penalty_decay_length},
    {"heuristic_speed", &SpatialOptimizerOptions::heuristic_speed},
    {"dynamic_weight", &SpatialOptimizerOptions::dynamic_weight}};
const std::vector<IntKey<SpatialOptimizerOptions>> kSpatialInts = {
    {"collision_samples_per_piece", &SpatialOptimizerOptions::collision_samples_per_piece},
    {"max_iterations", &SpatialOptimizerOptions::max_iterations}};
const std::vector<RealKey<PathSearchOptions>> kSearchReals = {
    {"heuristic_weight", &PathSearchOptions::heuristic_weight},
    {"clearance_cost_weight", &PathSearchOptions::clearance_cost_weight}};

template <typename Options>
std::set<std::string> Keys(const std::vector<RealKey<Options>>& reals, const std::vector<IntKey<Options>>& ints,
                           std::set<std::string> extra) {
  for (const auto& r : reals) extra.insert(r.key);
  for (const auto& i : ints) extra.insert(i.key);
  return extra;
}

template <typename Options>
void ReadKeys(const json& j, const std::string& where, const std::vector<RealKey<Options>>& reals,
              const std::vector<IntKey<Options>>& ints, Options* o) {
  for (const auto& r : reals) {
    if (j.contains(r.key)) o->*r.field = internal::FiniteNumber(j.at(r.key), where + "." + r.key);
  }
  for (const auto& i : ints) {
    if (j.contains(i.key)) {
      o->*i.field = static_cast<int>(internal::IntegerInRange(
          j.at(i.key), where + "." + i.key, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
    }
  }
}

template <typename Options>
void WriteKeys(const Options& o, const std::vector<RealKey<Options>>& reals, const std::vector<IntKey<Options>>& ints,
               json* j) {
  for (const auto& r : reals) (*j)[r.key] = o.*r.field;
  for (const auto& i : ints) (*j)[i.key] = o.*i.field;
}

const std::vector<IntKey<PathSearchOptions>> kNoSearchInts = {};

}  // namespace

PlannerOptions ParsePlannerConfigJson(const std::string& json_text, const PlannerOptions& options,
                                      const std::string& context) {
  const json root = internal::ParseJsonText(json_text, context);
  internal::RequireObject(root, context);
  internal::RejectUnknownKeys(root, Keys(kTopReals, kTopInts, {"limits", "temporal", "spatial", "search"}), context);
  PlannerOptions o = options;
  ReadKeys(root, context, kTopReals, kTopInts, &o);
  if (root.contains("limits")) internal::ReadLimits(root.at("limits"), context + ".limits", &o.limits);
  if (root.contains("temporal")) {
    const json& t = root.at("temporal");
    const std::string where = context + ".temporal";
    internal::RequireObject(t, where);
    internal::RejectUnknownKeys(t, {"K", "rho", "constraint_mode"}, where);
    if (t.contains("K")) {
      o.temporal_cells_per_piece =
          static_cast<int>(internal::IntegerInRange(t.at("K"), where + ".K", 1, kMaxCellsPerPiece));
    }
    if (t.contains("rho")) o.rho = internal::FiniteNumber(t.at("rho"), where + ".rho");
    if (t.contains("constraint_mode")) {
      o.constraint_mode = internal::EnumField(t.at("constraint_mode"), where + ".constraint_mode", kConstraintModes);
    }
  }
  if (root.contains("spatial")) {
    const json& s = root.at("spatial");
    const std::string where = context + ".spatial";
    internal::RequireObject(s, where);
    internal::RejectUnknownKeys(s, Keys(kSpatialReals, kSpatialInts, {"formulation", "parameterization"}), where);
    if (s.contains("parameterization")) {
      o.spatial.parameterization =
          internal::EnumField(s.at("parameterization"), where + ".parameterization", kSpatialParameterizations);
    }
    if (s.contains("formulation")) {
      o.spatial.formulation = internal::EnumField(s.at("formulation"), where + ".formulation", kSpatialFormulations);
    }
    ReadKeys(s, where, kSpatialReals, kSpatialInts, &o.spatial);
  }
  if (root.contains("search")) {
    const json& s = root.at("search");
    const std::string where = context + ".search";
    internal::RequireObject(s, where);
    internal::RejectUnknownKeys(s, Keys(kSearchReals, kNoSearchInts, {"max_expanded_nodes"}), where);
    ReadKeys(s, where, kSearchReals, kNoSearchInts, &o.search);
    if (s.contains("max_expanded_nodes")) {
      o.search.max_expanded_nodes = internal::IntegerInRange(s.at("max_expanded_nodes"), where + ".max_expanded_nodes",
                                                             1, std::numeric_limits<int64_t>::max());
    }
  }
  return o;
}

PlannerOptions ReadPlannerConfigJson(const std::string& path, const PlannerOptions& options) {
  const std::string text = ReadTextFile(path);
  try {
    return ParsePlannerConfigJson(text, options);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

std::string PlannerConfigToJson(const PlannerOptions& o, int indent) {
  json root;
  WriteKeys(o, kTopReals, kTopInts, &root);
  root["limits"] = internal::LimitsJson(o.limits);
  root["temporal"] = {
      {"K", o.temporal_cells_per_piece}, {"rho", o.rho}, {"constraint_mode", ToString(o.constraint_mode)}};
  json spatial = {{"formulation", ToString(o.spatial.formulation)},
                  {"parameterization", ToString(o.spatial.parameterization)}};
  WriteKeys(o.spatial, kSpatialReals, kSpatialInts, &spatial);
  root["spatial"] = spatial;
  json search;
  WriteKeys(o.search, kSearchReals, kNoSearchInts, &search);
  search["max_expanded_nodes"] = o.search.max_expanded_nodes;
  root["search"] = search;
  return root.dump(indent) + "\n";
}

std::string PlanResultToJson(const PlanResult& plan, int indent) {
  nlohmann::ordered_json j;
  const bool ok = plan.is_success();
  const bool has_curve = !plan.curve.empty();
  j["status"] = ToString(plan.status);
  j["message"] = plan.message;
  const auto value_if = [](bool known, double value) {
    return known ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
  };
  j["total_time"] = value_if(ok, plan.temporal.total_time);
  j["path_length"] = value_if(has_curve, plan.path_length);
  j["min_clearance"] = value_if(has_curve, plan.min_clearance);
  j["min_interior_speed"] = value_if(std::isfinite(plan.min_interior_speed), plan.min_interior_speed);
  j["min_curvature_radius"] = value_if(std::isfinite(plan.min_curvature_radius), plan.min_curvature_radius);
  j["pieces"] = plan.curve.num_pieces();
  j["waypoints"] = static_cast<int>(plan.waypoints.cols());
  j["spatial_attempts"] = plan.spatial_attempts;
  j["start_scale"] = plan.start_scale;
  if (!plan.temporal.method.empty()) j["temporal_method"] = plan.temporal.method;
  j["spatial_iterations"] = static_cast<int>(plan.spatial.iterations.size());
  j["max_velocity_ratio"] = value_if(ok, plan.temporal.max_velocity_ratio);
  j["max_acceleration_ratio"] = value_if(ok, plan.temporal.max_acceleration_ratio);
  // The quadrotor's limits, for the ones given.
  const auto ratio = [&](const char* key, const std::optional<double>& value) {
    if (value) j[key] = value_if(ok, *value);
  };
  ratio("max_speed_ratio", plan.temporal.max_speed_ratio);
  ratio("max_acceleration_norm_ratio", plan.temporal.max_acceleration_norm_ratio);
  ratio("max_thrust_ratio", plan.temporal.max_thrust_ratio);
  ratio("min_thrust_ratio", plan.temporal.min_thrust_ratio);
  ratio("max_tilt_ratio", plan.temporal.max_tilt_ratio);
  if (plan.temporal.boundary_relaxation) {
    // A start in motion too fast for the new curve: flown at the closest start speed instead.
    j["boundary_relaxation"] = {{"start_speed_given", plan.temporal.boundary_relaxation->start_speed_given},
                                {"start_speed", plan.temporal.boundary_relaxation->start_speed}};
  }
  j["time_ms"] = {{"search", plan.times.search_seconds * 1e3},
                  {"spatial", plan.times.spatial_seconds * 1e3},
                  {"check", plan.times.check_seconds * 1e3},
                  {"temporal", plan.times.temporal_seconds * 1e3},
                  {"plan_total", plan.times.total_seconds * 1e3}};
  return j.dump(indent) + "\n";
}

}  // namespace timeopt
