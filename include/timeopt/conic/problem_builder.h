#pragma once
// Row-by-row construction of a conic Problem (see problem.h) from affine expressions.
//
// Variables are free; bounds and cones are added as constraints. Cones may be added in any order:
// Build() places the rows of G as the ConeSpec requires (orthant rows, then second-order cones, then
// rotated cones, each group in the order it was added). Build() assembles the sparse matrices from
// triplets in time linear in the number of non-zeros; no dense matrix is ever formed. Repeated terms
// on the same variable in one row are summed.

#include <vector>

#include "timeopt/conic/problem.h"

namespace timeopt::conic {

/// One term coef * x[var] of a linear expression.
struct Term {
  int var;
  double coef;
};

/// An affine expression sum(coef * x[var]) + constant.
struct AffineExpr {
  std::vector<Term> terms;
  double constant = 0.0;
};

class ProblemBuilder {
 public:
  /// Adds n free variables (n >= 0) and returns the index of the first one.
  int AddVariables(int n);

  /// Adds coef to the objective coefficient of x[var].
  void SetObjectiveCoefficient(int var, double coef);

  /// Adds the equality sum(coef * x[var]) = rhs.
  void AddEquality(const std::vector<Term>& terms, double rhs);

  /// Adds the inequality sum(coef * x[var]) <= upper (one orthant row).
  void AddLessEqual(const std::vector<Term>& terms, double upper);

  /// Adds e(x) >= 0 (one orthant row).
  void AddNonnegative(const AffineExpr& e);

  /// Adds rows[0](x) >= ||(rows[1](x), ..., rows[d-1](x))||_2, d = rows.size() >= 1.
  void AddSecondOrderCone(const std::vector<AffineExpr>& rows);

  /// Adds 2 rows[0](x) rows[1](x) >= ||(rows[2](x), ..., rows[d-1](x))||_2^2 with rows[0](x) >= 0 and
  /// rows[1](x) >= 0, d = rows.size() >= 2.
  void AddRotatedCone(const std::vector<AffineExpr>& rows);

  int num_variables() const { return num_variables_; }
  int num_equalities() const { return static_cast<int>(equality_rhs_.size()); }
  /// Number of rows of G added so far.
  int num_cone_rows() const;

  /// Assembles the Problem. Throws std::invalid_argument if a term names a variable that does not
  /// exist (the check happens when the term is added). Cost: linear in the number of terms.
  Problem Build() const;

 private:
  struct Row {
    int begin;        // first term in terms_
    int end;          // one past the last term
    double constant;  // the row means constant + sum(terms) in K (h = constant, G = -terms)
  };
  void CheckVariable(int var, const char* where) const;
  void CheckTerms(const std::vector<Term>& terms, const char* where) const;
  // Appends term_sign * terms to terms_; the row means constant + sum(appended terms) in K.
  Row AppendRow(const std::vector<Term>& terms, double term_sign, double constant);

  int num_variables_ = 0;
  std::vector<double> objective_;
  std::vector<Term> terms_;  // all terms of all rows
  std::vector<Term> equality_terms_;
  std::vector<int> equality_begin_{0};  // row i uses equality_terms_[begin[i], begin[i+1])
  std::vector<double> equality_rhs_;
  std::vector<Row> orthant_rows_;
  std::vector<Row> soc_rows_;  // all rows of all second-order cones
  std::vector<int> soc_dims_;
  std::vector<Row> rotated_rows_;
  std::vector<int> rotated_dims_;
};

}  // namespace timeopt::conic
