#include "timeopt/conic/cbf.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <locale>
#include <new>
#include <set>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "timeopt/conic/problem_builder.h"

namespace timeopt::conic {
namespace {

// Largest number of variables, rows or entries a file may declare. Arrays of the declared sizes are
// allocated (about 20 bytes per row), so an absurd declaration in a tiny file would otherwise exhaust
// memory.
constexpr int kMaxSize = 10'000'000;
// Largest number of variables or constraint rows: the solver's workspace grows ~600 bytes per
// variable (a 62-byte file declaring 1e7 variables reached 5.9 GB), so 2e6 caps it near 1.2 GB;
// the benchmarks go to 1e5.
constexpr int kMaxVariablesOrRows = 2'000'000;

// The domains of a block of variables or constraint rows.
enum class Domain { kFree, kNonnegative, kNonpositive, kZero, kSoc, kRotated };

struct Block {
  Domain domain;
  int dim;
};

// Lines of the file without comments and blank lines, each with its 1-based number for messages.
class LineReader {
 public:
  explicit LineReader(std::istream& in) : in_(in) {}

  // The next content line; false at the end of the input.
  bool Next(std::string* line) {
    while (std::getline(in_, *line)) {
      ++number_;
      if (!line->empty() && line->back() == '\r') line->pop_back();
      const auto first = line->find_first_not_of(" \t");
      if (first == std::string::npos || (*line)[first] == '#') continue;
      return true;
    }
    return false;
  }

  // The next content line, split into whitespace-separated fields; throws at the end of the input.
  std::vector<std::string> Fields(const std::string& what) {
    std::string line;
    if (!Next(&line)) Fail("the file ends where " + what + " was expected");
    std::istringstream s(line);
    std::vector<std::string> fields;
    for (std::string f; s >> f;) fields.push_back(f);
    return fields;
  }

  [[noreturn]] void Fail(const std::string& message) const {
    throw std::invalid_argument("CBF line " + std::to_string(number_) + ": " + message);
  }

