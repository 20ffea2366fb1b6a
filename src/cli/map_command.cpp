// `timeopt map info MAP`, `timeopt map generate KIND ... -o MAP.bt`,
// `timeopt map slice MAP --z HEIGHT -o SLICE.png`

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/map/esdf.h"
#include "timeopt/viz/esdf_slice.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt::cli {
namespace {

// The bounds' volume less the known volumes; never below 0 (the difference of sums rounds, e.g.
// -3.5e-12 m^3 on a map with every voxel known).
double UnknownVolume(const OccupancyMap& map, const VoxelBox& box) {
  const double r = map.resolution();
  return std::max(0.0, box.num_voxels() * r * r * r - map.OccupiedVolume() - map.FreeVolume());
}

UnknownSpace ParseUnknown(const std::string& text) {
  UnknownSpace unknown = UnknownSpace::kFree;
  if (!FromString(text, &unknown)) {
    throw std::invalid_argument("--unknown: expected " + EnumChoices(kUnknownSpaces));
  }
  return unknown;
}

void AddUnknownOption(CLI::App* sub, std::string* value) {
  sub->add_option("--unknown", *value, "Unobserved voxels count as free or occupied")
      ->check(CLI::IsMember(EnumNames(kUnknownSpaces)))
      ->capture_default_str();
}

Eigen::AlignedBox3d BoundsFromVector(const std::vector<double>& v) {
  if (v.size() != 6) {
    throw std::invalid_argument("--bounds expects 6 numbers (xmin ymin zmin xmax ymax zmax), got " +
                                std::to_string(v.size()));
  }
  return Eigen::AlignedBox3d(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
}

std::string FormatBox(const Eigen::AlignedBox3d& box) {
  std::ostringstream out;
  out << std::setprecision(6) << "[" << box.min().x() << ", " << box.max().x() << "] x [" << box.min().y() << ", "
      << box.max().y() << "] x [" << box.min().z() << ", " << box.max().z() << "] m";
  return out.str();
}

// ---- info ----
struct InfoArgs {
  std::string map;
  std::string unknown = ToString(UnknownSpace::kFree);
  bool json = false;
};

int RunInfo(const InfoArgs& args) {
  const OccupancyMap map = OccupancyMap::Load(args.map, ParseUnknown(args.unknown));
  if (args.json) {
    nlohmann::ordered_json j = {
        {"map", args.map}, {"tree_type", map.source_type()}, {"resolution", map.resolution()}, {"empty", map.empty()}};
    if (!map.empty()) {
      const VoxelBox box = map.KnownBox();
      const Eigen::AlignedBox3d bounds = map.Bounds();
      j["bounds"] = {{"min", {bounds.min().x(), bounds.min().y(), bounds.min().z()}},
                     {"max", {bounds.max().x(), bounds.max().y(), bounds.max().z()}}};
      j["voxels"] = {box.size.x(), box.size.y(), box.size.z()};
      j["nodes"] = map.NumNodes();
      j["leaves"] = map.NumLeaves();
      j["occupied_volume"] = map.OccupiedVolume();
      j["free_volume"] = map.FreeVolume();
      j["unknown_volume"] = UnknownVolume(map, box);
      j["dense_esdf_mib"] = box.num_voxels() * 4.0 / (1 << 20);
    }
    std::cout << j.dump(2) << "\n";
    return kExitOk;
  }
  std::cout << "map: " << args.map << "\n"
            << "tree type: " << map.source_type() << "\n"
            << "resolution: " << map.resolution() << " m\n";
  if (map.empty()) {
    std::cout << "empty: no known voxel\n";
    return kExitOk;
  }
  const VoxelBox box = map.KnownBox();
  const double r = map.resolution();
  std::cout << "bounds: " << FormatBox(map.Bounds()) << "\n"
            << "size: " << box.size.x() * r << " x " << box.size.y() * r << " x " << box.size.z() * r << " m ("
            << box.size.x() << " x " << box.size.y() << " x " << box.size.z() << " = " << box.num_voxels()
            << " voxels)\n"
            << "tree: " << map.NumNodes() << " nodes, " << map.NumLeaves() << " leaves\n"
            << std::setprecision(6) << "occupied volume: " << map.OccupiedVolume() << " m^3\n"
            << "free volume: " << map.FreeVolume() << " m^3\n"
            << "unknown volume in bounds: " << UnknownVolume(map, box) << " m^3\n"
            << "dense ESDF over bounds: " << box.num_voxels() * 4.0 / (1 << 20) << " MiB\n";
  return kExitOk;
}

// ---- generate ----
struct GenerateArgs {
  std::string output;
  std::vector<double> bounds;
  ForestOptions forest;
  SharpTurnOptions sharp_turn;
  RandomBoxesOptions boxes;
};

int WriteGenerated(const OccupancyGrid& grid, const std::string& kind, const std::string& output) {
  const auto start = std::chrono::steady_clock::now();
  const OccupancyMap map = OccupancyMap::FromGrid(grid);
  map.Save(output);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "generated: " << kind << "\n"
            << "bounds: " << FormatBox(grid.box.Metric(grid.resolution)) << "\n"
            << "resolution: " << grid.resolution << " m\n"
            << "voxels: " << grid.box.num_voxels() << " (" << grid.CountOccupied() << " occupied)\n"
            << "tree: " << map.NumNodes() << " nodes (built and written in " << std::setprecision(3) << seconds
            << " s)\n"
            << "written: " << output << "\n";
  return kExitOk;
}

void CheckOutputName(const std::string& output) {
  if (output.size() < 3 || output.substr(output.size() - 3) != ".bt") {
    throw std::invalid_argument("output '" + output + "' must end in .bt (OctoMap binary file)");
  }
}

void AddBoundsOption(CLI::App* sub, GenerateArgs* args, const std::string& defaults) {
  sub->add_option("--bounds", args->bounds, "xmin ymin zmin xmax ymax zmax in metres (default " + defaults + ")")
      ->expected(6);
}

void RegisterGenerate(CLI::App* map_app, Runner& run) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* gen = map_app->add_subcommand("generate", "Generate a synthetic map (.bt)");
  gen->require_subcommand(1);

  CLI::App* forest = gen->add_subcommand("forest", "Random forest of vertical cylinders");
  AddBoundsOption(forest, args.get(), "0 0 0 10 10 3");
  forest->add_option("--resolution", args->forest.resolution, "Voxel edge, m")->capture_default_str();
  forest->add_option("--density", args->forest.density, "Trees per m^2")->capture_default_str();
  forest->add_option("--radius-min", args->forest.min_radius, "Smallest radius, m")->capture_default_str();
  forest->add_option("--radius-max", args->forest.max_radius, "Largest radius, m")->capture_default_str();
  forest->add_option("--seed", args->forest.seed, "Random seed")->capture_default_str();
  forest->add_option("-o,--output", args->output, "Output .bt file")->required();
  forest->callback([args, &run] {
    run = [args] {
      CheckOutputName(args->output);
      ForestOptions options = args->forest;
      if (!args->bounds.empty()) options.bounds = BoundsFromVector(args->bounds);
      return WriteGenerated(GenerateForest(options), "forest", args->output);
    };
  });

  CLI::App* turn = gen->add_subcommand("sharp-turn", "Narrow corridor with a near-reverse turn (paper Sect. I)");
  turn->add_option("--resolution", args->sharp_turn.resolution, "Voxel edge, m")->capture_default_str();
  turn->add_option("--width", args->sharp_turn.corridor_width, "Corridor width, m")->capture_default_str();
  turn->add_option("--leg-length", args->sharp_turn.leg_length, "Length of each leg, m")->capture_default_str();
  turn->add_option("--turn-angle", args->sharp_turn.turn_angle_deg,
                   "Heading change at the turn, degrees (180: full reversal)")
      ->capture_default_str();
  turn->add_option("--height", args->sharp_turn.height, "Free corridor height, m")->capture_default_str();
  turn->add_option("--wall", args->sharp_turn.wall, "Solid margin around the corridor, m")->capture_default_str();
  turn->add_option("-o,--output", args->output, "Output .bt file")->required();
  turn->callback([args, &run] {
    run = [args] {
      CheckOutputName(args->output);
      return WriteGenerated(GenerateSharpTurn(args->sharp_turn), "sharp-turn", args->output);
    };
  });

  CLI::App* boxes = gen->add_subcommand("boxes", "Random axis-aligned boxes");
  AddBoundsOption(boxes, args.get(), "0 0 0 10 10 3");
  boxes->add_option("--resolution", args->boxes.resolution, "Voxel edge, m")->capture_default_str();
  boxes->add_option("--count", args->boxes.count, "Number of boxes")->capture_default_str();
  boxes->add_option("--size-min", args->boxes.min_size, "Smallest edge, m")->capture_default_str();
  boxes->add_option("--size-max", args->boxes.max_size, "Largest edge, m")->capture_default_str();
  boxes->add_flag("--ground", args->boxes.ground, "Occupy the lowest voxel layer");
  boxes->add_option("--seed", args->boxes.seed, "Random seed")->capture_default_str();
  boxes->add_option("-o,--output", args->output, "Output .bt file")->required();
  boxes->callback([args, &run] {
    run = [args] {
      CheckOutputName(args->output);
      RandomBoxesOptions options = args->boxes;
      if (!args->bounds.empty()) options.bounds = BoundsFromVector(args->bounds);
      return WriteGenerated(GenerateRandomBoxes(options), "boxes", args->output);
    };
  });
}

// ---- slice ----
struct SliceArgs {
  std::string map;
  double z = 0.0;
  std::string output;
  std::string unknown = ToString(UnknownSpace::kFree);
  SliceImageOptions image;
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();
};

int RunSlice(const SliceArgs& args) {
  const OccupancyMap map = OccupancyMap::Load(args.map, ParseUnknown(args.unknown));
  const auto start = std::chrono::steady_clock::now();
  const Esdf esdf = Esdf::FromMap(map, std::nullopt, args.max_memory_mib * 1024 * 1024);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteEsdfSlicePng(esdf, args.z, args.output, args.image);
  std::cout << "esdf: " << esdf.box().size.x() << " x " << esdf.box().size.y() << " x " << esdf.box().size.z()
            << " voxels, built in " << std::setprecision(3) << seconds * 1e3 << " ms\n"
            << "slice: z = " << args.z << " m\n"
            << "written: " << args.output << "\n";
  return kExitOk;
}

}  // namespace

