#include "timeopt/map/esdf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace timeopt {
namespace internal {
namespace {
constexpr std::size_t kHugePage = std::size_t{2} << 20;
}  // namespace

void* AllocateLarge(std::size_t bytes) {
  if (bytes < kHugePage) return ::operator new(bytes);
  const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
  void* pointer = ::operator new (rounded, std::align_val_t{kHugePage});
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  madvise(pointer, rounded, MADV_HUGEPAGE);  // advice only: failure is harmless
#endif
  return pointer;
}

void DeallocateLarge(void* pointer, std::size_t bytes) noexcept {
  if (bytes < kHugePage) {
    ::operator delete(pointer);
  } else {
    ::operator delete (pointer, std::align_val_t{kHugePage});
  }
}

}  // namespace internal

namespace {

// Squared distances in voxel units are integers; uint32 keeps the working buffer at 4 bytes per
// voxel. kInfinite marks "no site on this line / plane / box yet".
using SquaredCells = uint32_t;
constexpr SquaredCells kInfinite = std::numeric_limits<SquaredCells>::max();
// "No site in this column" during the z pass (unsquared voxel counts stay far below it).
constexpr SquaredCells kFar = SquaredCells{1} << 30;

// Workspace of the 1-D lower-envelope transform (Felzenszwalb-Huttenlocher), sized for the
// longest axis.
struct EnvelopeWorkspace {
  explicit EnvelopeWorkspace(int n) : input(static_cast<size_t>(n)), envelope(static_cast<size_t>(n)) {}
  struct Parabola {
    int64_t height;     // F(apex) = f[apex] + apex^2
    int64_t start_num;  // F(apex) - F(previous apex)
    int64_t start_den;  // apex - previous apex (> 0)
    int64_t apex;
  };
  std::vector<SquaredCells> input;
  std::vector<Parabola> envelope;  // the lower envelope, apexes increasing
};

// Lower envelope on the sub-line [lo, hi] of the input, written to output[q] for q in
// [first, last) (a sub-range of [lo, hi]).
void EnvelopeRange(int lo, int hi, int first, int last, EnvelopeWorkspace* ws, SquaredCells* output,
                   int64_t output_stride) {
  const SquaredCells* f = ws->input.data();
  // Parabola p: (q - p)^2 + f[p]. Parabolas a > b cross at s(a, b) = (F(a) - F(b)) / (2 (a - b))
  // with F(p) = f[p] + p^2. Envelope entry k keeps the numerator F(v_k) - F(v_{k-1}) and the
  // denominator v_k - v_{k-1} of (twice) its start, so crossings are compared by
  // cross-multiplication in 64-bit integers: exact, and no division.
  EnvelopeWorkspace::Parabola* env = ws->envelope.data();
  int k = -1;
  for (int q = lo; q <= hi; ++q) {
    if (f[q] == kInfinite) continue;
    const int64_t fq = static_cast<int64_t>(f[q]) + static_cast<int64_t>(q) * q;
    // Pop entry k while the new parabola is below it before it starts being the lowest:
    // s(q, v_k) <= s(v_k, v_{k-1}).
    while (k > 0 && (fq - env[k].height) * env[k].start_den <= env[k].start_num * (q - env[k].apex)) {
      --k;
    }
    ++k;
    if (k > 0) {
      env[k].start_num = fq - env[k - 1].height;
      env[k].start_den = q - env[k - 1].apex;
    }
    env[k].apex = q;
    env[k].height = fq;
  }
  if (k < 0) {
    for (int q = first; q < last; ++q) output[q * output_stride] = kInfinite;
    return;
  }
  int j = 0;
  for (int q = first; q < last; ++q) {
    // Advance while the next parabola starts before q: s(v_{j+1}, v_j) < q.
    while (j < k && env[j + 1].start_num < 2 * static_cast<int64_t>(q) * env[j + 1].start_den) {
      ++j;
    }
    const int64_t dq = q - env[j].apex;
    output[q * output_stride] = static_cast<SquaredCells>(dq * dq + f[env[j].apex]);
  }
}

// output[q] = min_p (q - p)^2 + input[p] over the p with finite input; kInfinite when none.
// In place: `output` must hold the input already (ws->input is a copy of it), so entries that do
// not change (zeros, lines without a site) are not written again.
//
// A zero input (a site on this line) ends the influence of everything behind it: for q right of
// a zero at l, any p < l gives (q - p)^2 + f[p] > (q - l)^2. So the line splits at its zeros into
// independent runs, each solved with its two bounding zeros; zeros themselves output 0. In
// sparse or dense maps most of the work disappears this way.
void LowerEnvelope(int n, EnvelopeWorkspace* ws, SquaredCells* output, int64_t output_stride) {
  const SquaredCells* f = ws->input.data();
  int q = 0;
  while (q < n) {
    if (f[q] == 0) {  // a site: stays 0
      ++q;
      continue;
    }
    const int first = q;
    bool any_finite = false;
    while (q < n && f[q] != 0) {
      any_finite |= f[q] != kInfinite;
      ++q;
    }
    const int last = q;  // exclusive; f[last] == 0 when last < n
    const int lo = first > 0 ? first - 1 : first;
    const int hi = last < n ? last : last - 1;
    if (!any_finite && lo == first && hi == last - 1) {
      continue;  // no site on the whole line: stays kInfinite
    } else {
      EnvelopeRange(lo, hi, first, last, ws, output, output_stride);
    }
  }
}

// Exact squared Euclidean distance (voxel units) from every voxel to the nearest voxel whose
// occupancy equals `site_value`, into `out` (row-major, x fastest). The order of the axes
// follows the memory: z first (binary input, sweeps over whole planes), then y inside each
// plane (which fits in cache), then x along contiguous rows of the same plane.
void SquaredDistanceTransform(const OccupancyGrid& grid, uint8_t site_value, SquaredCells* out) {
  const int nx = grid.box.size.x();
  const int ny = grid.box.size.y();
  const int nz = grid.box.size.z();
  const int64_t plane = static_cast<int64_t>(nx) * ny;
  const uint8_t* occ = grid.occupied.data();

  // z, forward: distance (in voxels, not squared) to the nearest site at or below in the column;
  // kFar marks "no site". Whole planes at a time (branch-free, vectorizable).
  for (int64_t i = 0; i < plane; ++i) out[i] = occ[i] == site_value ? 0 : kFar;
  for (int z = 1; z < nz; ++z) {
    const uint8_t* o = occ + z * plane;
    const SquaredCells* previous = out + (z - 1) * plane;
    SquaredCells* current = out + z * plane;
    for (int64_t i = 0; i < plane; ++i) {
      current[i] = o[i] == site_value ? 0 : std::min<SquaredCells>(previous[i] + 1, kFar);
    }
  }
  // Then plane by plane from the top: the backward z sweep finishes the plane (squared), and the
  // y and x passes run on it while it is still in cache. `above` keeps the unsquared column
  // distances of the plane above.
  std::vector<SquaredCells> above(static_cast<size_t>(plane), kFar);
  EnvelopeWorkspace ws(std::max(nx, ny));
  for (int z = nz - 1; z >= 0; --z) {
    SquaredCells* p = out + z * plane;
    for (int64_t i = 0; i < plane; ++i) {
      const SquaredCells d = std::min(p[i], above[i] + 1);
      above[i] = d;
      p[i] = d >= kFar ? kInfinite : d * d;
    }
    // y: one gathered column at a time.
    if (ny > 1) {
      for (int x = 0; x < nx; ++x) {
        SquaredCells* line = p + x;
        for (int y = 0; y < ny; ++y) ws.input[y] = line[static_cast<int64_t>(y) * nx];
        LowerEnvelope(ny, &ws, line, nx);
      }
    }
    // x: contiguous rows.
    if (nx > 1) {
      for (int y = 0; y < ny; ++y) {
        SquaredCells* line = p + static_cast<int64_t>(y) * nx;
        std::copy_n(line, nx, ws.input.begin());
        LowerEnvelope(nx, &ws, line, 1);
      }
    }
  }
}

}  // namespace

