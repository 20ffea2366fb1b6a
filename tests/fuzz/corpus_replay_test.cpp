// Replays every input of tests/fuzz/corpus/ (the fuzzers' seeds, and the reproducer of any crash
// they find) through the parser its folder names, in the normal build: each must give a result or
// a documented exception (std::invalid_argument, std::out_of_range, timeopt::FileError), so a
// fixed crash stays fixed without running the fuzzers (scripts/fuzz.sh).

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "timeopt/conic/cbf.h"
#include "timeopt/core/errors.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/planner_io.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(FuzzCorpus, EveryInputEndsInAResultOrADocumentedException) {
  const fs::path root = fs::path(TIMEOPT_SOURCE_DIR) / "tests" / "fuzz" / "corpus";
  const std::map<std::string, std::function<void(const fs::path&)>> parsers = {
      {"problem_json", [](const fs::path& p) { ParseTemporalProblemJson(Slurp(p), "problem").Validate(); }},
      {"curve_json", [](const fs::path& p) { ParseCurveJson(Slurp(p)); }},
      {"planner_config", [](const fs::path& p) { ParsePlannerConfigJson(Slurp(p), PlannerOptions()); }},
      {"waypoints_csv", [](const fs::path& p) { MergeCoincidentWaypoints(ParseWaypointsCsv(Slurp(p))); }},
      {"samples_csv", [](const fs::path& p) { ParseSamplesCsv(Slurp(p), "samples"); }},
      {"cbf",
       [](const fs::path& p) {
         std::istringstream in(Slurp(p));
         conic::ReadCbf(in);
       }},
      {"octomap", [](const fs::path& p) { OccupancyMap::Load(p.string()).Bounds(); }},
  };
  int inputs = 0;
  for (const auto& [folder, parse] : parsers) {
    ASSERT_TRUE(fs::is_directory(root / folder)) << (root / folder) << " is missing";
    for (const fs::directory_entry& entry : fs::directory_iterator(root / folder)) {
      SCOPED_TRACE(entry.path().string());
      ++inputs;
      try {
        parse(entry.path());
      } catch (const std::invalid_argument&) {
      } catch (const std::out_of_range&) {
      } catch (const FileError&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << "undocumented exception: " << e.what();
      }
    }
  }
  // Every folder has at least one seed.
  EXPECT_GE(inputs, static_cast<int>(parsers.size()));
}

}  // namespace
}  // namespace timeopt
