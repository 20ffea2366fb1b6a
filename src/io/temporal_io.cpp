#include "timeopt/io/temporal_io.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "json_internal.h"

namespace timeopt {
namespace {

using internal::PerAxis;
using internal::RejectUnknownKeys;
using internal::Vector3;
using nlohmann::json;

const json& Require(const json& j, const std::string& key, const std::string& where) {
  if (!j.contains(key)) throw std::invalid_argument(where + key + ": missing");
  return j.at(key);
}

}  // namespace

TemporalProblem ParseTemporalProblemJson(const std::string& json_text, const std::string& context) {
  const json j = internal::ParseJsonText(json_text, context);
  if (!j.is_object()) throw std::invalid_argument(context + ": expected a JSON object");
  RejectUnknownKeys(j, {"curve", "limits", "boundary", "discretization", "rho", "constraint_mode", "relax_boundary"},
                    "");
  TemporalProblem p;
  p.curve = internal::CurveFromJson(Require(j, "curve", ""), "curve").curve;

  // The per-axis limits are optional when the quadrotor's norm limits bound the same quantity
  // (TemporalProblem::Validate says which is missing): absent means none on any axis.
  constexpr double kNone = std::numeric_limits<double>::infinity();
  p.limits.max_velocity = Eigen::Vector3d::Constant(kNone);
  p.limits.max_acceleration = Eigen::Vector3d::Constant(kNone);
  internal::ReadLimits(Require(j, "limits", ""), "limits", &p.limits);

  if (j.contains("boundary")) {
    const json& b = j.at("boundary");
    if (!b.is_object()) throw std::invalid_argument("boundary: expected an object");
    RejectUnknownKeys(b, {"start_velocity", "start_acceleration", "end_velocity", "end_acceleration"}, "boundary");
    if (b.contains("start_velocity"))
      p.boundary.start_velocity = Vector3(b.at("start_velocity"), "boundary.start_velocity");
    if (b.contains("start_acceleration"))
      p.boundary.start_acceleration = Vector3(b.at("start_acceleration"), "boundary.start_acceleration");
    if (b.contains("end_velocity")) p.boundary.end_velocity = Vector3(b.at("end_velocity"), "boundary.end_velocity");
    if (b.contains("end_acceleration"))
      p.boundary.end_acceleration = Vector3(b.at("end_acceleration"), "boundary.end_acceleration");
  }

  if (j.contains("discretization")) {
    const json& d = j.at("discretization");
    if (!d.is_object()) throw std::invalid_argument("discretization: expected an object");
    RejectUnknownKeys(d, {"K"}, "discretization");
    if (d.contains("K")) {
      p.cells_per_piece =
          static_cast<int>(internal::IntegerInRange(d.at("K"), "discretization.K", 1, kMaxCellsPerPiece));
    }
  }
  if (j.contains("rho")) p.rho = internal::FiniteNumber(j.at("rho"), "rho");
  if (j.contains("relax_boundary")) {
    if (!j.at("relax_boundary").is_boolean()) throw std::invalid_argument("relax_boundary: expected true or false");
    p.relax_boundary = j.at("relax_boundary").get<bool>();
  }
  if (j.contains("constraint_mode")) {
    p.constraint_mode = internal::EnumField(j.at("constraint_mode"), "constraint_mode", kConstraintModes);
  }
  p.Validate();
  return p;
}

TemporalProblem ReadTemporalProblemJson(const std::string& path) {
  try {
    return ParseTemporalProblemJson(ReadTextFile(path));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

std::string TemporalResultToJson(const TemporalResult& r, int indent) {
  json j;
  const bool ok = r.is_success();
  j["status"] = ToString(r.status);
  j["solver"] = r.solver;
  if (!r.method.empty()) j["method"] = r.method;
  j["total_time"] = ok ? json(r.total_time) : json(nullptr);
  j["objective"] = ok ? json(r.objective) : json(nullptr);
  j["piece_durations"] = ok ? json(r.piece_durations) : json::array();
  j["iterations"] = r.iterations;
  j["solve_time_ms"] = r.solve_time_seconds * 1e3;
  j["build_time_ms"] = r.build_time_seconds * 1e3;
  j["message"] = r.message;
  j["reduced_accuracy"] = r.reduced_accuracy;
  j["max_velocity_ratio"] = ok ? json(r.max_velocity_ratio) : json(nullptr);
  j["max_acceleration_ratio"] = ok ? json(r.max_acceleration_ratio) : json(nullptr);
  // The quadrotor's limits, for the ones given.
  const auto ratio = [&](const char* key, const std::optional<double>& value) {
    if (value) j[key] = ok ? json(*value) : json(nullptr);
  };
  ratio("max_speed_ratio", r.max_speed_ratio);
  ratio("max_acceleration_norm_ratio", r.max_acceleration_norm_ratio);
  ratio("max_thrust_ratio", r.max_thrust_ratio);
  ratio("min_thrust_ratio", r.min_thrust_ratio);
  ratio("max_tilt_ratio", r.max_tilt_ratio);
  if (r.jerk_limited) {
    // Jerk-limited results only (the paper's results keep their keys).
    j["max_jerk_ratio"] = ok ? json(r.max_jerk_ratio) : json(nullptr);
    j["scp_iterations"] = r.scp_iterations;
    j["scp_history"] = r.scp_history;
  }
  if (r.infeasibility) {
    j["infeasibility"] = {
        {"cause", r.infeasibility->cause}, {"where", r.infeasibility->where}, {"detail", r.infeasibility->detail}};
  }
  if (r.boundary_relaxation) {
    const TemporalResult::BoundaryRelaxation& b = *r.boundary_relaxation;
    j["boundary_relaxation"] = {{"start_speed_given", b.start_speed_given},
                                {"start_speed", b.start_speed},
                                {"start_violation", b.start_speed_given - b.start_speed},
                                {"end_speed_given", b.end_speed_given},
                                {"end_speed", b.end_speed},
                                {"end_violation", b.end_speed_given - b.end_speed},
                                {"start_scale", b.start_scale},
                                {"start_acceleration", b.start_acceleration}};
  }
  json joints = json::array();
  for (const JointInfo& ji : r.joints) {
    json joint = {
        {"joint", ji.joint}, {"type", ToString(ji.type)}, {"speed_ratio", ji.speed_ratio}, {"angle", ji.angle}};
    if (!ji.reason.empty()) joint["reason"] = ji.reason;
    joints.push_back(std::move(joint));
  }
  j["joints"] = joints;
  return j.dump(indent) + "\n";
}

std::string SamplesToCsv(const std::vector<TrajectoryState>& samples) {
  std::string out = "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz\n";
  out.reserve(out.size() + samples.size() * 13 * 24);
  char buffer[32];
  for (const TrajectoryState& s : samples) {
    const double values[13] = {s.t,
                               s.position.x(),
                               s.position.y(),
                               s.position.z(),
                               s.velocity.x(),
                               s.velocity.y(),
                               s.velocity.z(),
                               s.acceleration.x(),
                               s.acceleration.y(),
                               s.acceleration.z(),
                               s.jerk.x(),
                               s.jerk.y(),
                               s.jerk.z()};
    for (int i = 0; i < 13; ++i) {
      std::snprintf(buffer, sizeof(buffer), "%.17g", values[i]);
      out += buffer;
      out += i == 12 ? '\n' : ',';
    }
  }
  return out;
}

std::vector<TrajectoryState> ParseSamplesCsv(const std::string& csv_text, const std::string& source) {
  std::istringstream in(csv_text);
  std::string line;
  int line_number = 0, columns = 0;
  std::vector<TrajectoryState> samples;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::string compact;
    for (char ch : line) {
      if (ch != ' ' && ch != '\t') compact += ch;
    }
    if (compact.empty() || compact[0] == '#') continue;
    const std::string where = source + " line " + std::to_string(line_number);
    if (columns == 0) {
      if (compact == "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz")
        columns = 13;
      else if (compact == "t,x,y,z,vx,vy,vz,ax,ay,az")
        columns = 10;
      else
        throw std::invalid_argument(where + ": expected the header t,x,y,z,vx,vy,vz,ax,ay,az[,jx,jy,jz]");
      continue;
    }
    const std::vector<double> values = internal::CsvNumbers(compact, where);
    if (static_cast<int>(values.size()) != columns) {
      throw std::invalid_argument(where + ": expected " + std::to_string(columns) + " values, got " +
                                  std::to_string(values.size()));
    }
    TrajectoryState s;
    s.t = values[0];
    s.position = Eigen::Vector3d(values[1], values[2], values[3]);
    s.velocity = Eigen::Vector3d(values[4], values[5], values[6]);
    s.acceleration = Eigen::Vector3d(values[7], values[8], values[9]);
    if (columns == 13) s.jerk = Eigen::Vector3d(values[10], values[11], values[12]);
    if (!samples.empty() && !(s.t > samples.back().t)) {
      char text[96];
      std::snprintf(text, sizeof(text), "%.10g after %.10g", s.t, samples.back().t);
      throw std::invalid_argument(where + ": t must increase strictly (" + text + ")");
    }
    samples.push_back(s);
  }
  if (columns == 0) throw std::invalid_argument(source + ": no header t,x,y,z,vx,vy,vz,ax,ay,az[,jx,jy,jz]");
  if (samples.size() < 2) {
    throw std::invalid_argument(source + ": expected at least 2 samples, got " + std::to_string(samples.size()));
  }
  if (columns == 10) {
    for (size_t k = 0; k + 1 < samples.size(); ++k) {
      samples[k].jerk = (samples[k + 1].acceleration - samples[k].acceleration) / (samples[k + 1].t - samples[k].t);
    }
  }
  return samples;
}

std::vector<TrajectoryState> ReadSamplesCsv(const std::string& path) {
  return ParseSamplesCsv(ReadTextFile(path), path);
}

}  // namespace timeopt
