#include "timeopt/io/trajectory_io.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "json_internal.h"

namespace timeopt {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kFormatName = "timeopt-trajectory";
constexpr int kFormatVersion = 1;
constexpr double kPi = 3.14159265358979323846;

std::vector<std::vector<double>> Rows(const nlohmann::json& j, const std::string& field, size_t rows, int columns) {
  if (!j.is_array() || j.size() != rows) {
    throw std::invalid_argument(field + ": expected an array of " + std::to_string(rows) + " arrays (one per piece)");
  }
  std::vector<std::vector<double>> out;
  for (size_t i = 0; i < rows; ++i)
    out.push_back(internal::FiniteArray(j[i], field + "[" + std::to_string(i) + "]", columns));
  return out;
}

void AppendNumber(std::string* out, double value, char end) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  *out += buffer;
  *out += end;
}

}  // namespace

std::string TrajectoryToJson(const Trajectory& trajectory, int indent) {
  const TemporalProfile& profile = trajectory.profile();
  Json j;
  j["format"] = kFormatName;
  j["version"] = kFormatVersion;
  j["frame"] = "ENU";
  j["duration"] = trajectory.duration();
  j["curve"] = Json::parse(CurveToJson(trajectory.curve(), -1));
  Json p;
  const int m = profile.num_pieces(), K = profile.cells_per_piece();
  p["cells_per_piece"] = K;
  if (!profile.jerk_limited()) {
    p["b"] = profile.b();
  } else {
    Json half = Json::array(), shapes = Json::array();
    for (int i = 0; i < m; ++i) {
      std::vector<double> values;
      for (int h = 0; h <= 2 * K; ++h) values.push_back(profile.half_b(i, h));
      half.push_back(values);
      Json row = Json::array();
      for (int k = 0; k < K; ++k) row.push_back(ToString(profile.shape(i, k)));
      shapes.push_back(row);
    }
    p["half_b"] = half;
    p["shapes"] = shapes;
    if (!profile.cell_edges().empty()) p["cell_edges"] = profile.cell_edges();
  }
  j["profile"] = p;
  return j.dump(indent) + "\n";
}

void WriteTrajectoryJson(const Trajectory& trajectory, const std::string& path) {
  WriteTextFile(path, TrajectoryToJson(trajectory));
}

