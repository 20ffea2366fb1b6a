// libFuzzer targets, one per input path the library reads. Each takes the bytes as the file's
// content and must end in a result or a documented exception (std::invalid_argument,
// std::out_of_range or timeopt::FileError), never a crash, a sanitizer report or a hang. Which
// target this translation unit becomes is chosen by TIMEOPT_FUZZ_TARGET (see tests/fuzz/CMakeLists).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "timeopt/conic/cbf.h"
#include "timeopt/core/errors.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/planner_io.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/map/occupancy_map.h"

namespace {

void Run(const std::string& text) {
  using namespace timeopt;
#if TIMEOPT_FUZZ_TARGET == 1
  ParseTemporalProblemJson(text, "problem").Validate();
#elif TIMEOPT_FUZZ_TARGET == 2
  (void)ParseCurveJson(text);
#elif TIMEOPT_FUZZ_TARGET == 3
  (void)ParsePlannerConfigJson(text, PlannerOptions(), "config");
#elif TIMEOPT_FUZZ_TARGET == 4
  // As `curve` and `waypoints` read them: coincident waypoints merged.
  (void)MergeCoincidentWaypoints(ParseWaypointsCsv(text));
#elif TIMEOPT_FUZZ_TARGET == 5
  (void)ParseSamplesCsv(text, "samples");
#elif TIMEOPT_FUZZ_TARGET == 6
  std::istringstream in(text);
  (void)conic::ReadCbf(in);
#elif TIMEOPT_FUZZ_TARGET == 7
  // OctoMap reads files only: the bytes go to a per-process file (libFuzzer runs inputs one at a
  // time in a process), and the map is queried a little so that a bad tree is walked.
  static const std::string path = "/tmp/timeopt_fuzz_map_" + std::to_string(getpid()) + ".bt";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  const OccupancyMap map = OccupancyMap::Load(path);
  (void)map.Bounds();
  (void)map.State(Eigen::Vector3d::Zero());
#else
#error "TIMEOPT_FUZZ_TARGET must be 1..7"
#endif
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    Run(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const std::invalid_argument&) {
  } catch (const std::out_of_range&) {
  } catch (const timeopt::FileError&) {
  }
  return 0;
}
