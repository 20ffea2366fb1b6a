#pragma once

// Convenience header: the whole public API of timeopt.

#include "timeopt/curve/bernstein.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/curve/polynomial_piece.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/errors.h"
#include "timeopt/version.h"
