#include "timeopt/map/occupancy_map.h"

// OctoMap's debug macros print to stderr in builds without NDEBUG; the library never prints, so
// they are silenced for the OctoMap templates instantiated here.
#include <octomap/octomap_types.h>
#undef OCTOMAP_DEBUG
#define OCTOMAP_DEBUG(...) (void)0
#undef OCTOMAP_DEBUG_STR
#define OCTOMAP_DEBUG_STR(...) (void)0

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "timeopt/core/enum_strings.h"
#include "timeopt/core/errors.h"

namespace timeopt {
namespace {

// OctoMap's tree depth and key offset: key = index + 32768, 16 levels below the root.
constexpr int kTreeDepth = 16;
constexpr int kKeyOffset = 32768;
// The resolutions a map may have, metres: beyond them a map's extent (65,536 voxels a side) or its
// volumes (map info) leave the range of a double, or a voxel is below any sensor's resolution.
constexpr double kMinResolution = 1e-6;
constexpr double kMaxResolution = 1e6;
bool ValidResolution(double r) { return r >= kMinResolution && r <= kMaxResolution; }

constexpr const char* kBinaryFirstLine = "# Octomap OcTree binary file";
constexpr const char* kFullFirstLine = "# Octomap OcTree file";

struct FileHeader {
  bool binary = false;
  std::string id;
  int64_t size = -1;
  double resolution = 0.0;
  size_t data_offset = 0;  // first byte after the "data" line
};

std::string StripCarriageReturn(std::string line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

// Parses the text header of a .bt / .ot file as OctoMap writes it (first line, comment lines,
// "id", "size", "res", then "data").
FileHeader ParseHeader(const std::string& content, const std::string& path) {
  FileHeader header;
  size_t pos = 0;
  auto next_line = [&](std::string* line) {
    if (pos >= content.size()) return false;
    const size_t end = content.find('\n', pos);
    if (end == std::string::npos) {
      *line = content.substr(pos);
      pos = content.size();
    } else {
      *line = content.substr(pos, end - pos);
      pos = end + 1;
    }
    return true;
  };
  std::string line;
  if (!next_line(&line)) throw std::invalid_argument("map file '" + path + "' is empty");
  line = StripCarriageReturn(line);
  if (line == kBinaryFirstLine) {
    header.binary = true;
  } else if (line == kFullFirstLine) {
    header.binary = false;
  } else {
    throw std::invalid_argument("'" + path + "' is not an OctoMap file (first line is not '" + kBinaryFirstLine +
                                "' or '" + kFullFirstLine + "')");
  }
  bool have_data = false;
  while (next_line(&line)) {
    line = StripCarriageReturn(line);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream tokens(line);
    std::string key;
    tokens >> key;
    if (key == "data") {
      have_data = true;
      break;
    }
    if (key == "id") {
      tokens >> header.id;
    } else if (key == "size") {
      tokens >> header.size;
    } else if (key == "res") {
      tokens >> header.resolution;
    } else {
      throw std::invalid_argument("'" + path + "': unknown header line '" + line + "'");
    }
    if (tokens.fail()) throw std::invalid_argument("'" + path + "': bad header line '" + line + "'");
  }
  if (!have_data) throw std::invalid_argument("'" + path + "': header has no 'data' line");
  if (header.id.empty()) throw std::invalid_argument("'" + path + "': header has no 'id'");
  if (header.size < 0) throw std::invalid_argument("'" + path + "': header has no valid 'size'");
  if (!(header.resolution > 0.0) || !std::isfinite(header.resolution)) {
    throw std::invalid_argument("'" + path + "': header has no positive 'res'");
  }
  if (!ValidResolution(header.resolution)) {
    std::ostringstream message;
    message << "'" << path << "': resolution " << header.resolution << " m is outside [1e-6, 1e6] m";
    throw std::invalid_argument(message.str());
  }
  header.data_offset = pos;
  return header;
}

// Walks a node stream without building anything, checking that it is complete, that no node is
// deeper than the tree depth and (by the returned count) how many nodes it holds. OctoMap's own
// readers trust the stream and recurse without bound on corrupt data.
class StreamChecker {
 public:
  StreamChecker(const std::string& content, size_t offset, size_t node_bytes)
      : content_(content), pos_(offset), node_bytes_(node_bytes) {}

  // .bt: per inner node two bytes, 2 bits per child i at bit 2 (i % 4) of byte i / 4: value 1 a
  // free leaf, 2 an occupied leaf, 3 an inner node, 0 no child.
  bool CheckBinaryNode(int depth) {
    if (pos_ + 2 > content_.size()) return Fail("data ends early (truncated file)");
    const auto low = static_cast<unsigned char>(content_[pos_]);
    const auto high = static_cast<unsigned char>(content_[pos_ + 1]);
    pos_ += 2;
    int inner_children = 0;
    for (int child = 0; child < 8; ++child) {
      const unsigned bits = ((child < 4 ? low : high) >> (2 * (child % 4))) & 3u;
      if (bits == 0) continue;
      ++count_;
      if (bits == 3) ++inner_children;
    }
    if (inner_children > 0 && depth + 1 >= kTreeDepth) {
      return Fail("node deeper than the tree depth 16 (corrupt data)");
    }
    for (int i = 0; i < inner_children; ++i) {
      if (!CheckBinaryNode(depth + 1)) return false;
    }
    return true;
  }

  // .ot: per node its data (node_bytes_), then one byte with a bit per existing child.
  bool CheckFullNode(int depth) {
    if (pos_ + node_bytes_ + 1 > content_.size()) return Fail("data ends early (truncated file)");
    float value;
    std::memcpy(&value, content_.data() + pos_, sizeof(float));
    if (!std::isfinite(value)) return Fail("node with a non-finite occupancy value");
    pos_ += node_bytes_;
    const auto children = static_cast<unsigned char>(content_[pos_]);
    pos_ += 1;
    ++count_;
    if (children != 0 && depth >= kTreeDepth) {
      return Fail("node deeper than the tree depth 16 (corrupt data)");
    }
    for (int child = 0; child < 8; ++child) {
      if ((children >> child) & 1u) {
        if (!CheckFullNode(depth + 1)) return false;
      }
    }
    return true;
  }

  int64_t count() const { return count_; }
  size_t position() const { return pos_; }
  const std::string& error() const { return error_; }
  void set_count(int64_t count) { count_ = count; }

 private:
  bool Fail(const std::string& message) {
    error_ = message;
    return false;
  }

  const std::string& content_;
  size_t pos_;
  size_t node_bytes_;
  int64_t count_ = 0;
  std::string error_;
};

std::string ReadWholeFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FileError("map file '" + path + "' is a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw FileError("cannot open map file '" + path + "'");
  std::string content((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) throw FileError("cannot read map file '" + path + "'");
  return content;
}

// The shortest decimal text that reads back as exactly `value` ("0.1", not "0.10000000000000001").
std::string ShortestText(double value) {
  for (int digits = 6; digits <= 17; ++digits) {
    std::ostringstream text;
    text << std::setprecision(digits) << value;
    if (std::stod(text.str()) == value) return text.str();
  }
  std::ostringstream text;
  text << std::setprecision(17) << value;
  return text.str();
}

Eigen::Vector3i IndexFromKey(const octomap::OcTreeKey& key) {
  return Eigen::Vector3i(key[0] - kKeyOffset, key[1] - kKeyOffset, key[2] - kKeyOffset);
}

}  // namespace

const char* ToString(UnknownSpace unknown) {
  switch (unknown) {
    case UnknownSpace::kFree:
      return "free";
    case UnknownSpace::kOccupied:
      return "occupied";
  }
  return "unknown";
}

bool FromString(const std::string& text, UnknownSpace* unknown) {
  return EnumFromString(text, kUnknownSpaces, unknown);
}

struct OccupancyMap::Impl {
  explicit Impl(double resolution) : tree(resolution) {}
  Impl(const Impl& other) : tree(other.tree) {}
  octomap::OcTree tree;
};

OccupancyMap::OccupancyMap(double resolution, UnknownSpace unknown) : unknown_(unknown) {
  if (!ValidResolution(resolution)) {
    std::ostringstream message;
    message << "map resolution must be in [1e-6, 1e6] m, got " << resolution;
    throw std::invalid_argument(message.str());
  }
  impl_ = std::make_unique<Impl>(resolution);
}

OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl, UnknownSpace unknown, std::string source_type)
    : impl_(std::move(impl)), unknown_(unknown), source_type_(std::move(source_type)) {}

OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

OccupancyMap::OccupancyMap(const OccupancyMap& other)
    : impl_(std::make_unique<Impl>(*other.impl_)), unknown_(other.unknown_), source_type_(other.source_type_) {}

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) *this = OccupancyMap(other);
  return *this;
}

