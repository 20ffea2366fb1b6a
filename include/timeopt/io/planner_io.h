#pragma once

// Planner configuration files and plan results as JSON.
//
// Configuration JSON (every key optional, unknown keys rejected; a key overrides the options given):
//   {"robot_radius": 0.3, "safety_margin": 0.2, "max_segment_length": 1.5, "max_attempts": 4,
//    "limits": {"max_velocity": 2.0 | [vx, vy, vz], "max_acceleration": 2.0 | [..],
//               "max_acceleration_change": 0.5, "max_jerk": 10.0 | [..] | null},
//    "temporal": {"K": 20, "rho": 0.0, "constraint_mode": "certified" | "paper"},
//    "spatial": {"formulation": "spatial" | "time_coupled", "smoothness_weight", "collision_weight",
//                "length_weight", "penalty_decay_length", "collision_samples_per_piece",
//                "max_iterations", "heuristic_speed", "dynamic_weight"},
//    "search": {"heuristic_weight", "clearance_cost_weight", "max_expanded_nodes"}}
// Errors: std::invalid_argument naming the JSON key ("config.spatial.colision_weight: unknown
// key"); timeopt::FileError for an unreadable file. Values are checked by PlannerOptions::IsValid.

#include <string>

#include "timeopt/planner/planner.h"

namespace timeopt {

// `options` with the keys of the configuration text applied; `context` names the text in errors.
PlannerOptions ParsePlannerConfigJson(const std::string& json_text, const PlannerOptions& options,
                                      const std::string& context = "config");
PlannerOptions ReadPlannerConfigJson(const std::string& path, const PlannerOptions& options);

// The configuration that ParsePlannerConfigJson reads back into `options` (every key written).
std::string PlannerConfigToJson(const PlannerOptions& options, int indent = 2);

// {"status", "message", "total_time", "path_length", "min_clearance", "pieces", "waypoints",
//  "spatial_attempts", "spatial_iterations", "max_velocity_ratio", "max_acceleration_ratio",
//  "time_ms": {"search", "spatial", "check", "temporal", "plan_total"}}. Numbers that are not
// meaningful for the status are null.
std::string PlanResultToJson(const PlanResult& result, int indent = 2);

}  // namespace timeopt
