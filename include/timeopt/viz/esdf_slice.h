#pragma once

// A picture of a horizontal slice of an ESDF: the signed distance at height z, coloured from the
// obstacle surface (dark) to far away (bright), with obstacle voxels (distance < 0) in black and
// a colour bar. Written as PNG with cairo.

#include <string>

#include "timeopt/map/esdf.h"

namespace timeopt {

struct SliceImageOptions {
  int pixels_per_voxel = 4;   // image pixels per voxel edge (lowered for wide boxes)
  int max_image_size = 4000;  // largest width or height of the map part, pixels
  double max_distance = 0.0;  // distance at which the colour saturates, metres; 0: the slice's max
};

// Samples the field at every voxel centre of the box in the plane z = `height` (metres) and writes
// the image. Throws std::invalid_argument when the height is outside the ESDF's box or an option
// is invalid, timeopt::FileError when the file cannot be written.
void WriteEsdfSlicePng(const Esdf& esdf, double height, const std::string& path,
                       const SliceImageOptions& options = SliceImageOptions());

}  // namespace timeopt
