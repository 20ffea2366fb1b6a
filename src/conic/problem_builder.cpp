#include "timeopt/conic/problem_builder.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt::conic {

int ProblemBuilder::AddVariables(int n) {
  if (n < 0) throw std::invalid_argument("AddVariables: n is " + std::to_string(n) + ", expected >= 0");
  const int first = num_variables_;
  num_variables_ += n;
  objective_.resize(num_variables_, 0.0);
  return first;
}

void ProblemBuilder::CheckTerms(const std::vector<Term>& terms, const char* where) const {
  for (const Term& t : terms) {
    if (t.var < 0 || t.var >= num_variables_) {
      throw std::invalid_argument(std::string(where) + ": variable " + std::to_string(t.var) +
                                  " does not exist (" + std::to_string(num_variables_) +
                                  " variables)");
    }
  }
}

void ProblemBuilder::SetObjectiveCoefficient(int var, double coef) {
  CheckTerms({Term{var, coef}}, "SetObjectiveCoefficient");
  objective_[var] += coef;
}

void ProblemBuilder::AddEquality(const std::vector<Term>& terms, double rhs) {
  CheckTerms(terms, "AddEquality");
  equality_terms_.insert(equality_terms_.end(), terms.begin(), terms.end());
  equality_begin_.push_back(static_cast<int>(equality_terms_.size()));
  equality_rhs_.push_back(rhs);
}

ProblemBuilder::Row ProblemBuilder::AppendRow(const AffineExpr& e, double sign) {
  Row row{static_cast<int>(terms_.size()), 0, sign * e.constant};
  for (const Term& t : e.terms) terms_.push_back(Term{t.var, sign * t.coef});
  row.end = static_cast<int>(terms_.size());
  return row;
}

void ProblemBuilder::AddLessEqual(const std::vector<Term>& terms, double upper) {
  CheckTerms(terms, "AddLessEqual");
  // upper - sum(terms) >= 0.
  AffineExpr e;
  e.terms.reserve(terms.size());
  for (const Term& t : terms) e.terms.push_back(Term{t.var, -t.coef});
  e.constant = upper;
  orthant_rows_.push_back(AppendRow(e, 1.0));
}

void ProblemBuilder::AddNonnegative(const AffineExpr& e) {
  CheckTerms(e.terms, "AddNonnegative");
  orthant_rows_.push_back(AppendRow(e, 1.0));
}

void ProblemBuilder::AddSecondOrderCone(const std::vector<AffineExpr>& rows) {
  if (rows.empty()) throw std::invalid_argument("AddSecondOrderCone: rows is empty, expected >= 1");
  for (const AffineExpr& e : rows) CheckTerms(e.terms, "AddSecondOrderCone");
  for (const AffineExpr& e : rows) soc_rows_.push_back(AppendRow(e, 1.0));
  soc_dims_.push_back(static_cast<int>(rows.size()));
}

void ProblemBuilder::AddRotatedCone(const std::vector<AffineExpr>& rows) {
  if (rows.size() < 2) {
    throw std::invalid_argument("AddRotatedCone: rows has " + std::to_string(rows.size()) +
                                " entries, expected >= 2");
  }
  for (const AffineExpr& e : rows) CheckTerms(e.terms, "AddRotatedCone");
  for (const AffineExpr& e : rows) rotated_rows_.push_back(AppendRow(e, 1.0));
  rotated_dims_.push_back(static_cast<int>(rows.size()));
}

int ProblemBuilder::num_cone_rows() const {
  return static_cast<int>(orthant_rows_.size() + soc_rows_.size() + rotated_rows_.size());
}

Problem ProblemBuilder::Build() const {
  Problem problem;
  const int n = num_variables_;
  problem.c = Eigen::Map<const Eigen::VectorXd>(objective_.data(), n);

  const int p = num_equalities();
  problem.b = Eigen::Map<const Eigen::VectorXd>(equality_rhs_.data(), p);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(equality_terms_.size());
  for (int i = 0; i < p; ++i) {
    for (int q = equality_begin_[i]; q < equality_begin_[i + 1]; ++q) {
      triplets.emplace_back(i, equality_terms_[q].var, equality_terms_[q].coef);
    }
  }
  problem.A.resize(p, n);
  problem.A.setFromTriplets(triplets.begin(), triplets.end());
  problem.A.makeCompressed();

  // A cone row means constant + sum(terms) in K, i.e. s = h - G x with h = constant, G = -terms.
  const int m = num_cone_rows();
  problem.h.resize(m);
  triplets.clear();
  triplets.reserve(terms_.size());
  int r = 0;
  auto emit = [&](const std::vector<Row>& rows) {
    for (const Row& row : rows) {
      for (int q = row.begin; q < row.end; ++q) triplets.emplace_back(r, terms_[q].var, -terms_[q].coef);
      problem.h[r] = row.constant;
      ++r;
    }
  };
  emit(orthant_rows_);
  emit(soc_rows_);
  emit(rotated_rows_);
  problem.G.resize(m, n);
  problem.G.setFromTriplets(triplets.begin(), triplets.end());
  problem.G.makeCompressed();

  problem.cones.num_nonnegative = static_cast<int>(orthant_rows_.size());
  problem.cones.soc_dims = soc_dims_;
  problem.cones.rotated_dims = rotated_dims_;
  return problem;
}

}  // namespace timeopt::conic