Esdf::Esdf(const OccupancyGrid& grid) {
  grid.Validate();
  const Eigen::Vector3i n = grid.box.size;
  // The largest squared distance in voxels must stay below 2^31 (int32 conversion below; it is
  // also far from kInfinite).
  const double largest = (n.cast<double>().array() - 1.0).square().sum();
  if (largest >= 2147483648.0) {
    std::ostringstream message;
    message << "ESDF box of " << n.transpose() << " voxels is too long (squared diagonal must be "
            << "below 2^31 voxels^2)";
    throw std::invalid_argument(message.str());
  }
  const int64_t occupied = grid.CountOccupied();
  if (occupied == 0) {
    throw std::invalid_argument(
        "ESDF box has no occupied voxel: the distance is unbounded (give a box with obstacles, or "
        "treat unknown space as occupied)");
  }
  if (occupied == grid.box.num_voxels()) {
    throw std::invalid_argument("ESDF box has no free voxel: every voxel is occupied");
  }

  resolution_ = grid.resolution;
  inverse_resolution_ = 1.0 / resolution_;
  box_ = grid.box;
  first_centre_ = grid.Centre(box_.min);
  last_centre_ = grid.Centre(box_.end() - Eigen::Vector3i::Ones());
  max_cell_ = (n.array() - 2).cwiseMax(0);
  step_ << (n.x() > 1 ? 1 : 0), (n.y() > 1 ? n.x() : 0), (n.z() > 1 ? static_cast<int64_t>(n.x()) * n.y() : 0);

  const size_t count = static_cast<size_t>(grid.box.num_voxels());
  values_.resize(count);
  const float half = static_cast<float>(0.5 * resolution_);
  const float res = static_cast<float>(resolution_);
  // Uninitialized on purpose: every element is written by the z sweep first.
  struct Release {
    size_t bytes;
    void operator()(SquaredCells* p) const { internal::DeallocateLarge(p, bytes); }
  };
  const size_t squared_bytes = count * sizeof(SquaredCells);
  const std::unique_ptr<SquaredCells, Release> squared(
      static_cast<SquaredCells*>(internal::AllocateLarge(squared_bytes)), Release{squared_bytes});
  // Free voxels: distance to the nearest occupied centre minus half a voxel (occupied voxels get
  // -r/2 here and are overwritten next).
  SquaredDistanceTransform(grid, 1, squared.get());
  // Every squared distance is finite here (the box has a site of each kind) and below 2^31 (the
  // size check above), so it converts to float as int32, which vectorizes (uint32 does not without
  // AVX-512); so does Eigen's array sqrt, where std::sqrt in a loop would not (errno).
  using SquaredArray = Eigen::Map<const Eigen::Array<int32_t, Eigen::Dynamic, 1>>;
  using ValueArray = Eigen::Map<Eigen::ArrayXf>;
  const Eigen::Index size = static_cast<Eigen::Index>(count);
  ValueArray values(values_.data(), size);
  values = SquaredArray(reinterpret_cast<const int32_t*>(squared.get()), size).cast<float>().sqrt() * res - half;
  // Occupied voxels: minus (distance to the nearest free centre minus half a voxel).
  SquaredDistanceTransform(grid, 0, squared.get());
  const Eigen::Map<const Eigen::Array<uint8_t, Eigen::Dynamic, 1>> is_occupied(grid.occupied.data(), size);
  values =
      (is_occupied != uint8_t{0})
          .select(half - SquaredArray(reinterpret_cast<const int32_t*>(squared.get()), size).cast<float>().sqrt() * res,
                  values);
}

