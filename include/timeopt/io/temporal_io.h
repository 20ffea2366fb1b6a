#pragma once

// Temporal problem and result files, and trajectory sample CSVs (all in docs/formats.md).
//
// Problem JSON:
//   {"curve": {...curve contract, optional "durations"...},
//    "limits": {"max_velocity": 2.0 | [vx, vy, vz], "max_acceleration": 1.0 | [ax, ay, az],
//               "max_acceleration_change": 0.5,                (optional)
//               "max_jerk": 10.0 | [jx, jy, jz]},              (optional: jerk-limited profile)
//    "boundary": {"start_velocity": [..], "start_acceleration": [..],
//                 "end_velocity": [..], "end_acceleration": [..]},   (optional: rest to rest)
//    "discretization": {"K": 50}, "rho": 0.0, "constraint_mode": "paper" | "certified"}
// Unknown keys are rejected so that a typo does not silently fall back to a default.
// Errors: std::invalid_argument naming the field; timeopt::FileError for unreadable files.

#include <string>
#include <vector>

#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

TemporalProblem ParseTemporalProblemJson(const std::string& json_text, const std::string& context = "problem");
TemporalProblem ReadTemporalProblemJson(const std::string& path);

// {"status", "solver", "total_time", "objective", "piece_durations", "iterations",
//  "solve_time_ms", "build_time_ms", "message", "max_velocity_ratio", "max_acceleration_ratio",
//  "joints": [{"joint", "type", "speed_ratio", "angle"}]}, and for jerk-limited problems
// "max_jerk_ratio", "scp_iterations" and "scp_history" (T after each convex solve). Numbers that
// are not meaningful for a non-optimal status are null.
std::string TemporalResultToJson(const TemporalResult& result, int indent = 2);

// Header t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz then one row per state, full precision.
std::string SamplesToCsv(const std::vector<TrajectoryState>& samples);

// Reads samples written by SamplesToCsv, or by another planner in the same columns; the jerk columns
// may be left out (header t,x,y,z,vx,vy,vz,ax,ay,az), and then jerk is the difference quotient of
// the acceleration to the next sample (0 on the last). At least 2 rows, t finite and strictly
// increasing, every value finite. Throws std::invalid_argument naming the source and line, or
// timeopt::FileError when the file cannot be read.
std::vector<TrajectoryState> ParseSamplesCsv(const std::string& csv_text, const std::string& source);
std::vector<TrajectoryState> ReadSamplesCsv(const std::string& path);

}  // namespace timeopt
