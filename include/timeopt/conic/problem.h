#pragma once
// Data of a conic program in the standard form of the conic solver.
//
//   minimize    c'x
//   subject to  A x = b
//               G x + s = h,   s in K
//
// x in R^n, A is p x n, G is m x n. K is the Cartesian product, in the row order of G, of
//   - `num_nonnegative` rows of the nonnegative orthant (s_i >= 0),
//   - each second-order cone of `soc_dims` in order; a cone of dimension d takes d consecutive rows and
//     means s_0 >= ||(s_1, ..., s_{d-1})||_2 (d >= 1),
//   - each rotated second-order cone of `rotated_dims` in order (MOSEK convention); a cone of
//     dimension d (d >= 2) means 2 s_0 s_1 >= ||(s_2, ..., s_{d-1})||_2^2 with s_0, s_1 >= 0.
// All cones are self-dual, so the dual variable z of G x + s = h lives in the same K.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace timeopt::conic {

/// The cone K of a Problem, described by the sizes of its blocks in the row order of G.
struct ConeSpec {
  /// Number of leading rows that form the nonnegative orthant.
  int num_nonnegative = 0;
  /// Dimensions of the second-order cones that follow the orthant rows, in row order. Each >= 1.
  std::vector<int> soc_dims;
  /// Dimensions of the rotated second-order cones that follow the second-order cones. Each >= 2.
  std::vector<int> rotated_dims;

  /// Total number of rows of G that the cones need: num_nonnegative + sum(soc_dims) + sum(rotated_dims).
  int NumRows() const;
  /// Degree of the cone (barrier parameter): one per orthant row and one per (rotated) cone.
  int Degree() const;
};

/// A conic program (see the file comment for its meaning). Matrices are column-major with int indices.
struct Problem {
  Eigen::VectorXd c;              ///< Objective, size n.
  Eigen::SparseMatrix<double> A;  ///< Equality matrix, p x n (p may be 0).
  Eigen::VectorXd b;              ///< Equality right-hand side, size p.
  Eigen::SparseMatrix<double> G;  ///< Cone matrix, m x n, m = cones.NumRows().
  Eigen::VectorXd h;              ///< Cone right-hand side, size m.
  ConeSpec cones;                 ///< Layout of K along the rows of G.

  int num_variables() const { return static_cast<int>(c.size()); }
  int num_equalities() const { return static_cast<int>(b.size()); }
  int num_cone_rows() const { return static_cast<int>(h.size()); }

  /// Throws std::invalid_argument naming the first mismatch found, e.g. "G has 7 rows but the cones
  /// need 8", "c has NaN at 3", "soc_dims[2] is 0, expected >= 1". Returns normally when the problem is
  /// well formed. Cost: linear in the number of non-zeros.
  void Validate() const;
};

}  // namespace timeopt::conic