Trajectory ParseTrajectoryJson(const std::string& json_text, const std::string& context) {
  const nlohmann::json j = internal::ParseJsonText(json_text, context);
  internal::RequireObject(j, context);
  internal::RejectUnknownKeys(j, {"format", "version", "frame", "duration", "curve", "profile"}, context);
  for (const char* key : {"format", "version", "curve", "profile"}) {
    if (!j.contains(key)) throw std::invalid_argument(context + "." + key + ": missing");
  }
  if (!j["format"].is_string() || j["format"].get<std::string>() != kFormatName) {
    throw std::invalid_argument(context + ".format: expected \"" + std::string(kFormatName) + "\", got " +
                                j["format"].dump());
  }
  const long long version = internal::IntegerInRange(j["version"], context + ".version", 1, 1000000);
  if (version != kFormatVersion) {
    throw std::invalid_argument(context + ".version: " + std::to_string(version) +
                                " is not supported (this build reads " + std::to_string(kFormatVersion) + ")");
  }
  if (j.contains("frame") && (!j["frame"].is_string() || j["frame"].get<std::string>() != "ENU")) {
    throw std::invalid_argument(context + ".frame: expected \"ENU\", got " + j["frame"].dump());
  }
  PiecewiseCurve curve = internal::CurveFromJson(j["curve"], context + ".curve").curve;
  const nlohmann::json& p = j["profile"];
  const std::string where = context + ".profile";
  internal::RequireObject(p, where);
  internal::RejectUnknownKeys(p, {"cells_per_piece", "b", "half_b", "shapes", "cell_edges"}, where);
  if (!p.contains("cells_per_piece")) throw std::invalid_argument(where + ".cells_per_piece: missing");
  const int K =
      static_cast<int>(internal::IntegerInRange(p["cells_per_piece"], where + ".cells_per_piece", 1, 100000000));
  const size_t m = static_cast<size_t>(curve.num_pieces());
  TemporalProfile profile;
  try {
    if (p.contains("b")) {
      if (p.contains("half_b") || p.contains("shapes") || p.contains("cell_edges")) {
        throw std::invalid_argument(where + ": either \"b\" (linear cells) or \"half_b\" and \"shapes\", not both");
      }
      profile = TemporalProfile(Rows(p["b"], where + ".b", m, K + 1));
    } else {
      if (!p.contains("half_b")) throw std::invalid_argument(where + ": missing \"b\" or \"half_b\"");
      if (!p.contains("shapes")) throw std::invalid_argument(where + ".shapes: missing");
      auto half = Rows(p["half_b"], where + ".half_b", m, 2 * K + 1);
      const nlohmann::json& s = p["shapes"];
      if (!s.is_array() || s.size() != m)
        throw std::invalid_argument(where + ".shapes: expected an array of " + std::to_string(m) + " arrays");
      std::vector<std::vector<CellShape>> shapes(m);
      for (size_t i = 0; i < m; ++i) {
        const std::string row = where + ".shapes[" + std::to_string(i) + "]";
        if (!s[i].is_array() || s[i].size() != static_cast<size_t>(K)) {
          throw std::invalid_argument(row + ": expected " + std::to_string(K) + " shapes");
        }
        for (size_t k = 0; k < s[i].size(); ++k) {
          shapes[i].push_back(internal::EnumField(s[i][k], row + "[" + std::to_string(k) + "]", kCellShapes));
        }
      }
      std::vector<std::vector<double>> edges;
      if (p.contains("cell_edges")) edges = Rows(p["cell_edges"], where + ".cell_edges", m, K + 1);
      profile = TemporalProfile::JerkLimited(std::move(half), std::move(shapes), std::move(edges));
    }
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    if (what.rfind(context, 0) == 0) throw;
    throw std::invalid_argument(where + ": " + what);
  }
  if (profile.num_pieces() != curve.num_pieces()) {
    throw std::invalid_argument(where + ": " + std::to_string(profile.num_pieces()) + " pieces, the curve has " +
                                std::to_string(curve.num_pieces()));
  }
  Trajectory trajectory(std::move(curve), std::move(profile));
  if (j.contains("duration")) {
    const double given = internal::FiniteNumber(j["duration"], context + ".duration");
    if (!(std::abs(given - trajectory.duration()) <= 1e-9 * trajectory.duration())) {
      char buffer[160];
      std::snprintf(buffer, sizeof(buffer),
                    ".duration: %.17g s, but the profile takes %.17g s (an edited or damaged file?)", given,
                    trajectory.duration());
      throw std::invalid_argument(context + buffer);
    }
  }
  return trajectory;
}

Trajectory ReadTrajectoryJson(const std::string& path) { return ParseTrajectoryJson(ReadTextFile(path), path); }

HeadedSamples SampleWithYaw(const Trajectory& trajectory, double rate_hz, const YawOptions& yaw) {
  yaw.Validate();
  HeadedSamples out;
  out.states = trajectory.Sample(rate_hz);
  std::vector<double> times;
  times.reserve(out.states.size());
  for (const TrajectoryState& s : out.states) times.push_back(s.t);
  out.yaw = PlanYaw(trajectory, times, yaw);
  return out;
}

std::string ExportCsv(const HeadedSamples& samples) {
  std::string out = "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,yaw,yaw_rate\n";
  out.reserve(out.size() + samples.states.size() * 15 * 24);
  for (size_t i = 0; i < samples.states.size(); ++i) {
    const TrajectoryState& s = samples.states[i];
    const double values[15] = {s.t,
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
                               s.jerk.z(),
                               samples.yaw.yaw[i],
                               samples.yaw.rate[i]};
    for (int c = 0; c < 15; ++c) AppendNumber(&out, values[c], c == 14 ? '\n' : ',');
  }
  return out;
}

