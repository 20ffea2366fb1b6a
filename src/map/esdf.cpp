#include "timeopt/map/esdf.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace timeopt {
namespace {

// Squared distances in voxel units are integers; uint32 keeps the working buffer at 4 bytes per
// voxel. kInfinite marks "no site on this line / plane / box yet".
using SquaredCells = uint32_t;
constexpr SquaredCells kInfinite = std::numeric_limits<SquaredCells>::max();

// Workspace of the 1-D lower-envelope transform (Felzenszwalb-Huttenlocher), sized for the
// longest axis.
struct EnvelopeWorkspace {
  explicit EnvelopeWorkspace(int n)
      : input(n), output(n), sites(n), boundaries(static_cast<size_t>(n) + 1) {}
  std::vector<SquaredCells> input;
  std::vector<SquaredCells> output;
  std::vector<int> sites;          // parabola apexes of the envelope
  std::vector<double> boundaries;  // where parabola k starts to be the lowest
};

// output[q] = min_p (q - p)^2 + input[p] over the p with finite input; kInfinite when none.
void LowerEnvelope(int n, EnvelopeWorkspace* ws) {
  const SquaredCells* f = ws->input.data();
  SquaredCells* d = ws->output.data();
  int* v = ws->sites.data();
  double* z = ws->boundaries.data();
  int k = -1;
  auto intersection = [f](int q, int p) {
    const double fq = static_cast<double>(f[q]) + static_cast<double>(q) * q;
    const double fp = static_cast<double>(f[p]) + static_cast<double>(p) * p;
    return (fq - fp) / (2.0 * (q - p));
  };
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInfinite) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -std::numeric_limits<double>::infinity();
      z[1] = std::numeric_limits<double>::infinity();
      continue;
    }
    double s = intersection(q, v[k]);
    while (s <= z[k]) {  // z[0] = -inf ends the loop at k = 0
      --k;
      s = intersection(q, v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  if (k < 0) {
    std::fill_n(d, n, kInfinite);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const int64_t dq = q - v[j];
    d[q] = static_cast<SquaredCells>(dq * dq + f[v[j]]);
  }
}

// Exact squared Euclidean distance (voxel units) from every voxel to the nearest voxel whose
// occupancy equals `site_value`, into `squared` (row-major, x fastest).
void SquaredDistanceTransform(const OccupancyGrid& grid, uint8_t site_value,
                              std::vector<SquaredCells>* squared) {
  const int nx = grid.box.size.x();
  const int ny = grid.box.size.y();
  const int nz = grid.box.size.z();
  const int64_t plane = static_cast<int64_t>(nx) * ny;
  squared->resize(static_cast<size_t>(plane * nz));
  SquaredCells* out = squared->data();
  const uint8_t* occ = grid.occupied.data();

  // x: distance to the nearest site on the row, by a forward and a backward sweep.
  for (int64_t row = 0; row < static_cast<int64_t>(ny) * nz; ++row) {
    const uint8_t* in = occ + row * nx;
    SquaredCells* o = out + row * nx;
    int64_t last = -1;
    for (int x = 0; x < nx; ++x) {
      if (in[x] == site_value) last = x;
      o[x] = last < 0 ? kInfinite : static_cast<SquaredCells>(x - last);
    }
    last = -1;
    for (int x = nx - 1; x >= 0; --x) {
      if (in[x] == site_value) last = x;
      if (last >= 0) o[x] = std::min(o[x], static_cast<SquaredCells>(last - x));
      if (o[x] != kInfinite) o[x] *= o[x];
    }
  }
  // y, then z: lower envelope of parabolas along each line.
  EnvelopeWorkspace ws(std::max(ny, nz));
  if (ny > 1) {
    for (int z = 0; z < nz; ++z) {
      for (int x = 0; x < nx; ++x) {
        SquaredCells* line = out + z * plane + x;
        for (int y = 0; y < ny; ++y) ws.input[y] = line[static_cast<int64_t>(y) * nx];
        LowerEnvelope(ny, &ws);
        for (int y = 0; y < ny; ++y) line[static_cast<int64_t>(y) * nx] = ws.output[y];
      }
    }
  }
  if (nz > 1) {
    for (int64_t xy = 0; xy < plane; ++xy) {
      SquaredCells* line = out + xy;
      for (int z = 0; z < nz; ++z) ws.input[z] = line[z * plane];
      LowerEnvelope(nz, &ws);
      for (int z = 0; z < nz; ++z) line[z * plane] = ws.output[z];
    }
  }
}

}  // namespace