OccupancyMap OccupancyMap::Load(const std::string& path, UnknownSpace unknown) {
  const std::string content = ReadWholeFile(path);
  const FileHeader header = ParseHeader(content, path);
  auto impl = std::make_unique<Impl>(header.resolution);
  std::string source_type = "OcTree";

  if (header.binary) {
    // Every occupancy tree type writes the same binary stream; only the bits are read.
    StreamChecker checker(content, header.data_offset, 0);
    if (header.size > 0) {
      checker.set_count(1);  // the root
      if (!checker.CheckBinaryNode(0)) {
        throw std::invalid_argument("'" + path + "': " + checker.error());
      }
    }
    if (checker.count() != header.size) {
      throw std::invalid_argument("'" + path + "': header says " + std::to_string(header.size) +
                                  " nodes, the data holds " + std::to_string(checker.count()));
    }
    if (header.size > 0) {
      std::istringstream stream(content);
      stream.seekg(static_cast<std::streamoff>(header.data_offset));
      impl->tree.readBinaryData(stream);
    }
    if (header.id != "OcTree") source_type = header.id;
  } else {
    size_t node_bytes = 0;
    if (header.id == "OcTree") {
      node_bytes = sizeof(float);
    } else if (header.id == "ColorOcTree") {
      node_bytes = sizeof(float) + sizeof(octomap::ColorOcTreeNode::Color);
    } else {
      throw std::invalid_argument("'" + path + "': unsupported tree type '" + header.id +
                                  "' (OcTree and ColorOcTree are supported)");
    }
    StreamChecker checker(content, header.data_offset, node_bytes);
    if (header.size > 0 && !checker.CheckFullNode(0)) {
      throw std::invalid_argument("'" + path + "': " + checker.error());
    }
    if (checker.count() != header.size) {
      throw std::invalid_argument("'" + path + "': header says " + std::to_string(header.size) +
                                  " nodes, the data holds " + std::to_string(checker.count()));
    }
    if (header.size > 0) {
      std::istringstream stream(content);
      stream.seekg(static_cast<std::streamoff>(header.data_offset));
      if (header.id == "OcTree") {
        impl->tree.readData(stream);
      } else {
        octomap::ColorOcTree color_tree(header.resolution);
        color_tree.readData(stream);
        // Occupancy only: through OctoMap's binary stream (same resolution, thresholded).
        std::stringstream bits;
        color_tree.writeBinaryData(bits);
        impl->tree.readBinaryData(bits);
        source_type = "ColorOcTree";
      }
    }
  }
  return OccupancyMap(std::move(impl), unknown, source_type);
}

