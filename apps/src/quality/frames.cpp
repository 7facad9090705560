// The calibrated cameras against their URDF frames (frames.hpp).
#include "quality/frames.hpp"

#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/urdf_update.hpp"
#include "quality/words.hpp"

namespace fgcal::apps::quality {

namespace {

/// Every link below `link` in the tree, itself excluded.
void subtree(const kinematics::RobotModel& robot, const std::string& link, std::vector<std::string>& out) {
  for (const std::string& j : robot.link(link).child_joints) {
    const std::string& child = robot.joint(j).child_link;
    out.push_back(child);
    subtree(robot, child, out);
  }
}

/// The joint --urdf-out would rewrite for each camera with a frame, by camera;
/// empty when the plan is refused (a movable joint on the way, ...).
std::map<std::string, UrdfJointEdit> plannedEdits(const RigConfig& rig) {
  std::vector<UrdfCameraFrame> frames;
  for (const CameraConfig& c : rig.cameras)
    if (!c.frame.empty()) frames.push_back({c.name, c.frame, c.urdf_joint, "cameras[" + c.name + "]"});
  std::map<std::string, UrdfJointEdit> out;
  try {
    const UrdfUpdatePlan plan = planUrdfUpdate(readTextFile(rig.robot.urdf, "URDF (robot description)"),
                                               rig.robot.urdf, rig.robot.base_link, frames, rig.source);
    for (const UrdfJointEdit& e : plan.edits) out[e.camera] = e;
  } catch (const std::exception&) {
    out.clear();  // the shift is still shown; --urdf-out itself names the problem when asked
  }
  return out;
}

}  // namespace

std::vector<Finding> frameFindings(const RigConfig& rig, const kinematics::RobotModel& robot,
                                   const std::vector<CameraResult>& cameras) {
  std::vector<Finding> out;
  const std::map<std::string, UrdfJointEdit> edits = plannedEdits(rig);
  for (const CameraResult& cam : cameras) {
    const int index = rig.cameraIndex(cam.name);
    if (index < 0) continue;
    const CameraConfig& cfg = rig.cameras[static_cast<std::size_t>(index)];
    if (cfg.frame.empty() || !robot.hasLink(cfg.frame)) continue;
    SE3 T_base_frame;
    try {
      const kinematics::KinematicChain chain = robot.chain(rig.robot.base_link, cfg.frame);
      if (chain.numJoints() != 0) continue;  // a camera on a moving joint has no one URDF pose
      T_base_frame = chain.forward(VecX());
    } catch (const std::exception&) {
      continue;
    }
    const Vec6 d = T_base_frame.minus(cam.T_base_cam);
    const double mm = d.tail<3>().norm() * 1e3, deg = d.head<3>().norm() * 180.0 / M_PI;
    const bool far = mm > kFrameShiftCheckMm || deg > kFrameShiftCheckDeg;
    Finding f;
    f.check = "urdf_frame";
    f.severity = far ? Severity::Check : Severity::Note;
    f.fields = {"cameras[" + cam.name + "].frame"};
    f.message = "camera " + cam.name + " is " + fixed(mm, 1) + " mm, " + fixed(deg, 2) + " deg from its URDF frame " +
                cfg.frame;
    if (far)
      f.message += ", beyond what a camera's mounting tolerance moves it (" + fixed(kFrameShiftCheckMm, 0) + " mm, " +
                   fixed(kFrameShiftCheckDeg, 0) + " deg): frame: may name another camera's link, or a body frame "
                   "instead of the optical one (z forward, x right, y down). Check it before --urdf-out";
    if (const auto e = edits.find(cam.name); e != edits.end()) {
      std::vector<std::string> moved;
      subtree(robot, robot.joint(e->second.joint).child_link, moved);
      moved.insert(moved.begin(), robot.joint(e->second.joint).child_link);
      std::string others;
      for (const std::string& l : moved)
        if (l != cfg.frame) others += (others.empty() ? "" : ", ") + l;
      f.message += ". --urdf-out rewrites joint " + e->second.joint +
                   (others.empty() ? std::string(", which moves no other frame") : ", which also moves " + others);
    }
    f.estimate = {{"shift_mm", fixed(mm, 3)}, {"shift_deg", fixed(deg, 4)}};
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace fgcal::apps::quality