Esdf::Esdf(const OccupancyGrid& grid) {
  grid.Validate();
  const Eigen::Vector3i n = grid.box.size;
  // Largest squared distance in voxels must stay below kInfinite.
  const double largest = (n.cast<double>().array() - 1.0).square().sum();
  if (largest >= static_cast<double>(kInfinite)) {
    std::ostringstream message;
    message << "ESDF box of " << n.transpose() << " voxels is too long (squared diagonal must be "
            << "below 2^32 voxels^2)";
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
  step_ << (n.x() > 1 ? 1 : 0), (n.y() > 1 ? n.x() : 0),
      (n.z() > 1 ? static_cast<int64_t>(n.x()) * n.y() : 0);

  const size_t count = static_cast<size_t>(grid.box.num_voxels());
  values_.resize(count);
  const float half = static_cast<float>(0.5 * resolution_);
  const float res = static_cast<float>(resolution_);
  std::vector<SquaredCells> squared;
  SquaredDistanceTransform(grid, 1, &squared);  // to the nearest occupied voxel
  for (size_t i = 0; i < count; ++i) {
    if (grid.occupied[i] == 0) values_[i] = std::sqrt(static_cast<float>(squared[i])) * res - half;
  }
  SquaredDistanceTransform(grid, 0, &squared);  // to the nearest free voxel
  for (size_t i = 0; i < count; ++i) {
    if (grid.occupied[i] != 0) {
      values_[i] = half - std::sqrt(static_cast<float>(squared[i])) * res;
    }
  }
}

Esdf Esdf::FromMap(const OccupancyMap& map, const std::optional<Eigen::AlignedBox3d>& box) {
  VoxelBox voxels;
  if (box) {
    voxels = VoxelBox::Covering(*box, map.resolution());
  } else {
    if (map.empty()) {
      throw std::invalid_argument("the map is empty (no known voxel): give a box for the ESDF");
    }
    voxels = map.KnownBox();
  }
  return Esdf(map.Rasterize(voxels));
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
  const float* v = values_.data() + ix +
                   static_cast<int64_t>(box_.size.x()) *
                       (iy + static_cast<int64_t>(box_.size.y()) * iz);
  const double d000 = v[0], d100 = v[sx], d010 = v[sy], d110 = v[sx + sy];
  const double d001 = v[sz], d101 = v[sx + sz], d011 = v[sy + sz], d111 = v[sx + sy + sz];
  const double e00 = d100 - d000, e10 = d110 - d010, e01 = d101 - d001, e11 = d111 - d011;
  const double c00 = d000 + tx * e00, c10 = d010 + tx * e10;
  const double c01 = d001 + tx * e01, c11 = d011 + tx * e11;
  const double c0 = c00 + ty * (c10 - c00), c1 = c01 + ty * (c11 - c01);
  double distance = c0 + tz * (c1 - c0);

  const double ox = px - qx, oy = py - qy, oz = pz - qz;
  const double outside_sq = ox * ox + oy * oy + oz * oz;
  const double outside = std::sqrt(outside_sq);  // NaN for a NaN coordinate
  distance += outside;
  if constexpr (kWithGradient) {
    const double gx = ((1.0 - tz) * (e00 + ty * (e10 - e00)) + tz * (e01 + ty * (e11 - e01))) *
                      inverse_resolution_;
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

void Esdf::Distances(const Eigen::Matrix3Xd& points, Eigen::VectorXd* distances,
                     Eigen::Matrix3Xd* gradients) const {
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
  return values_[static_cast<size_t>(
      local.x() + static_cast<int64_t>(box_.size.x()) *
                      (local.y() + static_cast<int64_t>(box_.size.y()) * local.z()))];
}

bool Esdf::Contains(const Eigen::Vector3d& point) const {
  return (point.array() >= first_centre_.array()).all() &&
         (point.array() <= last_centre_.array()).all();
}

Eigen::AlignedBox3d Esdf::domain() const { return Eigen::AlignedBox3d(first_centre_, last_centre_); }

}  // namespace timeopt