OccupancyMap OccupancyMap::FromGrid(const OccupancyGrid& grid, UnknownSpace unknown) {
  grid.Validate();
  OccupancyMap map(grid.resolution, unknown);
  const Eigen::Vector3i lo = grid.box.min.array() + kKeyOffset;
  const Eigen::Vector3i hi = grid.box.end().array() + kKeyOffset;  // exclusive
  if ((lo.array() < 0).any() || (hi.array() > 2 * kKeyOffset).any()) {
    throw std::invalid_argument("grid box leaves the OctoMap key range");
  }
  // The pruned tree is written in OctoMap's binary node stream and read back by OctoMap (the
  // same stream a .bt file holds), which is linear in the voxels; inserting voxel by voxel with
  // setNodeValue costs a root-to-leaf walk each.
  //
  // Pyramid: level k cell c covers keys [c 2^k, (c + 1) 2^k) per axis; its state is unknown (no
  // voxel of the grid), free or occupied (every voxel the same) or mixed (an inner node).
  enum : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2, kMixed = 3 };
  struct Level {
    Eigen::Vector3i lo, size;  // cells [lo, lo + size)
    std::vector<uint8_t> state;
    uint8_t At(const Eigen::Vector3i& c) const {
      const Eigen::Vector3i local = c - lo;
      if ((local.array() < 0).any() || (local.array() >= size.array()).any()) return kUnknown;
      return state[static_cast<size_t>(local.x() + static_cast<int64_t>(size.x()) *
                                                       (local.y() + static_cast<int64_t>(size.y()) * local.z()))];
    }
  };
  std::vector<Level> levels(kTreeDepth + 1);
  levels[0].lo = lo;
  levels[0].size = hi - lo;
  levels[0].state.resize(grid.occupied.size());
  for (size_t i = 0; i < grid.occupied.size(); ++i) {
    levels[0].state[i] = grid.occupied[i] != 0 ? kOccupied : kFree;
  }
  for (int k = 1; k <= kTreeDepth; ++k) {
    const Level& below = levels[k - 1];
    Level& level = levels[k];
    level.lo = Eigen::Vector3i(below.lo.x() >> 1, below.lo.y() >> 1, below.lo.z() >> 1);
    const Eigen::Vector3i below_last = below.lo + below.size - Eigen::Vector3i::Ones();
    level.size = Eigen::Vector3i(below_last.x() >> 1, below_last.y() >> 1, below_last.z() >> 1) - level.lo +
                 Eigen::Vector3i::Ones();
    level.state.resize(static_cast<size_t>(level.size.prod()));
    size_t i = 0;
    for (int z = 0; z < level.size.z(); ++z) {
      for (int y = 0; y < level.size.y(); ++y) {
        for (int x = 0; x < level.size.x(); ++x, ++i) {
          const Eigen::Vector3i first_child = 2 * (level.lo + Eigen::Vector3i(x, y, z));
          uint8_t combined = below.At(first_child);
          for (int child = 1; child < 8 && combined != kMixed; ++child) {
            const Eigen::Vector3i offset(child & 1, (child >> 1) & 1, (child >> 2) & 1);
            if (below.At(first_child + offset) != combined) combined = kMixed;
          }
          level.state[i] = combined;
        }
      }
    }
  }
  // Pre-order stream: for each inner node its two child bytes, then its inner children.
  std::string stream;
  auto write = [&](auto&& self, int k, const Eigen::Vector3i& cell) -> void {
    uint8_t bytes[2] = {0, 0};
    uint8_t child_states[8];
    for (int child = 0; child < 8; ++child) {
      const Eigen::Vector3i offset(child & 1, (child >> 1) & 1, (child >> 2) & 1);
      child_states[child] = levels[k - 1].At(2 * cell + offset);
      bytes[child / 4] |= static_cast<uint8_t>(child_states[child] << (2 * (child % 4)));
    }
    stream.push_back(static_cast<char>(bytes[0]));
    stream.push_back(static_cast<char>(bytes[1]));
    for (int child = 0; child < 8; ++child) {
      if (child_states[child] == kMixed) {
        const Eigen::Vector3i offset(child & 1, (child >> 1) & 1, (child >> 2) & 1);
        self(self, k - 1, 2 * cell + offset);
      }
    }
  };
  write(write, kTreeDepth, Eigen::Vector3i::Zero());  // the root is always an inner node
  std::istringstream input(stream);
  map.impl_->tree.readBinaryData(input);
  return map;
}

