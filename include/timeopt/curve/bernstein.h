#pragma once

// Conversion between the power basis (ascending coefficients) and the Bernstein basis on [0, 1]:
//
//   f(s) = sum_{k=0}^{n} p_k B_{k,n}(s),   B_{k,n}(s) = C(n,k) s^k (1-s)^(n-k)
//
// The control points p_k (the columns of the returned matrix) enclose the piece in their convex
// hull, which is what the certified constraint mode and collision checks rely on.

#include "timeopt/curve/polynomial_piece.h"

namespace timeopt {

// Control points of a piece, one column per point (n + 1 for degree n).
Eigen::Matrix<double, 3, Eigen::Dynamic> ToBernstein(const PolynomialPiece& piece);

// The piece whose Bernstein control points are the given columns (at least one column).
PolynomialPiece FromBernstein(const Eigen::Matrix<double, 3, Eigen::Dynamic>& control_points);

// Scalar versions for a single axis (used where a polynomial is not a position, e.g. the certified
// constraint rows). `coefficients` ascending; the result has the same length.
Eigen::VectorXd PowerToBernstein(const Eigen::VectorXd& coefficients);
Eigen::VectorXd BernsteinToPower(const Eigen::VectorXd& control_values);

}  // namespace timeopt
