#include "timeopt/spatial/path_search.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <new>
#include <optional>
#include <queue>
#include <sstream>
#include <utility>
#include <vector>

#include "timeopt/core/enum_strings.h"
#include "timeopt/core/option_check.h"

namespace timeopt {
namespace {

struct Neighbour {
  Eigen::Vector3i offset;
  double length;  // in voxels
};

const std::array<Neighbour, 26>& Neighbours() {
  static const std::array<Neighbour, 26> table = [] {
    std::array<Neighbour, 26> t;
    int n = 0;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          t[n].offset = Eigen::Vector3i(dx, dy, dz);
          t[n].length = std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz));
          ++n;
        }
      }
    }
    return t;
  }();
  return table;
}

std::string Format(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// The corners of a voxel path (start, voxel centres, goal) shortcut by line of sight: from each
// corner, the farthest later point that the straight segment reaches while its samples (every
// `line_of_sight_step` metres, 0: a quarter voxel) keep the clearance of the path between them,
// between the robot radius and the inflated radius.
std::vector<Eigen::Vector3d> Shortcut(const Esdf& esdf, const std::vector<Eigen::Vector3d>& points, double radius,
                                      double inflated, double line_of_sight_step) {
  if (points.size() <= 2) return points;
  std::vector<double> clearance(points.size());
  for (size_t k = 0; k < points.size(); ++k) clearance[k] = esdf.Distance(points[k]);
  const double step = line_of_sight_step > 0.0 ? line_of_sight_step : 0.25 * esdf.resolution();
  auto visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double threshold) {
    const double length = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
    for (int k = 1; k < n; ++k) {
      if (esdf.Distance(a + (b - a) * (static_cast<double>(k) / n)) < threshold) return false;
    }
    return true;
  };
  std::vector<Eigen::Vector3d> corners;
  size_t i = 0;
  corners.push_back(points[0]);
  while (i + 1 < points.size()) {
    // Extend the segment from point i as far as it stays visible.
    size_t best = i + 1;
    double path_min = std::min(clearance[i], clearance[i + 1]);
    for (size_t j = i + 2; j < points.size(); ++j) {
      path_min = std::min(path_min, clearance[j]);
      const double threshold = std::max(radius, std::min(inflated, path_min));
      if (!visible(points[i], points[j], threshold)) break;
      best = j;
    }
    corners.push_back(points[best]);
    i = best;
  }
  return corners;
}

// Why start and goal cannot be searched from and to (outside the field's domain, or closer to an
// obstacle than the robot radius), or nullopt.
std::optional<std::pair<PathSearchStatus, std::string>> CheckEnds(const Esdf& esdf, const Eigen::Vector3d& start,
                                                                  const Eigen::Vector3d& goal, double radius) {
  const Eigen::AlignedBox3d domain = esdf.domain();
  auto outside = [&](const char* which, const Eigen::Vector3d& p) {
    std::ostringstream s;
    s << which << " " << Format(p) << " is outside the map's domain " << Format(domain.min()) << " - "
      << Format(domain.max());
    return s.str();
  };
  if (!esdf.Contains(start)) return std::make_pair(PathSearchStatus::kStartOutsideMap, outside("start", start));
  if (!esdf.Contains(goal)) return std::make_pair(PathSearchStatus::kGoalOutsideMap, outside("goal", goal));
  auto collides = [&](const char* which, const Eigen::Vector3d& p, double d) {
    std::ostringstream s;
    s << which << " " << Format(p) << " has clearance " << d << " m, below the robot radius " << radius << " m";
    return s.str();
  };
  const double d_start = esdf.Distance(start), d_goal = esdf.Distance(goal);
  if (d_start < radius) return std::make_pair(PathSearchStatus::kStartInCollision, collides("start", start, d_start));
  if (d_goal < radius) return std::make_pair(PathSearchStatus::kGoalInCollision, collides("goal", goal, d_goal));
  return std::nullopt;
}

}  // namespace

