#include "timeopt/conic/problem_builder.h"

#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

namespace timeopt::conic {

int ProblemBuilder::AddVariables(int n) {
  if (n < 0) throw std::invalid_argument("AddVariables: n is " + std::to_string(n) + ", expected >= 0");
  const int first = num_variables_;
  num_variables_ += n;
  objective_.resize(num_variables_, 0.0);
  return first;
}

void ProblemBuilder::CheckVariable(int var, const char* where) const {
  if (var < 0 || var >= num_variables_) {
    throw std::invalid_argument(std::string(where) + ": variable " + std::to_string(var) + " does not exist (" +
                                std::to_string(num_variables_) + " variables)");
  }
}

void ProblemBuilder::CheckTerms(const std::vector<Term>& terms, const char* where) const {
  for (const Term& t : terms) CheckVariable(t.var, where);
}

void ProblemBuilder::SetObjectiveCoefficient(int var, double coef) {
  CheckVariable(var, "SetObjectiveCoefficient");
  objective_[var] += coef;
}

void ProblemBuilder::AddEquality(const std::vector<Term>& terms, double rhs) {
  CheckTerms(terms, "AddEquality");
  equality_terms_.insert(equality_terms_.end(), terms.begin(), terms.end());
  equality_begin_.push_back(static_cast<int>(equality_terms_.size()));
  equality_rhs_.push_back(rhs);
}

ProblemBuilder::Row ProblemBuilder::AppendRow(const std::vector<Term>& terms, double term_sign, double constant) {
  Row row{static_cast<int>(terms_.size()), 0, constant};
  for (const Term& t : terms) terms_.push_back(Term{t.var, term_sign * t.coef});
  row.end = static_cast<int>(terms_.size());
  return row;
}

void ProblemBuilder::AddLessEqual(const std::vector<Term>& terms, double upper) {
  CheckTerms(terms, "AddLessEqual");
  orthant_rows_.push_back(AppendRow(terms, -1.0, upper));  // upper - sum(terms) >= 0
}

void ProblemBuilder::AddNonnegative(const AffineExpr& e) {
  CheckTerms(e.terms, "AddNonnegative");
  orthant_rows_.push_back(AppendRow(e.terms, 1.0, e.constant));
}

void ProblemBuilder::AddSecondOrderCone(const std::vector<AffineExpr>& rows) {
  if (rows.empty()) throw std::invalid_argument("AddSecondOrderCone: rows is empty, expected >= 1");
  for (const AffineExpr& e : rows) CheckTerms(e.terms, "AddSecondOrderCone");
  for (const AffineExpr& e : rows) soc_rows_.push_back(AppendRow(e.terms, 1.0, e.constant));
  soc_dims_.push_back(static_cast<int>(rows.size()));
}

void ProblemBuilder::AddRotatedCone(const std::vector<AffineExpr>& rows) {
  if (rows.size() < 2) {
    throw std::invalid_argument("AddRotatedCone: rows has " + std::to_string(rows.size()) + " entries, expected >= 2");
  }
  for (const AffineExpr& e : rows) CheckTerms(e.terms, "AddRotatedCone");
  for (const AffineExpr& e : rows) rotated_rows_.push_back(AppendRow(e.terms, 1.0, e.constant));
  rotated_dims_.push_back(static_cast<int>(rows.size()));
}

int ProblemBuilder::num_cone_rows() const {
  return static_cast<int>(orthant_rows_.size() + soc_rows_.size() + rotated_rows_.size());
}

namespace {

// Compressed columns from rows given in increasing order: a counting sort by column keeps each
// column's rows increasing, and repeated (row, column) terms are summed as they are placed.
// Linear in the number of terms (Eigen's setFromTriplets sorts through a transposed copy).
template <typename ForEachRow>
Eigen::SparseMatrix<double> CompressRows(int rows, int cols, std::size_t num_terms, ForEachRow for_each_row) {
  std::vector<int> count(static_cast<std::size_t>(cols) + 1, 0);
  for_each_row([&](int, int var, double) { ++count[static_cast<std::size_t>(var) + 1]; });
  for (int j = 0; j < cols; ++j) count[j + 1] += count[j];
  std::vector<int> row_index(num_terms);
  std::vector<double> values(num_terms);
  std::vector<int> next(count.begin(), count.end() - 1);
  for_each_row([&](int r, int var, double v) {
    int& q = next[var];
    if (q > count[var] && row_index[q - 1] == r) {
      values[q - 1] += v;  // a repeated term of the same row
      return;
    }
    row_index[q] = r;
    values[q] = v;
    ++q;
  });
  Eigen::SparseMatrix<double> matrix(rows, cols);
  std::size_t stored = 0;
  for (int j = 0; j < cols; ++j) stored += next[j] - count[j];
  matrix.resizeNonZeros(static_cast<Eigen::Index>(stored));
  int* outer = matrix.outerIndexPtr();
  int* inner = matrix.innerIndexPtr();
  double* val = matrix.valuePtr();
  int out = 0;
  for (int j = 0; j < cols; ++j) {
    outer[j] = out;
    for (int q = count[j]; q < next[j]; ++q) {
      inner[out] = row_index[q];
      val[out] = values[q];
      ++out;
    }
  }
  outer[cols] = out;
  return matrix;
}

}  // namespace

Problem ProblemBuilder::Build() const {
  Problem problem;
  const int n = num_variables_;
  problem.c = Eigen::Map<const Eigen::VectorXd>(objective_.data(), n);

  const int p = num_equalities();
  problem.b = Eigen::Map<const Eigen::VectorXd>(equality_rhs_.data(), p);
  problem.A = CompressRows(p, n, equality_terms_.size(), [&](auto&& emit) {
    for (int i = 0; i < p; ++i) {
      for (int q = equality_begin_[i]; q < equality_begin_[i + 1]; ++q) {
        emit(i, equality_terms_[q].var, equality_terms_[q].coef);
      }
    }
  });

  // A cone row means constant + sum(terms) in K, i.e. s = h - G x with h = constant, G = -terms.
  const int m = num_cone_rows();
  const std::initializer_list<const std::vector<Row>*> cone_rows = {&orthant_rows_, &soc_rows_, &rotated_rows_};
  problem.h.resize(m);
  int r = 0;
  for (const std::vector<Row>* rows : cone_rows) {
    for (const Row& row : *rows) problem.h[r++] = row.constant;
  }
  problem.G = CompressRows(m, n, terms_.size(), [&](auto&& emit) {
    int row_index = 0;
    for (const std::vector<Row>* rows : cone_rows) {
      for (const Row& row : *rows) {
        for (int q = row.begin; q < row.end; ++q) emit(row_index, terms_[q].var, -terms_[q].coef);
        ++row_index;
      }
    }
  });

  problem.cones.num_nonnegative = static_cast<int>(orthant_rows_.size());
  problem.cones.soc_dims = soc_dims_;
  problem.cones.rotated_dims = rotated_dims_;
  return problem;
}

}  // namespace timeopt::conic