void OccupancyMap::Save(const std::string& path) const {
  std::ofstream file(path, std::ios::binary);
  if (!file) throw FileError("cannot write map file '" + path + "'");
  // The header as OctoMap writes it (its own writer prints progress to stderr).
  file << kBinaryFirstLine << "\n"
       << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
       << "id OcTree\n"
       << "size " << impl_->tree.size() << "\n"
       << "res " << ShortestText(impl_->tree.getResolution()) << "\n"
       << "data\n";
  impl_->tree.writeBinaryData(file);
  file.close();
  if (!file) throw FileError("cannot write map file '" + path + "'");
}

double OccupancyMap::resolution() const { return impl_->tree.getResolution(); }

bool OccupancyMap::empty() const { return impl_->tree.size() == 0; }

VoxelBox OccupancyMap::KnownBox() const {
  const octomap::OcTree& tree = impl_->tree;
  if (tree.size() == 0) return VoxelBox();
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(2 * kKeyOffset);
  Eigen::Vector3i hi = Eigen::Vector3i::Constant(-1);
  bool any = false;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const Eigen::Vector3i corner = IndexFromKey(it.getIndexKey()).array() + kKeyOffset;
    const int size = 1 << (kTreeDepth - static_cast<int>(it.getDepth()));
    lo = lo.cwiseMin(corner);
    hi = hi.cwiseMax(corner + Eigen::Vector3i::Constant(size));
    any = true;
  }
  if (!any) return VoxelBox();
  VoxelBox box;
  box.min = lo.array() - kKeyOffset;
  box.size = hi - lo;
  return box;
}