std::string ExportPx4Csv(const HeadedSamples& samples) {
  std::string out = "timestamp_us,x,y,z,vx,vy,vz,ax,ay,az,yaw,yawspeed\n";
  out.reserve(out.size() + samples.states.size() * 12 * 24);
  char buffer[32];
  for (size_t i = 0; i < samples.states.size(); ++i) {
    const TrajectoryState& s = samples.states[i];
    std::snprintf(buffer, sizeof(buffer), "%lld,", static_cast<long long>(std::llround(s.t * 1e6)));
    out += buffer;
    // NED from ENU: north = y, east = x, down = -z; yaw from north, clockwise.
    const double values[11] = {s.position.y(),           s.position.x(),
                               -s.position.z(),          s.velocity.y(),
                               s.velocity.x(),           -s.velocity.z(),
                               s.acceleration.y(),       s.acceleration.x(),
                               -s.acceleration.z(),      kPi / 2.0 - samples.yaw.yaw[i],
                               0.0 - samples.yaw.rate[i]};  // (0 - 0 is +0, not -0)
    for (int c = 0; c < 11; ++c) AppendNumber(&out, values[c], c == 10 ? '\n' : ',');
  }
  return out;
}

std::string ExportPolynomialJson(const Trajectory& trajectory, const PolynomialFitOptions& fit, const YawOptions& yaw) {
  yaw.Validate();
  const PolynomialSegments segments = FitPolynomialSegments(trajectory, fit);
  std::vector<double> edges;
  for (const PolynomialSegment& s : segments.segments) edges.push_back(s.start);
  edges.push_back(trajectory.duration());
  // Segments start where the previous one ends; a rounding tie keeps the times increasing.
  for (size_t i = 1; i < edges.size(); ++i) edges[i] = std::max(edges[i], std::nextafter(edges[i - 1], INFINITY));
  const YawProfile headings = PlanYaw(trajectory, edges, yaw);
  Json j;
  j["frame"] = "ENU";
  j["degree"] = segments.degree;
  j["duration"] = trajectory.duration();
  Json list = Json::array();
  for (size_t i = 0; i < segments.segments.size(); ++i) {
    const PolynomialSegment& s = segments.segments[i];
    Json item;
    item["start"] = s.start;
    item["duration"] = s.duration;
    Json axes = Json::array();
    for (int a = 0; a < 3; ++a) {
      std::vector<double> row(s.coefficients.cols());
      for (int c = 0; c < s.coefficients.cols(); ++c) row[static_cast<size_t>(c)] = s.coefficients(a, c);
      axes.push_back(row);
    }
    item["coefficients"] = axes;
    item["exact"] = s.exact;
    item["yaw"] = {headings.yaw[i], headings.rate[i]};
    list.push_back(item);
  }
  j["segments"] = list;
  j["max_error"] = {{"position", segments.max_position_error},
                    {"velocity", segments.max_velocity_error},
                    {"acceleration", segments.max_acceleration_error},
                    {"check_spacing", segments.largest_checked_gap}};
  j["tolerance"] = {{"position", fit.max_position_error},
                    {"velocity", fit.max_velocity_error},
                    {"acceleration", fit.max_acceleration_error}};
  j["yaw"] = {{"mode", ToString(yaw.mode)}, {"max_rate", yaw.max_rate}};
  return j.dump(2) + "\n";
}

const char* ToString(ExportFormat format) {
  switch (format) {
    case ExportFormat::kCsv:
      return "csv";
    case ExportFormat::kPolynomial:
      return "polynomial";
    case ExportFormat::kPx4:
      return "px4";
    case ExportFormat::kRosbag:
      return "rosbag";
  }
  return "unknown";
}

bool FromString(const std::string& text, ExportFormat* format) { return EnumFromString(text, kExportFormats, format); }

void WriteExport(const Trajectory& trajectory, ExportFormat format, const std::string& path,
                 const ExportOptions& options) {
  if (options.map != nullptr && format != ExportFormat::kRosbag) {
    throw std::invalid_argument(std::string("export: only the rosbag format draws a map (format ") + ToString(format) +
                                ")");
  }
  if (format == ExportFormat::kPolynomial) {
    WriteTextFile(path, ExportPolynomialJson(trajectory, options.fit, options.yaw));
    return;
  }
  trajectory.CheckSampleRate(options.rate_hz);
  const HeadedSamples samples = SampleWithYaw(trajectory, options.rate_hz, options.yaw);
  if (format == ExportFormat::kCsv) {
    WriteTextFile(path, ExportCsv(samples));
  } else if (format == ExportFormat::kPx4) {
    WriteTextFile(path, ExportPx4Csv(samples));
  } else {
    WriteRosbag(RosbagContentJson(samples, options.map, options.voxel_radius), path);
  }
}