const char* ToString(PathSearchStatus status) {
  switch (status) {
    case PathSearchStatus::kSuccess:
      return "success";
    case PathSearchStatus::kInvalidInput:
      return "invalid_input";
    case PathSearchStatus::kStartOutsideMap:
      return "start_outside_map";
    case PathSearchStatus::kGoalOutsideMap:
      return "goal_outside_map";
    case PathSearchStatus::kStartInCollision:
      return "start_in_collision";
    case PathSearchStatus::kGoalInCollision:
      return "goal_in_collision";
    case PathSearchStatus::kUnreachable:
      return "unreachable";
    case PathSearchStatus::kNodeLimit:
      return "node_limit";
  }
  return "unknown";
}

bool FromString(const std::string& text, PathSearchStatus* status) {
  return EnumFromString(text, kPathSearchStatuses, status);
}

bool PathSearchOptions::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& field, const std::string& expected, double got) {
    return internal::FailOption(error, field, expected, got);
  };
  if (!std::isfinite(robot_radius) || robot_radius < 0.0) {
    return fail("robot_radius", "a finite number >= 0 (metres)", robot_radius);
  }
  if (!std::isfinite(clearance_margin) || clearance_margin <= 0.0) {
    return fail("clearance_margin", "a positive number (metres)", clearance_margin);
  }
  if (!std::isfinite(clearance_cost_weight) || clearance_cost_weight < 0.0) {
    return fail("clearance_cost_weight", "a finite number >= 0", clearance_cost_weight);
  }
  if (!std::isfinite(heuristic_weight) || heuristic_weight < 1.0) {
    return fail("heuristic_weight", "a finite number >= 1", heuristic_weight);
  }
  if (max_expanded_nodes < 1) {
    return fail("max_expanded_nodes", "an integer >= 1", static_cast<double>(max_expanded_nodes));
  }
  if (!std::isfinite(line_of_sight_step) || line_of_sight_step < 0.0) {
    return fail("line_of_sight_step", "a finite number >= 0 (0: automatic)", line_of_sight_step);
  }
  return true;
}

PathSearch::PathSearch(const Esdf& esdf) : esdf_(&esdf) {}