namespace {

// The budget check of FromMap and FromMapRegion, before anything is allocated.
void CheckBudget(const VoxelBox& voxels, int64_t max_bytes) {
  // Above the dense grid's own cap, the grid refuses it with a message that does not depend on the
  // machine's budget.
  if (max_bytes <= 0 || Esdf::PeakBytes(voxels) <= max_bytes || voxels.num_voxels() > kMaxGridVoxels) return;
  std::ostringstream message;
  constexpr double kMiB = 1024.0 * 1024.0;
  message << std::fixed << std::setprecision(2) << "the distance field over " << voxels.size(0) << " x "
          << voxels.size(1) << " x " << voxels.size(2) << " voxels needs "
          << static_cast<double>(Esdf::PeakBytes(voxels)) / kMiB << " MiB at its peak, above the memory budget of "
          << static_cast<double>(max_bytes) / kMiB << " MiB (a smaller region, a coarser map, or a larger budget)";
  throw std::invalid_argument(message.str());
}

// Marks the voxels of box's faces occupied where faces[2 axis + side] (side 0: the low face): a
// region's cut faces, or every face of a box without an obstacle (there the box is the world and its
// walls bound the distance, which would otherwise be unbounded).
void OccupyFaces(const VoxelBox& box, const std::array<bool, 6>& faces, OccupancyGrid* grid) {
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      if (!faces[static_cast<size_t>(2 * axis + side)]) continue;
      const int layer = side == 0 ? box.min(axis) : box.end()(axis) - 1;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      Eigen::Vector3i index;
      index(axis) = layer;
      for (int i = box.min(u); i < box.end()(u); ++i) {
        for (int j = box.min(v); j < box.end()(v); ++j) {
          index(u) = i;
          index(v) = j;
          grid->Set(index, true);
        }
      }
    }
  }
}

}  // namespace