void RegisterMapCommand(CLI::App& app, Runner& run) {
  CLI::App* map_app = app.add_subcommand("map", "Occupancy maps: inspect, generate, ESDF slices");
  map_app->require_subcommand(1);

  auto info = std::make_shared<InfoArgs>();
  CLI::App* info_app = map_app->add_subcommand("info", "Bounds, resolution and volumes of a map");
  info_app->add_option("MAP", info->map, "OctoMap file (.bt or .ot)")->required();
  AddUnknownOption(info_app, &info->unknown);
  info_app->add_flag("--json", info->json,
                     "Print the figures as JSON (map, tree_type, resolution m, empty, bounds m, voxels, nodes, "
                     "leaves, occupied_volume / free_volume / unknown_volume m^3, dense_esdf_mib)");
  info_app->callback([info, &run] { run = [info] { return RunInfo(*info); }; });

  RegisterGenerate(map_app, run);

  auto slice = std::make_shared<SliceArgs>();
  CLI::App* slice_app = map_app->add_subcommand("slice", "PNG of the signed distance at a height, obstacles in black");
  slice_app->add_option("MAP", slice->map, "OctoMap file (.bt or .ot)")->required();
  slice_app->add_option("--z", slice->z, "Height of the slice, m")->required();
  slice_app->add_option("-o,--output", slice->output, "Output PNG file")->required();
  AddUnknownOption(slice_app, &slice->unknown);
  AddMemoryBudgetOption(slice_app, &slice->max_memory_mib);
  slice_app->add_option("--pixels-per-voxel", slice->image.pixels_per_voxel, "Image pixels per voxel edge")
      ->capture_default_str();
  slice_app
      ->add_option("--max-distance", slice->image.max_distance,
                   "Distance where the colour saturates, m (0: the slice's largest)")
      ->capture_default_str();
  slice_app->callback([slice, &run] { run = [slice] { return RunSlice(*slice); }; });
}

}  // namespace timeopt::cli
