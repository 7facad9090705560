// fgcal init --bag: cameras, topics and joint states found in a robot log
// (rig_init_bag.hpp).
#include "commands/init/rig_init_bag.hpp"

#include <algorithm>
#include <cctype>
#include <map>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/intrinsics_import.hpp"
#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps::detail {

namespace {

// "/cam0/camera_info" -> "/cam0"; "/camera_info" -> "".
std::string namespaceOf(const std::string& topic) {
  const auto slash = topic.rfind('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

// "/cam0" -> "cam0", "/robot/front" -> "robot_front", "" -> "camera".
std::string cameraNameOf(const std::string& ns) {
  std::string name;
  for (char c : ns) {
    if (c == '/') {
      if (!name.empty() && name.back() != '_') name += '_';
    } else {
      const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
      name += ok ? c : '_';
    }
  }
  while (!name.empty() && (name.back() == '_' || name.front() == '.')) {
    if (name.back() == '_') name.pop_back();
    else name.erase(0, 1);
  }
  return name.empty() ? "camera" : name;
}

// A decoded CameraInfo as the ROS camera_info YAML the importer reads, so the
// bag's intrinsics pass the same checks (no skew, extra coefficients zero) and
// conversion (plumb_bob -> radtan) as a camera_info file would. Numbers are
// written in their shortest round-trip form: the values stay exact.
std::string asCameraInfoYaml(const logs::CameraInfo& ci, const std::string& name) {
  std::vector<double> d = ci.d;
  std::string model = ci.distortion_model;
  if (d.empty()) {  // ROS: no coefficients means an undistorted (e.g. rectified) image
    d = {0.0, 0.0, 0.0, 0.0};
    model = "plumb_bob";
  }
  auto list = [](const double* v, std::size_t n) {
    std::string s = "[";
    for (std::size_t i = 0; i < n; ++i) s += (i ? ", " : "") + formatDouble(v[i]);
    return s + "]";
  };
  std::string s;
  s += "image_width: " + std::to_string(ci.width) + "\n";
  s += "image_height: " + std::to_string(ci.height) + "\n";
  s += "camera_name: " + yamlQuoted(name) + "\n";
  s += "camera_matrix: {rows: 3, cols: 3, data: " + list(ci.k.data(), 9) + "}\n";
  s += "distortion_model: " + yamlQuoted(model) + "\n";
  s += "distortion_coefficients: {rows: 1, cols: " + std::to_string(d.size()) + ", data: " + list(d.data(), d.size()) +
       "}\n";
  return s;
}

// Best image topic of a camera: raw before rectified (the intrinsics describe
// the unrectified image), uncompressed before compressed (lossless corners).
int imageTopicRank(const logs::TopicInfo& t) {
  const bool compressed = logs::messageKind(t.type) == logs::MessageKind::CompressedImage;
  const bool raw = t.name.find("raw") != std::string::npos;
  const bool rect = t.name.find("rect") != std::string::npos;
  return (rect ? 4 : 0) + (compressed ? 2 : 0) + (raw ? 0 : 1);
}

/// The bag's topics by the kind of message they carry.
struct TopicsByKind {
  std::vector<const logs::TopicInfo*> infos, images, joints;
};
TopicsByKind topicsByKind(const logs::BagReader& bag, const std::string& bag_path) {
  TopicsByKind k;
  for (const auto& t : bag.topics()) {
    switch (logs::messageKind(t.type)) {
      case logs::MessageKind::CameraInfo: k.infos.push_back(&t); break;
      case logs::MessageKind::Image:
      case logs::MessageKind::CompressedImage: k.images.push_back(&t); break;
      case logs::MessageKind::JointState: k.joints.push_back(&t); break;
      default: break;
    }
  }
  if (k.infos.empty()) {
    std::vector<std::string> names;
    for (const auto& t : bag.topics()) names.push_back(t.name + " (" + t.type + ")");
    throw InputError(bag_path, "",
                     "expected at least one sensor_msgs/CameraInfo topic to take the cameras from, found none "
                     "among: " + joinNames(names) + "; give the intrinsics with --camera-info NAME:FILE instead");
  }
  return k;
}

/// The first message of each CameraInfo topic; a warning for each topic without one.
std::map<std::string, logs::CameraInfo> firstCameraInfos(logs::BagReader& bag, const std::string& bag_path,
                                                         const TopicsByKind& k, std::vector<std::string>* warnings) {
  std::map<std::string, logs::CameraInfo> first;
  std::vector<std::string> wanted;
  for (const auto* t : k.infos) {
    if (t->message_count > 0) wanted.push_back(t->name);
    else warnings->push_back(bag_path + ": topic " + t->name + " has no message; no camera taken from it");
  }
  if (!wanted.empty()) {
    bag.read(wanted, [&](const logs::RawMessage& m) {
      if (!first.count(m.topic->name)) first.emplace(m.topic->name, logs::decodeCameraInfo(m, bag_path));
      return first.size() < wanted.size();
    });
  }
  return first;
}

/// The camera's URDF frame from its camera_info's frame_id, or why not.
void frameOf(const logs::CameraInfo& ci, const kinematics::RobotModel& model, InitCamera& ic) {
  ic.frame_hint = ci.header.frame_id.empty() ? ic.camera.name : ci.header.frame_id;
  if (ci.header.frame_id.empty()) {
    ic.frame_note = "its camera_info has an empty frame_id";
  } else if (model.hasLink(ci.header.frame_id)) {
    ic.frame = ci.header.frame_id;
    ic.frame_note = "the camera_info frame_id";
  } else {
    ic.frame_note = "the camera_info frame_id '" + ci.header.frame_id + "' is not a URDF link";
  }
}

/// The camera's image topic: the best of those under its namespace, the others named.
void imageTopicOf(const std::string& ns, const std::vector<const logs::TopicInfo*>& images, InitCamera& ic) {
  std::vector<const logs::TopicInfo*> mine;
  for (const auto* img : images)
    if (img->name.rfind(ns + "/", 0) == 0) mine.push_back(img);
  std::stable_sort(mine.begin(), mine.end(), [](const logs::TopicInfo* a, const logs::TopicInfo* b) {
    return imageTopicRank(*a) < imageTopicRank(*b);
  });
  if (mine.empty()) {
    ic.topic_note = "topic: left out: no Image or CompressedImage topic under " + (ns.empty() ? "/" : ns) +
                    "/; add the camera's image topic";
    return;
  }
  ic.topic = mine.front()->name;
  if (mine.size() > 1) {
    std::vector<std::string> others;
    for (std::size_t i = 1; i < mine.size(); ++i) others.push_back(mine[i]->name);
    ic.topic_note = "other image topics of this camera in the bag: " + joinNames(others);
  }
}

/// One camera from a CameraInfo topic's first message.
InitCamera cameraOf(const std::string& bag_path, const logs::TopicInfo& info, const logs::CameraInfo& ci,
                    const TopicsByKind& k, const kinematics::RobotModel& model) {
  const std::string ns = namespaceOf(info.name);
  InitCamera ic;
  const std::string name = cameraNameOf(ns);
  const std::string source = bag_path + ", topic " + info.name;
  auto cams = parseIntrinsics(asCameraInfoYaml(ci, name), source, kInitPixelSigma, name);
  ic.camera = cams.at(0);
  ic.source = source;
  ic.camera_info_topic = info.name;
  frameOf(ci, model, ic);
  imageTopicOf(ns, k.images, ic);
  return ic;
}

/// The joint states topic: /joint_states when there, else the busiest; the others named.
void jointStatesOf(const TopicsByKind& k, BagCameras& out) {
  const auto& joints = k.joints;
  if (joints.empty()) {
    out.joint_states_note = "joint_states_topic: left out: the bag has no sensor_msgs/JointState topic";
    return;
  }
  const auto pick =
      std::find_if(joints.begin(), joints.end(), [](const logs::TopicInfo* t) { return t->name == "/joint_states"; });
  const logs::TopicInfo* chosen =
      pick != joints.end() ? *pick : *std::max_element(joints.begin(), joints.end(), [](const auto* a, const auto* b) {
        return a->message_count < b->message_count;
      });
  out.joint_states_topic = chosen->name;
  if (joints.size() > 1) {
    std::vector<std::string> others;
    for (const auto* t : joints)
      if (t != chosen) others.push_back(t->name);
    out.joint_states_note = "other JointState topics in the bag: " + joinNames(others);
  }
}

}  // namespace

BagCameras camerasFromBag(const std::string& bag_path, const kinematics::RobotModel& model) {
  try {
    auto bag = logs::openBag(bag_path);
    BagCameras out;
    const TopicsByKind k = topicsByKind(*bag, bag_path);
    const auto first = firstCameraInfos(*bag, bag_path, k, &out.warnings);
    for (const auto* t : k.infos) {
      const auto it = first.find(t->name);
      if (it != first.end()) out.cameras.push_back(cameraOf(bag_path, *t, it->second, k, model));
    }
    if (out.cameras.empty())
      throw InputError(bag_path, "", "its CameraInfo topics hold no message; expected at least one per camera");
    jointStatesOf(k, out);
    return out;
  } catch (const logs::LogError& e) {
    throw InputError(e.file(), e.where(), e.detail());
  }
}

}  // namespace fgcal::apps::detail
