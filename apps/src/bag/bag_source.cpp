// The one pass over a robot bag (bag_source.hpp).
#include "bag/bag_source.hpp"

#include <algorithm>
#include <climits>

#include "fgcal/apps/bag_messages.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/logs/log_error.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps {

namespace {

std::string messageWhere(const logs::RawMessage& m, std::int64_t stamp_ns) {
  return "topic " + m.topic->name + ", message " + std::to_string(m.index) + " (stamp " + std::to_string(stamp_ns) +
         ")";
}

std::string topicList(const logs::BagReader& bag) {
  std::vector<std::string> names;
  for (const auto& t : bag.topics()) names.push_back(t.name + " (" + t.type + ")");
  return names.empty() ? std::string("none") : detail::joinNames(names);
}

/// The topic rig.yaml's `field` names, checked to be in the bag and of one
/// of `kinds`: an error names rig.yaml's field (that is what to edit), with
/// the bag's topics of those kinds closest to it.
const logs::TopicInfo& requireTopic(const logs::BagReader& bag, const std::string& topic,
                                    const std::vector<logs::MessageKind>& kinds, const RigConfig& rig,
                                    const std::string& field) {
  std::vector<std::string> want, fitting;
  for (auto k : kinds) want.push_back(logs::messageKindName(k));
  for (const auto& info : bag.topics())
    if (std::find(kinds.begin(), kinds.end(), logs::messageKind(info.type)) != kinds.end()) fitting.push_back(info.name);
  std::string kinds_text;
  for (std::size_t i = 0; i < want.size(); ++i) kinds_text += (i == 0 ? "" : i + 1 == want.size() ? " or " : ", ") + want[i];
  const std::string expected = "expected a " + kinds_text + " topic of " + bag.path();
  const logs::TopicInfo* t = bag.findTopic(topic);
  if (!t)
    throw rigFieldError(rig, field,
                        expected + ", got '" + topic + "', which is not in the bag" +
                            (fitting.empty() ? "; the bag has no such topic; its topics: " + topicList(bag)
                                             : closestNote(topic, fitting, "topics of that type")));
  if (std::find(kinds.begin(), kinds.end(), logs::messageKind(t->type)) == kinds.end())
    throw rigFieldError(rig, field,
                        expected + ", got '" + topic + "', whose type is " + t->type +
                            (fitting.empty() ? "" : closestNote(topic, fitting, "topics of that type")));
  return *t;
}

/// The joint table and the checks that need the whole bag read.
void finishScan(const std::string& file, const BagPlan& plan, const JointStateCollector& joints,
                const std::vector<std::size_t>& per_camera, BagScan& scan) {
  std::size_t duplicates = 0;
  scan.joints = joints.finish(&duplicates);
  const std::string jwhere = "topic " + plan.joints_topic;
  if (duplicates)
    scan.warnings.push_back(file + ": " + jwhere + ": " + std::to_string(duplicates) +
                            " message(s) share their header stamp with another; merged into one sample per stamp "
                            "(the message recorded later wins for the joints both carry)");
  if (joints.withoutPositions())
    scan.warnings.push_back(file + ": " + jwhere + ": " + std::to_string(joints.withoutPositions()) +
                            " message(s) without positions, ignored");
  if (scan.joints.stamps_ns.empty())
    throw InputError(file, jwhere, "no joint positions in the bag; expected sensor_msgs/JointState messages with "
                                   "positions over the time of the images");
  for (std::size_t c = 0; c < per_camera.size(); ++c)
    if (per_camera[c] == 0)
      throw InputError(file, "topic " + plan.image_topics[c],
                       "no image messages on this topic; expected the images of the camera that rig.yaml gives it");
  const std::int64_t j0 = scan.joints.stamps_ns.front(), j1 = scan.joints.stamps_ns.back();
  if (j1 < scan.first_image_ns || j0 > scan.last_image_ns)
    throw InputError(file, jwhere,
                     "the joint samples (header stamps " + std::to_string(j0) + " to " + std::to_string(j1) +
                         ") overlap none of the images (header stamps " + std::to_string(scan.first_image_ns) +
                         " to " + std::to_string(scan.last_image_ns) +
                         "); expected joint states recorded over the same time as the images");
}

}  // namespace

