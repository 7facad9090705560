// The robot and camera side of the installed package: a leg's forward
// kinematics from fgcal's own URDF (fgcal::kinematics), and a ChArUco board
// rendered, detected and located by PnP (fgcal::vision). Linking this against
// the installed static libraries checks that find_package(fgcal) brings their
// dependencies (urdfdom, OpenCV with aruco) too.
#include <cmath>
#include <cstdio>

#include <fgcal/kinematics/chain.hpp>
#include <fgcal/kinematics/default_robot.hpp>
#include <fgcal/vision/board_renderer.hpp>
#include <fgcal/vision/charuco_detector.hpp>
#include <fgcal/vision/pnp.hpp>

int main() {
  using namespace fgcal;
  const kinematics::RobotModel robot = kinematics::loadDefaultRobot();
  const kinematics::KinematicChain leg =
      robot.chain(kinematics::defaultRobotBaseLink(), kinematics::defaultRobotFeet()[0]);
  const SE3 T_base_foot = leg.forward(VecX::Zero(leg.numJoints()));

  const vision::CameraModel camera(vision::Projection::Pinhole, vision::Distortion::RadTan, 500.0, 502.0, 319.3,
                                   241.7, {-0.28, 0.07, 1e-4, -2e-4}, 640, 480);
  const vision::CharucoTarget board{5, 7, 0.04, 0.025, "DICT_4X4_50"};
  // The board's centre 0.4 m in front of the camera, turned a little.
  const SO3 R = SO3::fromRpy(0.2, -0.1, 0.3);
  const SE3 T_cam_marker(R, Vec3(0.0, 0.0, 0.4) - R.matrix() * Vec3(0.1, 0.14, 0.0));
  const vision::CharucoDetection detection =
      vision::CharucoDetector(board).detect(vision::BoardRenderer(camera, board).render(T_cam_marker));
  if (!detection.ok()) {
    std::printf("FAILED: no board detected: %s\n", detection.message.c_str());
    return 1;
  }
  const vision::PoseEstimate pose = vision::estimatePose(camera, detection);
  const double gap_mm = 1e3 * (pose.T_cam_marker.translation() - T_cam_marker.translation()).norm();
  std::printf("%s: foot %.3f m from the base over %d joints; %zu corners, board found %.3f mm off\n",
              pose.converged && gap_mm < 1.0 ? "modules ok" : "FAILED", T_base_foot.translation().norm(),
              leg.numJoints(), detection.ids.size(), gap_mm);
  return pose.converged && gap_mm < 1.0 ? 0 : 1;
}
