// Cameras, board and poses shared by the rendered-image tests.
#pragma once

#include <cmath>
#include <vector>

#include "fgcal/core/se3.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_target.hpp"

namespace fgcal::vision::testing {

inline CameraModel radtanCamera() {
  return CameraModel(Projection::Pinhole, Distortion::RadTan, 500.0, 502.0, 319.3, 241.7,
                     {-0.28, 0.07, 1e-4, -2e-4}, 640, 480);
}

inline CameraModel equidistantCamera() {
  return CameraModel(Projection::Pinhole, Distortion::Equidistant, 420.0, 421.0, 322.4, 238.6,
                     {-0.01, 0.002, 0.0003, -0.0001}, 640, 480);
}

// Markers of 0.025 in squares of 0.04: the white gap around each corner
// (7.5 mm) leaves cornerSubPix a usable window out to 0.85 m. With 0.03
// markers the gap is 5 mm, the window shrinks to a few pixels and the worst
// oblique view at 0.85 m reaches 0.09 deg (measured; see vision report).
inline CharucoTarget testBoard() { return CharucoTarget{5, 7, 0.04, 0.025, "DICT_4X4_50"}; }

/// Board centre at `centre_cam` (camera frame), board tilted by roll/pitch/yaw
/// (radians) about its centre from facing the camera squarely.
inline SE3 boardPose(const CharucoTarget& t, const Vec3& centre_cam, double roll, double pitch,
                     double yaw) {
  const Vec3 c(0.5 * t.squares_x * t.square_size, 0.5 * t.squares_y * t.square_size, 0.0);
  const SO3 R = SO3::fromRpy(roll, pitch, yaw);
  return SE3(R, centre_cam - R.matrix() * c);
}

}  // namespace fgcal::vision::testing
