// The quadrotor's own limits as command-line options (commands.h).

#include <cmath>
#include <stdexcept>
#include <string>

#include "commands.h"

namespace timeopt::cli {

void AddQuadrotorLimitOptions(CLI::App* sub, QuadrotorLimitArgs* args) {
  sub->add_option("--max-speed", args->max_speed, "Speed limit ||v||, m/s (with or instead of --max-velocity)");
  sub->add_option("--max-acceleration-norm", args->max_acceleration_norm, "Acceleration limit ||a||, m/s^2");
  sub->add_option("--max-thrust", args->max_thrust, "Largest mass-normalized thrust ||a + g e3||, m/s^2");
  sub->add_option("--min-thrust", args->min_thrust, "Smallest mass-normalized thrust (a_z + g), m/s^2");
  sub->add_option("--max-tilt", args->max_tilt, "Largest tilt of the thrust from the vertical, rad");
}

void ApplyQuadrotorLimits(const QuadrotorLimitArgs& args, VehicleLimits* limits) {
  const auto set = [](const std::optional<double>& value, const char* option, std::optional<double>* field) {
    if (!value) return;
    if (!std::isfinite(*value) || *value < 0.0) {
      throw std::invalid_argument(std::string(option) + ": expected a finite number >= 0, got " +
                                  std::to_string(*value));
    }
    *field = *value;
  };
  set(args.max_speed, "--max-speed", &limits->max_speed);
  set(args.max_acceleration_norm, "--max-acceleration-norm", &limits->max_acceleration_norm);
  set(args.max_thrust, "--max-thrust", &limits->max_thrust);
  set(args.min_thrust, "--min-thrust", &limits->min_thrust);
  set(args.max_tilt, "--max-tilt", &limits->max_tilt);
}

}  // namespace timeopt::cli