void translateLogErrors(const std::function<void()>& f) {
  try {
    f();
  } catch (const logs::LogError& e) {
    throw InputError(e.file(), e.where(), e.detail());
  }
}

std::unique_ptr<logs::BagReader> openBagInput(const std::string& path) {
  std::unique_ptr<logs::BagReader> bag;
  translateLogErrors([&] { bag = logs::openBag(path); });
  return bag;
}

BagPlan planBag(const logs::BagReader& bag, const RigConfig& rig) {
  BagPlan plan;
  plan.joints_topic = rig.joint_states_topic;
  requireTopic(bag, plan.joints_topic, {logs::MessageKind::JointState}, rig, "joint_states_topic");
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const CameraConfig& cc = rig.cameras[c];
    const std::string field = cameraField(cc.name);
    if (cc.topic.empty()) {
      std::vector<std::string> images;
      for (const auto& info : bag.topics())
        if (logs::messageKind(info.type) == logs::MessageKind::Image ||
            logs::messageKind(info.type) == logs::MessageKind::CompressedImage)
          images.push_back(info.name);
      throw rigFieldError(rig, field + ".topic",
                          "missing; expected the Image or CompressedImage topic of camera '" + cc.name +
                              "' (reading a bag needs it)" + closestNote(cc.name, images, "image topics"));
    }
    const auto& t = requireTopic(bag, cc.topic, {logs::MessageKind::Image, logs::MessageKind::CompressedImage},
                                 rig, field + ".topic");
    plan.image_topics.push_back(cc.topic);
    plan.image_kinds.push_back(logs::messageKind(t.type));
    plan.image_counts.push_back(t.message_count);
    if (!cc.camera_info_topic.empty())
      requireTopic(bag, cc.camera_info_topic, {logs::MessageKind::CameraInfo}, rig, field + ".camera_info_topic");
    plan.info_topics.push_back(cc.camera_info_topic);
  }
  return plan;
}

namespace {

/// An image message of camera `c` as a BagImage: decoded (a raw Image's
/// bytes that do not fit its header mark it damaged), its format checked.
BagImage imageOf(const logs::RawMessage& m, const BagPlan& plan, std::size_t c, const std::string& file) {
  BagImage im;
  im.camera = static_cast<int>(c);
  im.index = m.index;
  if (plan.image_kinds[c] == logs::MessageKind::Image) {
    logs::Image img = logs::decodeImage(m, file);
    im.stamp_ns = img.header.stamp_ns;
    if (const std::string bad = imageProblem(img); !bad.empty()) {
      // An encoding fgcal cannot read is the recording's format: an
      // error. Bytes that do not fit their own header are one damaged
      // message: skipped, as a CompressedImage that does not decode.
      const auto& known = supportedImageEncodings();
      if (std::find(known.begin(), known.end(), img.encoding) == known.end())
        throw InputError(file, messageWhere(m, im.stamp_ns), bad);
      im.damaged = bad;
      img.data.clear();
    }
    im.message = std::move(img);
  } else {
    logs::CompressedImage img = logs::decodeCompressedImage(m, file);
    im.stamp_ns = img.header.stamp_ns;
    if (compressedImageFormat(img.format).empty())
      throw InputError(file, messageWhere(m, im.stamp_ns),
                       "compressed image format '" + img.format +
                           "' cannot be read; expected jpeg or png (e.g. \"jpeg\", \"mono8; jpeg compressed \")");
    im.message = std::move(img);
  }
  return im;
}

}  // namespace

