#pragma once
// PLY point clouds (ASCII): x y z, label, and an RGB color per point.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/label.h"

namespace idyvins::io {

/// One labelled point: label 0 static, 1 eliminated-dynamic, 2 confirmed-dynamic.
struct LabelledPoint {
  Eigen::Vector3d p;
  int label = 0;
};

/// The PLY label of a map point's label (static 0, eliminated 1, confirmed dynamic 2).
int plyLabel(FeatureLabel label);

/// Writes an ASCII PLY with properties x y z label red green blue (static gray,
/// eliminated red, confirmed dynamic orange). Throws InputError if unwritable.
void writePly(const std::string& path, const std::vector<LabelledPoint>& points);

/// Reads a PLY that writePly wrote (ASCII; x y z label red green blue). Throws InputError with
/// the file and line on anything else: another format, a short or malformed vertex line, a label
/// outside 0..2, fewer or more vertices than the header says.
std::vector<LabelledPoint> readPly(const std::string& path);

}  // namespace idyvins::io