PathSearchResult PathSearch::Search(const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                                    const PathSearchOptions& options) {
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  PathSearchResult result;
  auto finish = [&](PathSearchStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.search_time_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    return result;
  };
  std::string error;
  if (!options.IsValid(&error)) return finish(PathSearchStatus::kInvalidInput, "options." + error);
  if (!start.allFinite()) return finish(PathSearchStatus::kInvalidInput, "start: not finite");
  if (!goal.allFinite()) return finish(PathSearchStatus::kInvalidInput, "goal: not finite");

  const Esdf& esdf = *esdf_;
  const double radius = options.robot_radius;
  if (const auto bad = CheckEnds(esdf, start, goal, radius)) return finish(bad->first, bad->second);

  const VoxelBox& box = esdf.box();
  const double res = esdf.resolution();
  const int64_t total = box.num_voxels();
  if (total > std::numeric_limits<int32_t>::max()) {
    return finish(PathSearchStatus::kInvalidInput, "map: too many voxels for the search");
  }
  if (cells_ != total) {
    const size_t n = static_cast<size_t>(total);
    g_.reset(static_cast<float*>(std::malloc(n * sizeof(float))));
    parent_.reset(static_cast<int32_t*>(std::malloc(n * sizeof(int32_t))));
    state_.reset(static_cast<uint8_t*>(std::calloc(n, sizeof(uint8_t))));
    touched_.clear();
    if (!g_ || !parent_ || !state_) {
      cells_ = 0;
      throw std::bad_alloc();
    }
    cells_ = total;
  }
  for (const int32_t i : touched_) state_[i] = 0;
  touched_.clear();

  const int nx = box.size.x(), ny = box.size.y();
  auto local_of = [&](const Eigen::Vector3d& p) {
    Eigen::Vector3i w = (p / res).array().floor().cast<int>();
    Eigen::Vector3i l = w - box.min;
    return Eigen::Vector3i(l.cwiseMax(0).cwiseMin(box.size - Eigen::Vector3i::Ones()));
  };
  auto linear = [&](const Eigen::Vector3i& l) { return l.x() + nx * (l.y() + ny * l.z()); };
  auto decode = [&](int32_t i) { return Eigen::Vector3i(i % nx, (i / nx) % ny, i / (nx * ny)); };
  auto centre = [&](const Eigen::Vector3i& l) {
    return Eigen::Vector3d(((l + box.min).cast<double>().array() + 0.5) * res);
  };

  const Eigen::Vector3i start_local = local_of(start), goal_local = local_of(goal);
  const int32_t start_index = linear(start_local), goal_index = linear(goal_local);
  const double inflated = radius + options.clearance_margin;
  const double eps = options.heuristic_weight;
  // The 26-connected grid distance (octile in 3-D), in voxels: the length of the shortest lattice
  // path ignoring obstacles. Admissible (every step costs at least its length) and much tighter
  // than the Euclidean distance, so far fewer voxels are expanded.
  auto heuristic = [&](const Eigen::Vector3i& l) {
    Eigen::Vector3i d = (l - goal_local).cwiseAbs();
    std::sort(d.data(), d.data() + 3);  // d(0) <= d(1) <= d(2)
    constexpr double kSqrt2 = 1.4142135623730951, kSqrt3 = 1.7320508075688772;
    return eps * (kSqrt3 * d(0) + kSqrt2 * (d(1) - d(0)) + (d(2) - d(1)));
  };

  using Entry = std::pair<float, int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  g_[start_index] = 0.0f;
  parent_[start_index] = -1;
  state_[start_index] = 1;
  touched_.push_back(start_index);
  open.emplace(static_cast<float>(heuristic(start_local)), start_index);
  bool found = false;
  while (!open.empty()) {
    const int32_t current = open.top().second;
    open.pop();
    if (state_[current] == 2) continue;
    state_[current] = 2;
    if (current == goal_index) {
      found = true;
      break;
    }
    if (++result.expanded_nodes > options.max_expanded_nodes) {
      std::ostringstream s;
      s << "the search expanded " << options.max_expanded_nodes
        << " voxels (max_expanded_nodes) without reaching the goal";
      return finish(PathSearchStatus::kNodeLimit, s.str());
    }
    const Eigen::Vector3i l = decode(current);
    const float g_current = g_[current];
    for (const Neighbour& n : Neighbours()) {
      const Eigen::Vector3i nl = l + n.offset;
      if ((nl.array() < 0).any() || (nl.array() >= box.size.array()).any()) continue;
      const int32_t ni = linear(nl);
      if (state_[ni] == 2) continue;
      double extra = 0.0;
      if (ni != goal_index) {
        const double d = esdf.VoxelDistance(nl + box.min);
        if (d < radius) continue;
        if (d < inflated) extra = options.clearance_cost_weight * (inflated - d) / options.clearance_margin;
      }
      const float g_new = g_current + static_cast<float>(n.length * (1.0 + extra));
      if (state_[ni] == 0 || g_new < g_[ni]) {
        if (state_[ni] == 0) touched_.push_back(ni);
        state_[ni] = 1;
        g_[ni] = g_new;
        parent_[ni] = current;
        open.emplace(static_cast<float>(g_new + heuristic(nl)), ni);
      }
    }
  }
  if (!found) {
    std::ostringstream s;
    s << "no path with clearance " << radius << " m from " << Format(start) << " to " << Format(goal) << " ("
      << result.expanded_nodes << " voxels expanded)";
    return finish(PathSearchStatus::kUnreachable, s.str());
  }

  // Voxel path: start point, interior voxel centres, goal point.
  std::vector<int32_t> chain;
  for (int32_t i = goal_index; i != -1; i = parent_[i]) chain.push_back(i);
  std::reverse(chain.begin(), chain.end());
  std::vector<Eigen::Vector3d> points;
  points.push_back(start);
  for (size_t k = 1; k + 1 < chain.size(); ++k) points.push_back(centre(decode(chain[k])));
  points.push_back(goal);
  result.voxel_path.resize(3, static_cast<Eigen::Index>(points.size()));
  for (size_t k = 0; k < points.size(); ++k) result.voxel_path.col(static_cast<Eigen::Index>(k)) = points[k];

  const std::vector<Eigen::Vector3d> corners =
      options.shortcut ? Shortcut(esdf, points, radius, inflated, options.line_of_sight_step) : points;
  result.waypoints.resize(3, static_cast<Eigen::Index>(corners.size()));
  for (size_t k = 0; k < corners.size(); ++k) result.waypoints.col(static_cast<Eigen::Index>(k)) = corners[k];
  return finish(PathSearchStatus::kSuccess, "");
}

}  // namespace timeopt