BagScan scanBag(logs::BagReader& bag, const BagPlan& plan, const std::function<void(BagImage&&)>& on_image) {
  const std::string& file = bag.path();
  BagScan scan;
  scan.camera_info.resize(plan.image_topics.size());
  JointStateCollector joints(plan.joints_kept);
  std::vector<std::string> topics{plan.joints_topic};
  for (const auto& t : plan.image_topics) topics.push_back(t);
  for (const auto& t : plan.info_topics)
    if (!t.empty()) topics.push_back(t);
  std::sort(topics.begin(), topics.end());
  topics.erase(std::unique(topics.begin(), topics.end()), topics.end());
  bool any_image = false;
  std::vector<std::size_t> per_camera(plan.image_topics.size(), 0);

  translateLogErrors([&] {
    bag.read(topics, [&](const logs::RawMessage& m) {
      const std::string& name = m.topic->name;
      if (name == plan.joints_topic) {
        const logs::JointState js = logs::decodeJointState(m, file);
        if (const std::string bad = joints.add(js, m.index); !bad.empty())
          throw InputError(file, messageWhere(m, js.header.stamp_ns), bad);
      }
      for (std::size_t c = 0; c < plan.info_topics.size(); ++c) {
        if (name != plan.info_topics[c]) continue;
        logs::CameraInfo info = logs::decodeCameraInfo(m, file);
        auto& first = scan.camera_info[c];
        if (!first) {
          first = std::move(info);
        } else if (!sameIntrinsics(*first, info)) {
          throw InputError(file, messageWhere(m, info.header.stamp_ns),
                           "the camera_info changed (K, D, distortion model or size differ from the first one, "
                           "stamp " + std::to_string(first->header.stamp_ns) +
                               "); one calibration needs one set of intrinsics: cut the bag where they change");
        }
      }
      for (std::size_t c = 0; c < plan.image_topics.size(); ++c) {
        if (name != plan.image_topics[c]) continue;
        BagImage im = imageOf(m, plan, c, file);
        im.label = file + ": " + messageWhere(m, im.stamp_ns);
        if (const auto& info = scan.camera_info[c]) {
          im.info_width = static_cast<int>(std::min<std::uint32_t>(info->width, INT_MAX));
          im.info_height = static_cast<int>(std::min<std::uint32_t>(info->height, INT_MAX));
        }
        if (!any_image || im.stamp_ns < scan.first_image_ns) scan.first_image_ns = im.stamp_ns;
        if (!any_image || im.stamp_ns > scan.last_image_ns) scan.last_image_ns = im.stamp_ns;
        any_image = true;
        ++scan.images;
        ++per_camera[c];
        on_image(std::move(im));
      }
      return true;
    });
  });

  finishScan(file, plan, joints, per_camera, scan);
  return scan;
}

void applyCameraInfo(const BagScan& scan, const BagPlan& plan, const std::string& bag_path, RigConfig* rig,
                     std::vector<std::string>* warnings) {
  for (std::size_t c = 0; c < rig->cameras.size(); ++c) {
    CameraConfig& cc = rig->cameras[c];
    const auto& info = scan.camera_info[c];
    if (plan.info_topics[c].empty()) continue;
    const std::string where = "topic " + plan.info_topics[c];
    if (!info) {
      if (cc.intrinsics_from_bag)
        throw InputError(bag_path, where,
                         "no camera_info message; camera '" + cc.name +
                             "' has no intrinsics in rig.yaml and takes them from this topic");
      continue;
    }
    CameraConfig from_bag = cc;
    if (const std::string bad = intrinsicsFromCameraInfo(*info, &from_bag); !bad.empty()) {
      if (!cc.intrinsics_from_bag) {
        warnings->push_back(bag_path + ": " + where + ": not compared with rig.yaml's intrinsics: " + bad);
        continue;
      }
      throw InputError(bag_path, where + ", message stamp " + std::to_string(info->header.stamp_ns), bad);
    }
    if (cc.intrinsics_from_bag) {
      from_bag.intrinsics_from_bag = false;
      cc = std::move(from_bag);
    } else if (from_bag.intrinsics != cc.intrinsics || from_bag.distortion_coeffs != cc.distortion_coeffs ||
               from_bag.distortion_model != cc.distortion_model || from_bag.resolution != cc.resolution) {
      warnings->push_back(bag_path + ": " + where + ": the camera_info's intrinsics differ from those rig.yaml " +
                              "gives camera '" + cc.name + "'; rig.yaml's are used");
    }
  }
}

}  // namespace fgcal::apps
