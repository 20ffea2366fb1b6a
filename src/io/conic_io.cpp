#include "timeopt/io/conic_io.h"

#include <vector>

#include <nlohmann/json.hpp>

namespace timeopt {

std::string ConicResultToJson(const conic::CbfModel& model, const conic::Result& result, double solve_time_seconds,
                              int indent) {
  nlohmann::ordered_json j;
  j["status"] = conic::ToString(result.status);
  j["message"] = result.message;
  // Only an optimal solve has an objective value; otherwise x is a certificate or an unconverged
  // iterate.
  if (result.is_success())
    j["objective"] = model.FileObjective(result.primal_objective);
  else
    j["objective"] = nullptr;
  j["iterations"] = result.iterations;
  j["solve_time_ms"] = (solve_time_seconds >= 0.0 ? solve_time_seconds : result.solve_time_seconds) * 1e3;
  j["reduced_accuracy"] = result.reduced_accuracy;
  j["primal_residual"] = result.primal_residual;
  j["dual_residual"] = result.dual_residual;
  j["gap"] = result.gap;
  j["kkt_method"] = conic::ToString(result.kkt_method);
  j["num_variables"] = model.problem.num_variables();
  j["num_equalities"] = model.problem.num_equalities();
  j["num_cone_rows"] = model.problem.num_cone_rows();
  j["x"] = std::vector<double>(result.x.data(), result.x.data() + result.x.size());
  return j.dump(indent) + "\n";
}

}  // namespace timeopt