  long long Integer(const std::string& text, const std::string& what) const {
    std::size_t used = 0;
    long long v = 0;
    try {
      v = std::stoll(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size()) Fail(what + ": expected an integer, got '" + text + "'");
    return v;
  }

  // An integer in [0, limit).
  int Index(const std::string& text, long long limit, const std::string& what) const {
    const long long v = Integer(text, what);
    if (v < 0 || v >= limit) {
      Fail(what + " " + text + " is out of range [0, " + std::to_string(limit) + ")");
    }
    return static_cast<int>(v);
  }

  // A size or count in [0, kMaxSize].
  int Count(const std::string& text, const std::string& what) const { return Index(text, kMaxSize + 1LL, what); }

  double Real(const std::string& text, const std::string& what) const {
    // strtod, not stod: stod rejects subnormal values (ERANGE on underflow), which WriteCbf writes.
    const char* begin = text.c_str();
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(begin, &end);
    if (end == begin || *end != '\0') Fail(what + ": expected a number, got '" + text + "'");
    if (!std::isfinite(v)) {
      Fail(what + " " + (errno == ERANGE ? "'" + text + "' is out of the range of a double" : "is not finite"));
    }
    return v;
  }

  void ExpectFields(const std::vector<std::string>& f, std::size_t n, const std::string& what) const {
    if (f.size() != n) {
      Fail(what + ": expected " + std::to_string(n) + " fields, got " + std::to_string(f.size()));
    }
  }

 private:
  std::istream& in_;
  int number_ = 0;
};

// "n k" followed by k lines "DOMAIN dim" whose dims add up to n.
std::vector<Block> ReadBlocks(LineReader& reader, const std::string& keyword, int* total) {
  const auto head = reader.Fields(keyword + " sizes");
  reader.ExpectFields(head, 2, keyword);
  *total = reader.Count(head[0], keyword + " size");
  const int count = reader.Count(head[1], keyword + " number of cones");
  std::vector<Block> blocks;
  long long sum = 0;
  for (int k = 0; k < count; ++k) {
    const auto f = reader.Fields(keyword + " cone");
    reader.ExpectFields(f, 2, keyword + " cone");
    const std::string& name = f[0];
    const int dim = reader.Count(f[1], keyword + " cone dimension");
    Block b{Domain::kFree, dim};
    if (name == "F") {
      b.domain = Domain::kFree;
    } else if (name == "L+") {
      b.domain = Domain::kNonnegative;
    } else if (name == "L-") {
      b.domain = Domain::kNonpositive;
    } else if (name == "L=") {
      b.domain = Domain::kZero;
    } else if (name == "Q") {
      b.domain = Domain::kSoc;
    } else if (name == "QR") {
      b.domain = Domain::kRotated;
    } else {
      reader.Fail("cone '" + name + "' is not supported (supported: F, L+, L-, L=, Q, QR)");
    }
    if (b.domain == Domain::kSoc && dim < 1) reader.Fail("a Q cone needs dimension >= 1");
    if (b.domain == Domain::kRotated && dim < 2) reader.Fail("a QR cone needs dimension >= 2");
    sum += dim;
    blocks.push_back(b);
  }
  if (sum != *total) {
    reader.Fail(keyword + " cones add up to " + std::to_string(sum) + ", not " + std::to_string(*total));
  }
  return blocks;
}

// Adds "e in domain" for one scalar row (L+, L-, L=; nothing for F). May change e.
void AddScalarRow(Domain domain, AffineExpr& e, ProblemBuilder& builder) {
  switch (domain) {
    case Domain::kNonnegative:
      builder.AddNonnegative(e);
      return;
    case Domain::kNonpositive:
      for (Term& t : e.terms) t.coef = -t.coef;
      e.constant = -e.constant;
      builder.AddNonnegative(e);
      return;
    case Domain::kZero:
      builder.AddEquality(e.terms, -e.constant);
      return;
    default:
      return;
  }
}

// Adds one block, whose row i fill(i, &expr) writes. Scalar domains go row by row, so that a large
// block needs no array of its rows; a cone needs its rows together.
template <typename Fill>
void AddBlock(const Block& block, const Fill& fill, std::vector<AffineExpr>& cone, ProblemBuilder& builder) {
  if (block.domain == Domain::kFree) return;
  if (block.domain == Domain::kSoc || block.domain == Domain::kRotated) {
    cone.resize(static_cast<std::size_t>(block.dim));
    for (int i = 0; i < block.dim; ++i) fill(i, &cone[static_cast<std::size_t>(i)]);
    if (block.domain == Domain::kSoc)
      builder.AddSecondOrderCone(cone);
    else
      builder.AddRotatedCone(cone);
    return;
  }
  AffineExpr e;
  for (int i = 0; i < block.dim; ++i) {
    fill(i, &e);
    AddScalarRow(block.domain, e, builder);
  }
}

CbfModel ReadCbfUnguarded(std::istream& in) {
  LineReader reader(in);
  CbfModel model;
  bool have_version = false, have_var = false, have_con = false;
  std::set<std::string> seen;
  int n = 0, m = 0;
  std::vector<Block> var_blocks, con_blocks;
  std::vector<std::pair<int, double>> objective;
  // ACOORD as (row, column, value) and BCOORD as (row, value), grouped by row after reading.
  struct Entry {
    int row, col;
    double value;
  };
  std::vector<Entry> a_entries;
  std::vector<std::pair<int, double>> b_entries;

  std::string line;
  while (reader.Next(&line)) {
    std::istringstream s(line);
    std::string keyword, extra;
    s >> keyword;
    if (s >> extra) reader.Fail("expected a keyword alone on its line, got '" + line + "'");
    if (!have_version && keyword != "VER") reader.Fail("the file must start with VER");
    if (!seen.insert(keyword).second) reader.Fail(keyword + " given twice");
    if (keyword == "VER") {
      const auto f = reader.Fields("the version");
      reader.ExpectFields(f, 1, "VER");
      const long long v = reader.Integer(f[0], "VER");
      if (v < 1 || v > 4) reader.Fail("CBF version " + f[0] + " is not supported (1 to 4 are)");
      have_version = true;
    } else if (keyword == "OBJSENSE") {
      const auto f = reader.Fields("MIN or MAX");
      reader.ExpectFields(f, 1, "OBJSENSE");
      if (f[0] != "MIN" && f[0] != "MAX") reader.Fail("OBJSENSE must be MIN or MAX, got '" + f[0] + "'");
      model.maximize = f[0] == "MAX";
    } else if (keyword == "VAR") {
      var_blocks = ReadBlocks(reader, "VAR", &n);
      if (n > kMaxVariablesOrRows)
        reader.Fail("VAR declares " + std::to_string(n) + " variables, above the 2000000 supported");
      have_var = true;
    } else if (keyword == "CON") {
      con_blocks = ReadBlocks(reader, "CON", &m);
      if (m > kMaxVariablesOrRows)
        reader.Fail("CON declares " + std::to_string(m) + " rows, above the 2000000 supported");
      have_con = true;
    } else if (keyword == "OBJACOORD" || keyword == "ACOORD" || keyword == "BCOORD") {
      if (!have_var) reader.Fail(keyword + " before VAR");
      if (keyword != "OBJACOORD" && !have_con) reader.Fail(keyword + " before CON");
      const auto head = reader.Fields(keyword + " count");
      reader.ExpectFields(head, 1, keyword);
      const int count = reader.Count(head[0], keyword + " count");
      for (int k = 0; k < count; ++k) {
        if (keyword == "OBJACOORD") {
          const auto f = reader.Fields("an OBJACOORD entry");
          reader.ExpectFields(f, 2, "OBJACOORD entry");
          objective.push_back({reader.Index(f[0], n, "variable"), reader.Real(f[1], "coefficient")});
        } else if (keyword == "ACOORD") {
          const auto f = reader.Fields("an ACOORD entry");
          reader.ExpectFields(f, 3, "ACOORD entry");
          const int row = reader.Index(f[0], m, "constraint row");
          const int col = reader.Index(f[1], n, "variable");
          a_entries.push_back({row, col, reader.Real(f[2], "coefficient")});
        } else {
          const auto f = reader.Fields("a BCOORD entry");
          reader.ExpectFields(f, 2, "BCOORD entry");
          const int row = reader.Index(f[0], m, "constraint row");
          b_entries.push_back({row, reader.Real(f[1], "constant")});
        }
      }
    } else if (keyword == "OBJBCOORD") {
      const auto f = reader.Fields("the objective constant");
      reader.ExpectFields(f, 1, "OBJBCOORD");
      model.objective_constant = reader.Real(f[0], "objective constant");
    } else if (keyword == "INT" || keyword == "PSDVAR" || keyword == "PSDCON" || keyword == "FCOORD" ||
               keyword == "HCOORD" || keyword == "DCOORD" || keyword == "OBJFCOORD" || keyword == "POWCONES" ||
               keyword == "POW*CONES" || keyword == "CHANGE") {
      reader.Fail(keyword +
                  " is not supported: the solver handles continuous problems over linear, "
                  "second-order and rotated second-order cones only");
    } else {
      reader.Fail("unknown keyword '" + keyword + "'");
    }
  }
  if (!have_version) throw std::invalid_argument("CBF: the input is empty (no VER)");
  if (!have_var) throw std::invalid_argument("CBF: no VAR section");

  ProblemBuilder builder;
  builder.AddVariables(n);
  for (const auto& [var, coef] : objective) {
    builder.SetObjectiveCoefficient(var, model.maximize ? -coef : coef);
  }
  std::vector<AffineExpr> cone;
  int first = 0;
  for (const Block& block : var_blocks) {
    AddBlock(
        block,
        [first](int i, AffineExpr* e) {
          e->terms.assign(1, Term{first + i, 1.0});
          e->constant = 0.0;
        },
        cone, builder);
    first += block.dim;
  }

  // Constraint rows: entries grouped by row (a counting sort keeps their order within a row).
  std::vector<int> row_start(static_cast<std::size_t>(m) + 1, 0);
  for (const Entry& e : a_entries) ++row_start[static_cast<std::size_t>(e.row) + 1];
  for (int r = 0; r < m; ++r) row_start[static_cast<std::size_t>(r) + 1] += row_start[static_cast<std::size_t>(r)];
  std::vector<Term> terms(a_entries.size());
  {
    std::vector<int> next(row_start.begin(), row_start.end() - 1);
    for (const Entry& e : a_entries)
      terms[static_cast<std::size_t>(next[static_cast<std::size_t>(e.row)]++)] = {e.col, e.value};
  }
  a_entries = {};
  std::vector<double> b(static_cast<std::size_t>(m), 0.0);
  for (const auto& [row, value] : b_entries) b[static_cast<std::size_t>(row)] += value;
  first = 0;
  for (const Block& block : con_blocks) {
    AddBlock(
        block,
        [&, first](int i, AffineExpr* e) {
          const auto r = static_cast<std::size_t>(first + i);
          e->terms.assign(terms.begin() + row_start[r], terms.begin() + row_start[r + 1]);
          e->constant = b[r];
        },
        cone, builder);
    first += block.dim;
  }
  model.problem = builder.Build();
  try {
    model.problem.Validate();  // repeated entries are summed, and a sum can overflow
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("CBF: ") + e.what());
  }
  return model;
}

}  // namespace

CbfModel ReadCbf(std::istream& in) {
  try {
    return ReadCbfUnguarded(in);
  } catch (const std::bad_alloc&) {
    throw std::invalid_argument("CBF: the problem the file declares does not fit in memory");
  }
}

void WriteCbf(const Problem& problem, std::ostream& destination) {
  problem.Validate();
  const int n = problem.num_variables(), p = problem.num_equalities(), m = problem.num_cone_rows();
  const ConeSpec& k = problem.cones;
  // Formatted here, not in the caller's stream, whose flags (std::fixed) or locale (digit grouping)
  // would change the numbers.
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out.precision(17);

  out << "# timeopt: the first " << p << " rows are A x - b (L=), the other " << m << " are h - G x\n"
      << "VER\n3\n\nOBJSENSE\nMIN\n\nVAR\n"
      << n << " " << (n > 0 ? 1 : 0) << "\n";
  if (n > 0) out << "F " << n << "\n";

  const int blocks =
      (p > 0 ? 1 : 0) + (k.num_nonnegative > 0 ? 1 : 0) + static_cast<int>(k.soc_dims.size() + k.rotated_dims.size());
  out << "\nCON\n" << p + m << " " << blocks << "\n";
  if (p > 0) out << "L= " << p << "\n";
  if (k.num_nonnegative > 0) out << "L+ " << k.num_nonnegative << "\n";
  for (int d : k.soc_dims) out << "Q " << d << "\n";
  for (int d : k.rotated_dims) out << "QR " << d << "\n";

  int nonzero_c = 0;
  for (int j = 0; j < n; ++j) nonzero_c += problem.c[j] != 0.0 ? 1 : 0;
  out << "\nOBJACOORD\n" << nonzero_c << "\n";
  for (int j = 0; j < n; ++j) {
    if (problem.c[j] != 0.0) out << j << " " << problem.c[j] << "\n";
  }

  out << "\nACOORD\n" << problem.A.nonZeros() + problem.G.nonZeros() << "\n";
  for (int j = 0; j < problem.A.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(problem.A, j); it; ++it) {
      out << it.row() << " " << j << " " << it.value() << "\n";
    }
  }
  for (int j = 0; j < problem.G.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(problem.G, j); it; ++it) {
      out << p + it.row() << " " << j << " " << -it.value() << "\n";
    }
  }

  int nonzero_b = 0;
  for (int i = 0; i < p; ++i) nonzero_b += problem.b[i] != 0.0 ? 1 : 0;
  for (int i = 0; i < m; ++i) nonzero_b += problem.h[i] != 0.0 ? 1 : 0;
  out << "\nBCOORD\n" << nonzero_b << "\n";
  for (int i = 0; i < p; ++i) {
    if (problem.b[i] != 0.0) out << i << " " << -problem.b[i] << "\n";
  }
  for (int i = 0; i < m; ++i) {
    if (problem.h[i] != 0.0) out << p + i << " " << problem.h[i] << "\n";
  }
  destination << out.str();
  if (!destination) throw std::runtime_error("CBF: writing failed");
}

}  // namespace timeopt::conic