Eigen::AlignedBox3d OccupancyMap::Bounds() const {
  const VoxelBox box = KnownBox();
  if (box.empty()) return Eigen::AlignedBox3d();
  return box.Metric(resolution());
}

VoxelState OccupancyMap::State(const Eigen::Vector3d& point) const {
  const octomap::OcTree& tree = impl_->tree;
  octomap::OcTreeKey key;
  if (!tree.coordToKeyChecked(point.x(), point.y(), point.z(), key)) return VoxelState::kUnknown;
  const octomap::OcTreeNode* node = tree.search(key);
  if (node == nullptr) return VoxelState::kUnknown;
  return tree.isNodeOccupied(node) ? VoxelState::kOccupied : VoxelState::kFree;
}

bool OccupancyMap::IsOccupied(const Eigen::Vector3d& point) const {
  const VoxelState state = State(point);
  if (state == VoxelState::kUnknown) return unknown_ == UnknownSpace::kOccupied;
  return state == VoxelState::kOccupied;
}

double OccupancyMap::OccupiedVolume() const {
  const octomap::OcTree& tree = impl_->tree;
  double volume = 0.0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it)) volume += std::pow(it.getSize(), 3);
  }
  return volume;
}

double OccupancyMap::FreeVolume() const {
  const octomap::OcTree& tree = impl_->tree;
  double volume = 0.0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) volume += std::pow(it.getSize(), 3);
  }
  return volume;
}

int64_t OccupancyMap::NumLeaves() const { return static_cast<int64_t>(impl_->tree.getNumLeafNodes()); }

int64_t OccupancyMap::NumNodes() const { return static_cast<int64_t>(impl_->tree.size()); }

OccupancyGrid OccupancyMap::Rasterize(const VoxelBox& box) const {
  if (box.empty()) throw std::invalid_argument("rasterize: the box is empty (a size is not positive)");
  const octomap::OcTree& tree = impl_->tree;
  OccupancyGrid grid(resolution(), box, unknown_ == UnknownSpace::kOccupied);
  if (tree.size() == 0) return grid;
  const Eigen::Vector3i lo_key = box.min.array() + kKeyOffset;
  const Eigen::Vector3i hi_key = box.end().array() + kKeyOffset - 1;  // inclusive
  if ((lo_key.array() < 0).any() || (hi_key.array() >= 2 * kKeyOffset).any()) {
    throw std::invalid_argument("rasterize: the box leaves the OctoMap key range");
  }
  const octomap::OcTreeKey min_key(static_cast<octomap::key_type>(lo_key.x()),
                                   static_cast<octomap::key_type>(lo_key.y()),
                                   static_cast<octomap::key_type>(lo_key.z()));
  const octomap::OcTreeKey max_key(static_cast<octomap::key_type>(hi_key.x()),
                                   static_cast<octomap::key_type>(hi_key.y()),
                                   static_cast<octomap::key_type>(hi_key.z()));
  const Eigen::Vector3i box_end = box.end();
  for (auto it = tree.begin_leafs_bbx(min_key, max_key), end = tree.end_leafs_bbx(); it != end; ++it) {
    const uint8_t value = tree.isNodeOccupied(*it) ? 1 : 0;
    const Eigen::Vector3i corner = IndexFromKey(it.getIndexKey());
    const int size = 1 << (kTreeDepth - static_cast<int>(it.getDepth()));
    const Eigen::Vector3i a = corner.cwiseMax(box.min);
    const Eigen::Vector3i b = (corner.array() + size).matrix().cwiseMin(box_end);  // exclusive
    if ((b.array() <= a.array()).any()) continue;
    for (int z = a.z(); z < b.z(); ++z) {
      for (int y = a.y(); y < b.y(); ++y) {
        const int64_t row = grid.Linear(Eigen::Vector3i(a.x(), y, z) - box.min);
        std::fill_n(grid.occupied.begin() + row, b.x() - a.x(), value);
      }
    }
  }
  return grid;
}