Esdf Esdf::FromMap(const OccupancyMap& map, const std::optional<Eigen::AlignedBox3d>& box, int64_t max_bytes) {
  VoxelBox voxels;
  if (box) {
    voxels = VoxelBox::Covering(*box, map.resolution());
  } else {
    if (map.empty()) {
      throw std::invalid_argument("the map is empty (no known voxel): give a box for the ESDF");
    }
    voxels = map.KnownBox();
  }
  CheckBudget(voxels, max_bytes);
  OccupancyGrid grid = map.Rasterize(voxels);
  if (grid.CountOccupied() == 0) OccupyFaces(voxels, {true, true, true, true, true, true}, &grid);
  return Esdf(grid);
}

Esdf Esdf::FromMapRegion(const OccupancyMap& map, const Eigen::AlignedBox3d& region, int64_t max_bytes) {
  if (map.empty()) throw std::invalid_argument("the map is empty (no known voxel)");
  const VoxelBox known = map.KnownBox();
  // The region clipped to the known box first, so that a region far larger than the map (a huge
  // margin) is the map, not a box beyond the OctoMap key range.
  const Eigen::AlignedBox3d known_metric = known.Metric(map.resolution());
  const Eigen::AlignedBox3d clipped = region.intersection(known_metric);
  const auto no_overlap = [&] {
    std::ostringstream message;
    message << "the region [" << region.min().transpose() << "] - [" << region.max().transpose()
            << "] m does not overlap the map's known box "
            << "[" << known_metric.min().transpose() << "] - [" << known_metric.max().transpose() << "] m";
    return std::invalid_argument(message.str());
  };
  if (clipped.isEmpty()) throw no_overlap();
  const VoxelBox wanted = VoxelBox::Covering(clipped, map.resolution());
  VoxelBox box;
  box.min = wanted.min.cwiseMax(known.min);
  box.size = wanted.end().cwiseMin(known.end()) - box.min;
  if ((box.size.array() <= 0).any()) throw no_overlap();
  CheckBudget(box, max_bytes);
  OccupancyGrid grid = map.Rasterize(box);
  // The cut faces: a face of the region strictly inside the known box.
  std::array<bool, 6> cut{};
  for (int axis = 0; axis < 3; ++axis) {
    cut[2 * axis] = box.min(axis) > known.min(axis);
    cut[2 * axis + 1] = box.end()(axis) < known.end()(axis);
  }
  OccupyFaces(box, cut, &grid);
  if (grid.CountOccupied() == 0) OccupyFaces(box, {true, true, true, true, true, true}, &grid);
  return Esdf(grid);
}

