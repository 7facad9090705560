// Private to fgcal init: the cameras of a bag, found from its CameraInfo
// topics (rig_init_bag.cpp). Kept out of the public header so that users of
// fgcal::apps never see the robot-log module.
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/rig_init.hpp"
#include "fgcal/kinematics/robot_model.hpp"

namespace fgcal::apps::detail {

struct BagCameras {
  std::vector<InitCamera> cameras;
  std::string joint_states_topic;  ///< empty when the bag has no JointState topic
  std::string joint_states_note;   ///< a comment: other candidates, or none found
  std::vector<std::string> warnings;  ///< e.g. a CameraInfo topic without messages
};

/// One camera per sensor_msgs/CameraInfo topic, named from its namespace
/// (/cam0/camera_info -> cam0, /a/b/camera_info -> a_b), with the intrinsics of
/// its first message, its frame_id as `frame` when the URDF has that link, and
/// the Image or CompressedImage topic of the same namespace. Throws InputError
/// (a bag that cannot be read, no CameraInfo topic, a camera_info whose model
/// fgcal cannot represent), naming the bag and topic.
BagCameras camerasFromBag(const std::string& bag_path, const kinematics::RobotModel& model);

}  // namespace fgcal::apps::detail
