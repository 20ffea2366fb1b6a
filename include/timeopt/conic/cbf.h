#pragma once
// Reading and writing conic problems in the Conic Benchmark Format (CBF, the text format of the
// CBLIB library, read and written by MOSEK and other solvers), so that a problem can be handed to
// another solver, and a CBLIB instance solved by ours.
//
// The subset supported is the one our solver handles: scalar variables in the free (F), nonnegative
// (L+), nonpositive (L-) or zero (L=) domain, or in second-order (Q) or rotated second-order (QR)
// cones; affine constraint rows A x + b in the same cones; a linear objective with a constant, to be
// minimized or maximized. CBF's rotated cone, 2 u v >= ||w||^2 with u, v >= 0, is ours, so QR maps
// one to one. Integer variables, semidefinite and exponential or power cones are rejected by name.

#include <iosfwd>

#include "timeopt/conic/problem.h"

namespace timeopt::conic {

/// A problem read from CBF, in the solver's minimization form.
struct CbfModel {
  /// minimize problem.c'x subject to the constraints. Variable domains become rows: L= of A, the
  /// others of G.
  Problem problem;
  /// True if the file asked to maximize: problem.c is then the negated objective.
  bool maximize = false;
  /// The objective's constant term (OBJBCOORD), in the file's sense.
  double objective_constant = 0.0;

  /// The file's objective value at a solution x of `problem` with value problem.c'x = min_value.
  double FileObjective(double min_value) const { return (maximize ? -min_value : min_value) + objective_constant; }
};

/// Parses CBF text (versions 1 to 4; only the subset above). Entries repeated within a section are
/// summed. Throws std::invalid_argument naming the line and what is wrong (unknown or unsupported
/// keyword, a section given twice, a count or index out of range, cone sizes not adding up, a number
/// that is not finite, a size above 1e7, a problem that does not fit in memory). Cost: linear in the
/// file's size and the declared sizes.
CbfModel ReadCbf(std::istream& in);

/// Writes `problem` as CBF version 3: n free variables; the rows A x - b in L= followed by h - G x in
/// the cones of problem.cones (L+, then Q, then QR), i.e. exactly A x = b and G x + s = h, s in K.
/// Numbers are written with 17 significant digits, so ReadCbf gives back every value bit for bit
/// (zeros are not written; a -0 reads back as 0). Throws std::invalid_argument if the problem fails
/// Problem::Validate(), std::runtime_error if the stream fails.
void WriteCbf(const Problem& problem, std::ostream& out);

}  // namespace timeopt::conic