std::string RosbagContentJson(const HeadedSamples& samples, const OccupancyMap* map, double voxel_radius) {
  if (samples.states.empty()) throw std::invalid_argument("rosbag: no samples");
  Json j;
  j["frame"] = "map";
  Json rows = Json::array();
  double fastest = 0.0;
  for (size_t i = 0; i < samples.states.size(); ++i) {
    const TrajectoryState& s = samples.states[i];
    rows.push_back({s.t, s.position.x(), s.position.y(), s.position.z(), s.velocity.x(), s.velocity.y(), s.velocity.z(),
                    s.acceleration.x(), s.acceleration.y(), s.acceleration.z(), samples.yaw.yaw[i],
                    samples.yaw.rate[i]});
    fastest = std::max(fastest, s.velocity.norm());
  }
  j["columns"] = {"t", "x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "yaw", "yaw_rate"};
  j["samples"] = rows;
  j["max_speed"] = fastest;
  const TrajectoryState& first = samples.states.front();
  const TrajectoryState& last = samples.states.back();
  j["start"] = {first.position.x(), first.position.y(), first.position.z()};
  j["goal"] = {last.position.x(), last.position.y(), last.position.z()};
  if (map != nullptr) {
    std::vector<Eigen::Vector3d> path;
    for (const TrajectoryState& s : samples.states) path.push_back(s.position);
    Json centers = Json::array();
    for (const Eigen::Vector3d& c : OccupiedVoxelsNear(*map, path, voxel_radius, kMaxMarkerVoxels)) {
      centers.push_back({c.x(), c.y(), c.z()});
    }
    j["voxels"] = {{"size", map->resolution()}, {"centers", centers}};
  }
  return j.dump() + "\n";
}

}  // namespace timeopt

namespace timeopt {

void WriteRosbag(const std::string& content, const std::string& bag_path) {
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("TIMEOPT_ROSBAG_WRITER")) candidates.emplace_back(env);
  candidates.emplace_back(TIMEOPT_SOURCE_ROSBAG_WRITER);
  candidates.emplace_back(TIMEOPT_INSTALLED_ROSBAG_WRITER);
  std::error_code error;
  fs::path script;
  std::string tried;
  for (const fs::path& path : candidates) {
    if (fs::is_regular_file(path, error)) {
      script = path;
      break;
    }
    tried += (tried.empty() ? "" : ", ") + path.string();
  }
  if (script.empty())
    throw FileError("rosbag: the bag writer timeopt_rosbag.py was not found (looked in " + tried + ")");
  const char* python = "/usr/bin/python3";
  if (access(python, X_OK) != 0) {
    throw FileError("rosbag: the bag is written by Debian's python3 with python3-rosbag; /usr/bin/python3 is missing");
  }
  // The content and the writer's messages go through two temporary files.
  std::string input = (fs::temp_directory_path() / "timeopt-rosbag-XXXXXX").string();
  std::string messages;
  const int fd = mkstemp(input.data());
  if (fd < 0) throw FileError("rosbag: cannot create a temporary file in " + fs::temp_directory_path().string());
  messages = input + ".stderr";
  const auto cleanup = [&] {
    fs::remove(input, error);
    fs::remove(messages, error);
  };
  const bool written = write(fd, content.data(), content.size()) == static_cast<ssize_t>(content.size());
  close(fd);
  if (!written) {
    cleanup();
    throw FileError("rosbag: cannot write the temporary file " + input);
  }
  const std::string script_text = script.string();  // (no allocation in the child)
  const pid_t child = fork();
  if (child < 0) {
    cleanup();
    throw FileError("rosbag: cannot start " + std::string(python));
  }
  if (child == 0) {
    const int err = open(messages.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (err >= 0) {
      dup2(err, 2);
      dup2(err, 1);
    }
    execl(python, python, script_text.c_str(), input.c_str(), bag_path.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  std::string said;
  try {
    said = ReadTextFile(messages);
  } catch (const FileError&) {
  }
  cleanup();
  while (!said.empty() && (said.back() == '\n' || said.back() == '\r')) said.pop_back();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string last_line =
        said.substr(said.find_last_of('\n') == std::string::npos ? 0 : said.find_last_of('\n') + 1);
    throw FileError("rosbag: " +
                    (last_line.empty() ? std::string("the writer failed (") + script.string() + ")" : last_line));
  }
}

}  // namespace timeopt
