// Importer of camera intrinsics written by other tools, so a user can build
// rig.yaml's cameras from an existing calibration instead of retyping numbers:
// a Kalibr camchain (cam0:, cam1:, ... with camera_model, distortion_model,
// intrinsics, distortion_coeffs, resolution), a ROS camera_info YAML
// (camera_matrix, distortion_model plumb_bob | rational_polynomial |
// equidistant, distortion_coefficients, image_width/height) or an OpenCV
// FileStorage YAML (camera_matrix: !!opencv-matrix, distortion_coefficients,
// image_width/height).
//
// fgcal's pinhole models are radtan [k1 k2 p1 p2], equidistant [k1..k4] and
// none: OpenCV/ROS coefficients beyond p2 (k3, k4..k6, thin prism, tilt) are
// accepted only when they are zero; otherwise InputError says which one is not
// and why, rather than silently dropping it.
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/rig_config.hpp"

namespace fgcal::apps {

/// Reads the file at `path`; every camera gets `pixel_sigma` (these files do
/// not hold one). Cameras are named by the file (Kalibr's cam0, cam1, ...,
/// ROS camera_name), else `default_name`. Throws InputError naming the file and
/// field.
std::vector<CameraConfig> importIntrinsics(const std::string& path, double pixel_sigma,
                                           const std::string& default_name = "cam0");
/// The same from text; `source_name` names it in messages.
std::vector<CameraConfig> parseIntrinsics(const std::string& yaml_text, const std::string& source_name,
                                          double pixel_sigma, const std::string& default_name = "cam0");

}  // namespace fgcal::apps
