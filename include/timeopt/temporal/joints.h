#pragma once

// What a temporal solve found at the joints of a curve (TemporalResult::joints): whether the
// vehicle keeps its speed through a joint, scales it by the tangents' length ratio, or stops.

#include <array>
#include <string>

namespace timeopt {

enum class JointType {
  kC1,    // tangents equal: b = sdot^2 continuous (eq. 43)
  kG1,    // tangents parallel, lengths differ: b scaled by the squared length ratio (eq. 42)
  kStop,  // tangents turn or vanish: the vehicle stops, b = 0 on both sides
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<JointType, 3> kJointTypes = {
    JointType::kC1,
    JointType::kG1,
    JointType::kStop,
};
// "C1", "G1", "stop".
const char* ToString(JointType type);
// The enumerator named `text` (as ToString writes it) into *type; false when none is.
bool FromString(const std::string& text, JointType* type);

struct JointInfo {
  int joint = 0;  // between piece `joint` and `joint + 1`
  JointType type = JointType::kC1;
  double speed_ratio = 1.0;  // |f'_i(1)| / |f'_{i+1}(0)| (1 for C1; 0 for a vanishing tangent)
  double angle = 0.0;        // angle between the tangents, radians
  // For a stop, why the vehicle must stop there (empty otherwise): "the tangent vanishes" (on the
  // side named, at most TemporalProblem::zero_tangent_tolerance: a piece of almost no length, or a
  // cusp), "the tangents turn" (a kink: angle above parallel_tolerance), or "the curvature jumps"
  // (jerk-limited: the acceleration across the path could not stay continuous at speed).
  std::string reason;
};

}  // namespace timeopt