template <bool kWithGradient>
inline double Esdf::Evaluate(const Eigen::Vector3d& point, Eigen::Vector3d* gradient) const {
  // Clamp to the interpolation domain; the part outside adds its length (see the header).
  const double px = point.x(), py = point.y(), pz = point.z();
  // Argument order makes a NaN coordinate clamp to the box (the result is then NaN, never an
  // out-of-range read).
  const double qx = std::max(first_centre_.x(), std::min(last_centre_.x(), px));
  const double qy = std::max(first_centre_.y(), std::min(last_centre_.y(), py));
  const double qz = std::max(first_centre_.z(), std::min(last_centre_.z(), pz));
  const double ux = (qx - first_centre_.x()) * inverse_resolution_;
  const double uy = (qy - first_centre_.y()) * inverse_resolution_;
  const double uz = (qz - first_centre_.z()) * inverse_resolution_;
  const int ix = std::min(static_cast<int>(ux), max_cell_.x());
  const int iy = std::min(static_cast<int>(uy), max_cell_.y());
  const int iz = std::min(static_cast<int>(uz), max_cell_.z());
  const double tx = ux - ix, ty = uy - iy, tz = uz - iz;
  const int64_t sx = step_.x(), sy = step_.y(), sz = step_.z();
  const float* v =
      values_.data() + ix + static_cast<int64_t>(box_.size.x()) * (iy + static_cast<int64_t>(box_.size.y()) * iz);
  const double d000 = v[0], d100 = v[sx], d010 = v[sy], d110 = v[sx + sy];
  const double d001 = v[sz], d101 = v[sx + sz], d011 = v[sy + sz], d111 = v[sx + sy + sz];
  const double e00 = d100 - d000, e10 = d110 - d010, e01 = d101 - d001, e11 = d111 - d011;
  const double c00 = d000 + tx * e00, c10 = d010 + tx * e10;
  const double c01 = d001 + tx * e01, c11 = d011 + tx * e11;
  const double c0 = c00 + ty * (c10 - c00), c1 = c01 + ty * (c11 - c01);
  double distance = c0 + tz * (c1 - c0);

  const double ox = px - qx, oy = py - qy, oz = pz - qz;
  const double outside_sq = ox * ox + oy * oy + oz * oz;
  // Inside the domain the square root is skipped; a NaN coordinate still gives NaN.
  const double outside = outside_sq != 0.0 ? std::sqrt(outside_sq) : 0.0;
  distance += outside;
  if constexpr (kWithGradient) {
    const double gx = ((1.0 - tz) * (e00 + ty * (e10 - e00)) + tz * (e01 + ty * (e11 - e01))) * inverse_resolution_;
    const double gy = ((1.0 - tz) * (c10 - c00) + tz * (c11 - c01)) * inverse_resolution_;
    const double gz = (c1 - c0) * inverse_resolution_;
    // Along an axis where the point was clamped, the interpolant no longer depends on it.
    Eigen::Vector3d g(ox == 0.0 ? gx : 0.0, oy == 0.0 ? gy : 0.0, oz == 0.0 ? gz : 0.0);
    if (outside > 0.0) g += Eigen::Vector3d(ox, oy, oz) / outside;
    *gradient = g;
  }
  return distance;
}

double Esdf::Distance(const Eigen::Vector3d& point) const { return Evaluate<false>(point, nullptr); }

double Esdf::DistanceAndGradient(const Eigen::Vector3d& point, Eigen::Vector3d* gradient) const {
  if (gradient == nullptr) throw std::invalid_argument("DistanceAndGradient: gradient is null");
  return Evaluate<true>(point, gradient);
}

void Esdf::Distances(const Eigen::Matrix3Xd& points, Eigen::VectorXd* distances, Eigen::Matrix3Xd* gradients) const {
  if (distances == nullptr) throw std::invalid_argument("Distances: distances is null");
  const Eigen::Index n = points.cols();
  distances->resize(n);
  if (gradients == nullptr) {
    for (Eigen::Index j = 0; j < n; ++j) (*distances)(j) = Evaluate<false>(points.col(j), nullptr);
    return;
  }
  gradients->resize(3, n);
  Eigen::Vector3d g;
  for (Eigen::Index j = 0; j < n; ++j) {
    (*distances)(j) = Evaluate<true>(points.col(j), &g);
    gradients->col(j) = g;
  }
}

double Esdf::VoxelDistance(const Eigen::Vector3i& index) const {
  if (!box_.Contains(index)) {
    std::ostringstream message;
    message << "voxel index (" << index.transpose() << ") is outside the ESDF box";
    throw std::invalid_argument(message.str());
  }
  const Eigen::Vector3i local = index - box_.min;
  return values_[static_cast<size_t>(local.x() + static_cast<int64_t>(box_.size.x()) *
                                                     (local.y() + static_cast<int64_t>(box_.size.y()) * local.z()))];
}

bool Esdf::Contains(const Eigen::Vector3d& point) const {
  return (point.array() >= first_centre_.array()).all() && (point.array() <= last_centre_.array()).all();
}

Eigen::AlignedBox3d Esdf::domain() const { return Eigen::AlignedBox3d(first_centre_, last_centre_); }

}  // namespace timeopt
