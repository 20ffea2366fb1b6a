// The exit code of every library status, in one place (see commands.h).

#include "commands.h"

namespace timeopt::cli {

int ExitCodeFor(TemporalStatus status) {
  switch (status) {
    case TemporalStatus::kOptimal:
      return kExitOk;
    case TemporalStatus::kInfeasible:
      return kExitInfeasible;
    case TemporalStatus::kInvalidInput:
      return kExitInvalidInput;
    case TemporalStatus::kIterationLimit:
    case TemporalStatus::kNumericalError:
      return kExitFailure;
  }
  return kExitFailure;
}

int ExitCodeFor(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSuccess:
      return kExitOk;
    case PlanStatus::kInvalidInput:
    case PlanStatus::kStartOutsideMap:
    case PlanStatus::kGoalOutsideMap:
    case PlanStatus::kStartInCollision:
    case PlanStatus::kGoalInCollision:
      return kExitInvalidInput;
    case PlanStatus::kUnreachable:
    case PlanStatus::kTemporalInfeasible:
      return kExitInfeasible;
    case PlanStatus::kSearchLimit:
    case PlanStatus::kCollision:
    case PlanStatus::kSpatialFailure:
    case PlanStatus::kTemporalFailure:
      return kExitFailure;
  }
  return kExitFailure;
}

int ExitCodeFor(conic::Status status) {
  switch (status) {
    case conic::Status::kOptimal:
      return kExitOk;
    case conic::Status::kPrimalInfeasible:
      return kExitInfeasible;
    default:
      return kExitFailure;  // unbounded (dual infeasible), limits, numerical trouble
  }
}

}  // namespace timeopt::cli
