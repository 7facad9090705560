// Reading a CameraModel from an OpenCV FileStorage calibration file (the
// `camera_matrix` / `distortion_coefficients` / `image_width` / `image_height`
// files that cv::calibrateCamera tools write). Kalibr and ROS YAML files are
// not FileStorage files (docs/toolchain.md, gotcha 7); rig.yaml's camera fields go
// through CameraModel::fromKalibr instead.
#pragma once

#include <string>

#include "fgcal/vision/camera_model.hpp"

namespace fgcal::vision {

/// Pinhole + radtan from an OpenCV calibration file. Distortion vectors of 4
/// or 5 values (row or column) are taken as [k1 k2 p1 p2 (k3)]; longer ones
/// (rational, thin-prism, tilt) only when their extra terms are zero. When the
/// file has no image size, `width` and `height` must be given. Throws
/// VisionError naming the file and the field.
CameraModel readOpenCvCamera(const std::string& path, int width = 0, int height = 0);

}  // namespace fgcal::vision
