#pragma once

// The distance-field interface the optimizers see (they never see OctoMap).
//
// A distance field maps a point p in R^3 (metres, world frame) to the signed distance d(p) to the
// nearest obstacle surface: d > 0 in free space, d < 0 inside obstacles. Implementations define d
// everywhere in R^3 (documenting what they do far from their data) and return a finite value.

#include <Eigen/Core>

namespace timeopt {

class DistanceField {
 public:
  virtual ~DistanceField() = default;

  // Signed distance at `point`, in metres.
  virtual double Distance(const Eigen::Vector3d& point) const = 0;

  // Signed distance at `point`, in metres, and its gradient (dimensionless) in `*gradient`
  // (must not be null). The gradient is that of the function Distance() evaluates, so it is
  // consistent with finite differences of Distance() wherever that function is differentiable.
  virtual double DistanceAndGradient(const Eigen::Vector3d& point, Eigen::Vector3d* gradient) const = 0;

  // Batched queries: column j of `points` gives (*distances)(j) and, when `gradients` is not
  // null, gradients->col(j); both outputs are resized. One virtual call per batch: implementations
  // override it with a loop free of virtual calls (the default calls DistanceAndGradient per
  // point). Throws std::invalid_argument when `distances` is null.
  virtual void Distances(const Eigen::Matrix3Xd& points, Eigen::VectorXd* distances, Eigen::Matrix3Xd* gradients) const;
};

}  // namespace timeopt
