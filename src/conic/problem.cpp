#include "timeopt/conic/problem.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace timeopt::conic {

int ConeSpec::NumRows() const {
  long long rows = num_nonnegative;
  for (int d : soc_dims) rows += d;
  for (int d : rotated_dims) rows += d;
  return static_cast<int>(rows);
}

int ConeSpec::Degree() const { return num_nonnegative + static_cast<int>(soc_dims.size() + rotated_dims.size()); }

namespace {

[[noreturn]] void Fail(const std::string& message) { throw std::invalid_argument(message); }

void CheckFinite(const Eigen::VectorXd& v, const char* name) {
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      std::ostringstream os;
      os << name << " has " << (std::isnan(v[i]) ? "NaN" : "Inf") << " at " << i;
      Fail(os.str());
    }
  }
}

void CheckMatrix(const Eigen::SparseMatrix<double>& M, const char* name) {
  // The sparse matrix may be uncompressed; iterate over its stored entries.
  for (int j = 0; j < M.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it) {
      if (!std::isfinite(it.value())) {
        std::ostringstream os;
        os << name << " has " << (std::isnan(it.value()) ? "NaN" : "Inf") << " at (" << it.row() << ", " << it.col()
           << ")";
        Fail(os.str());
      }
    }
  }
}

}  // namespace

void Problem::Validate() const {
  const Eigen::Index n = c.size();
  if (A.cols() != n) {
    Fail("A has " + std::to_string(A.cols()) + " columns but c has " + std::to_string(n) + " entries");
  }
  if (A.rows() != b.size()) {
    Fail("A has " + std::to_string(A.rows()) + " rows but b has " + std::to_string(b.size()) + " entries");
  }
  if (G.cols() != n) {
    Fail("G has " + std::to_string(G.cols()) + " columns but c has " + std::to_string(n) + " entries");
  }
  if (cones.num_nonnegative < 0) {
    Fail("num_nonnegative is " + std::to_string(cones.num_nonnegative) + ", expected >= 0");
  }
  for (std::size_t k = 0; k < cones.soc_dims.size(); ++k) {
    if (cones.soc_dims[k] < 1) {
      Fail("soc_dims[" + std::to_string(k) + "] is " + std::to_string(cones.soc_dims[k]) + ", expected >= 1");
    }
  }
  for (std::size_t k = 0; k < cones.rotated_dims.size(); ++k) {
    if (cones.rotated_dims[k] < 2) {
      Fail("rotated_dims[" + std::to_string(k) + "] is " + std::to_string(cones.rotated_dims[k]) + ", expected >= 2");
    }
  }
  const int m = cones.NumRows();
  if (G.rows() != m) {
    Fail("G has " + std::to_string(G.rows()) + " rows but the cones need " + std::to_string(m));
  }
  if (h.size() != m) {
    Fail("h has " + std::to_string(h.size()) + " entries but the cones need " + std::to_string(m));
  }
  CheckFinite(c, "c");
  CheckFinite(b, "b");
  CheckFinite(h, "h");
  CheckMatrix(A, "A");
  CheckMatrix(G, "G");
}

}  // namespace timeopt::conic
