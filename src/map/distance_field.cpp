#include "timeopt/map/distance_field.h"

#include <stdexcept>

namespace timeopt {

void DistanceField::Distances(const Eigen::Matrix3Xd& points, Eigen::VectorXd* distances,
                              Eigen::Matrix3Xd* gradients) const {
  if (distances == nullptr) throw std::invalid_argument("Distances: distances is null");
  const Eigen::Index n = points.cols();
  distances->resize(n);
  if (gradients != nullptr) gradients->resize(3, n);
  Eigen::Vector3d g;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (gradients != nullptr) {
      (*distances)(j) = DistanceAndGradient(points.col(j), &g);
      gradients->col(j) = g;
    } else {
      (*distances)(j) = Distance(points.col(j));
    }
  }
}

}  // namespace timeopt
