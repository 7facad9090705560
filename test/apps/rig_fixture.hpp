// A valid rig.yaml used as the starting point of the rig and dataset tests;
// each error case changes one thing in it.
#pragma once

#include <string>

namespace fgcal::apps::test {

inline const std::string kValidRig = R"(robot:
  urdf: robot.urdf
  base_link: base_link
  marker_link: lf_foot
  T_link_marker:
    [[1,0,0,0],[0,1,0,0],[0,0,1,0.02],[0,0,0,1]]
  mount_sigma: [0.002, 0.01]
  encoder_sigma: 0.001
target:
  type: charuco
  squares_x: 5
  squares_y: 7
  square_size: 0.04
  marker_size: 0.03
  dictionary: DICT_4X4_50
cameras:
  - name: cam0
    camera_model: pinhole
    distortion_model: radtan
    intrinsics: [600, 601, 320, 240]
    distortion_coeffs: [0.1, -0.05, 0.001, 0.002]
    resolution: [640, 480]
    pixel_sigma: 0.5
  - name: cam1
    camera_model: pinhole
    distortion_model: equidistant
    intrinsics: [400, 400, 330.5, 250.25]
    distortion_coeffs: [0.1, 0.01, 0.001, 0.0001]
    resolution: [752, 480]
    pixel_sigma: 0.7
    T_base_cam_guess: [[0,0,1,0.3],[-1,0,0,0],[0,-1,0,0.1],[0,0,0,1]]
sync_tolerance_ms: 2.5
)";

}  // namespace fgcal::apps::test
