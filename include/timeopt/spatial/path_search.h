#pragma once

// The front-end of the planner: A* on the voxel grid of an ESDF (26-connected), then greedy
// line-of-sight shortcutting against the field, giving a few waypoints for the spatial optimizer.
//
// Clearance: a voxel is entered only when the distance stored at its centre is at least the robot
// radius (hard). Below robot radius + clearance margin a step costs more (soft), so the search
// prefers wide gaps but still threads a gap that is only slightly wider than the robot:
//   step cost = step length * (1 + clearance_cost_weight * max(0, r + margin - d) / margin).
// The heuristic is the 26-connected lattice distance (admissible: every step costs at least its
// length), times heuristic_weight.
//
// A PathSearch keeps its work arrays between calls (no allocation per search after the first on
// a map); it is not thread-safe, one object per thread.

#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "timeopt/curve/interpolation.h"
#include "timeopt/map/esdf.h"

namespace timeopt {

struct PathSearchOptions {
  // Radius of the sphere that must stay free, metres. 0.3: the default quadrotor.
  double robot_radius = 0.3;
  // Soft clearance above the radius, metres: below radius + margin steps cost more. 0.2: two
  // voxels of the forest maps, room for the optimizer's smoothing without touching the radius.
  double clearance_margin = 0.2;
  // Relative extra cost of a step at the radius (dimensionless; 0 disables the soft term). 2:
  // a detour of up to about twice the length is preferred over grazing an obstacle.
  double clearance_cost_weight = 2.0;
  // A* inflation factor epsilon >= 1 on the heuristic (1: optimal paths; larger: faster, paths at
  // most epsilon times the optimal cost). 1.2: on the shipped forest's default plan the path of 1.5
  // went round a longer way (T 13.30 s against 11.99 s, search 8 ms against 28 ms), and in dense
  // generated forests it left a start the wrong way and turned back around a tree (2 of 2,500
  // plans braked below 0.3 vmax; none with 1.2, and 1 with 1.3; docs/planner.md).
  double heuristic_weight = 1.2;
  // The search stops with kNodeLimit after expanding this many voxels (it never hangs).
  int64_t max_expanded_nodes = 2000000;
  // Shortcut the voxel path by line of sight. A segment is accepted when the field along it stays
  // at or above min(radius + margin, the smallest centre distance on the voxel path it replaces),
  // and never below the radius.
  bool shortcut = true;
  // Sampling step of the line-of-sight checks, metres; 0: a quarter of the map resolution.
  double line_of_sight_step = 0.0;

  bool IsValid(std::string* error) const;
};

enum class PathSearchStatus {
  kSuccess,           // waypoints usable
  kInvalidInput,      // bad options or a non-finite point; message names it
  kStartOutsideMap,   // the start is outside the ESDF's domain
  kGoalOutsideMap,    // the goal is outside the ESDF's domain
  kStartInCollision,  // the field at the start is below the robot radius
  kGoalInCollision,   // the field at the goal is below the robot radius
  kUnreachable,       // no voxel path with the clearance exists
  kNodeLimit,         // max_expanded_nodes reached first
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<PathSearchStatus, 8> kPathSearchStatuses = {
    PathSearchStatus::kSuccess,        PathSearchStatus::kInvalidInput,     PathSearchStatus::kStartOutsideMap,
    PathSearchStatus::kGoalOutsideMap, PathSearchStatus::kStartInCollision, PathSearchStatus::kGoalInCollision,
    PathSearchStatus::kUnreachable,    PathSearchStatus::kNodeLimit,
};
const char* ToString(PathSearchStatus status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, PathSearchStatus* status);

struct PathSearchResult {
  PathSearchStatus status = PathSearchStatus::kInvalidInput;
  std::string message;
  Waypoints waypoints;   // start, shortcut corners, goal (exact start and goal points)
  Waypoints voxel_path;  // start, the voxel centres visited by A*, goal (before shortcutting)
  int64_t expanded_nodes = 0;
  double search_time_seconds = 0.0;
  bool is_success() const { return status == PathSearchStatus::kSuccess; }
};

class PathSearch {
 public:
  // The ESDF must outlive the object.
  explicit PathSearch(const Esdf& esdf);
  PathSearchResult Search(const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                          const PathSearchOptions& options = {});

 private:
  // Per-voxel arrays that cost memory only where the search writes: state_ is zeroed by calloc and
  // g_ and parent_ are left uninitialized (read only where state_ is not 0), so the kernel maps
  // their pages on first touch. A whole-map field of 1e8 voxels no longer costs 900 MB here.
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  const Esdf* esdf_;
  int64_t cells_ = 0;                               // size of the arrays below
  std::unique_ptr<float[], FreeDeleter> g_;         // cost-to-come per voxel
  std::unique_ptr<int32_t[], FreeDeleter> parent_;  // linear index of the parent, -1 for none
  std::unique_ptr<uint8_t[], FreeDeleter> state_;   // 0 new, 1 open, 2 closed
  std::vector<int32_t> touched_;                    // voxels to reset before the next search
};

}  // namespace timeopt