void OccupancyMap::SetOccupied(const Eigen::Vector3d& point, bool occupied) {
  octomap::OcTree& tree = impl_->tree;
  octomap::OcTreeKey key;
  if (!point.allFinite() || !tree.coordToKeyChecked(point.x(), point.y(), point.z(), key)) {
    throw std::invalid_argument("point outside the OctoMap key range");
  }
  tree.setNodeValue(key, occupied ? tree.getClampingThresMaxLog() : tree.getClampingThresMinLog());
}

std::vector<Eigen::Vector3d> OccupiedVoxelsNear(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& points,
                                                double radius, size_t max_voxels) {
  if (!(radius >= 0.0) || !std::isfinite(radius)) {
    throw std::invalid_argument("voxels near the path: the radius must be a finite number of metres >= 0");
  }
  const double res = map.resolution();
  const double reach_voxels = std::ceil(radius / res);
  const auto too_many = [&] {
    return std::invalid_argument("voxels near the path: more than " + std::to_string(kMaxVoxelLookups) +
                                 " voxels within the radius of the path to look at (lower it)");
  };
  // Refused before any work when one point's neighbourhood alone is above the cap.
  if (!(std::pow(2.0 * reach_voxels + 1.0, 3) <= static_cast<double>(kMaxVoxelLookups))) throw too_many();
  const long reach = static_cast<long>(reach_voxels);
  // Voxel indices packed into one key (OctoMap's keys span 2^16 voxels per axis).
  const auto key = [](long x, long y, long z) {
    const auto part = [](long v) { return static_cast<uint64_t>(v + (1L << 20)) & ((uint64_t{1} << 21) - 1); };
    return (part(x) << 42) | (part(y) << 21) | part(z);
  };
  std::unordered_set<uint64_t> seen;
  std::vector<Eigen::Vector3d> centers;
  const double spacing = std::max(0.5 * res, 0.25 * radius);
  Eigen::Vector3d kept = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (size_t p = 0; p < points.size(); ++p) {
    const Eigen::Vector3d& point = points[p];
    if ((point - kept).norm() < spacing && p + 1 != points.size()) continue;
    kept = point;
    const long cx = static_cast<long>(std::floor(point.x() / res));
    const long cy = static_cast<long>(std::floor(point.y() / res));
    const long cz = static_cast<long>(std::floor(point.z() / res));
    for (long dx = -reach; dx <= reach; ++dx) {
      for (long dy = -reach; dy <= reach; ++dy) {
        for (long dz = -reach; dz <= reach; ++dz) {
          const Eigen::Vector3d center((cx + dx + 0.5) * res, (cy + dy + 0.5) * res, (cz + dz + 0.5) * res);
          // Within the radius of the point, allowing for the checked points' spacing.
          if ((center - point).norm() > radius + 0.87 * res) continue;
          if (!seen.insert(key(cx + dx, cy + dy, cz + dz)).second) continue;
          if (seen.size() > kMaxVoxelLookups) throw too_many();
          if (!map.IsOccupied(center)) continue;
          centers.push_back(center);
          if (centers.size() > max_voxels) {
            throw std::invalid_argument("voxels near the path: more than " + std::to_string(max_voxels) +
                                        " occupied voxels within the radius of the path (lower it)");
          }
        }
      }
    }
  }
  return centers;
}

}  // namespace timeopt
