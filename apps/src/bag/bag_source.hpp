// One pass over a robot bag for the calibration and for `fgcal import`: the
// topics rig.yaml names are checked against the bag, then every message is
// read once, in storage order. Joint states and camera_info are collected
// here; each image message is decoded from its serialization, checked, and
// handed to the caller (which detects it or writes it) without being kept.
//
// Every error is an InputError (exit 2) naming the bag, the topic and the
// message (index in storage order and header stamp); the readers' own
// LogError becomes an InputError in translateLogErrors, the one place.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/messages.hpp"

namespace fgcal::apps {

/// Runs `f`; a logs::LogError it throws becomes the InputError of the same
/// file, place and text.
void translateLogErrors(const std::function<void()>& f);

/// openBag with its errors as InputError.
std::unique_ptr<logs::BagReader> openBagInput(const std::string& path);

/// The topics a rig reads from a bag, each checked: present (else the error
/// lists the topics the bag has) and of the right type.
struct BagPlan {
  std::string joints_topic;
  std::vector<std::string> image_topics;  ///< per camera, rig.yaml order
  std::vector<logs::MessageKind> image_kinds;  ///< Image or CompressedImage
  std::vector<std::string> info_topics;   ///< per camera; empty when none
  std::vector<std::uint64_t> image_counts;  ///< messages per image topic (progress)
  /// The joints whose positions scanBag keeps (a calibration: its chain's);
  /// empty: every joint (import).
  std::vector<std::string> joints_kept;
};
/// Errors name rig.yaml's field (rig.source, the line), e.g. a camera without
/// `topic` or a topic the bag does not hold, with the closest topics.
BagPlan planBag(const logs::BagReader& bag, const RigConfig& rig);

/// One image message, decoded and checked (a readable encoding or format).
struct BagImage {
  int camera = 0;  ///< index into rig.cameras
  std::uint64_t index = 0;  ///< among its topic's messages, storage order
  std::int64_t stamp_ns = 0;
  std::string label;  ///< "BAG: topic T, message I (stamp S)", for messages
  std::variant<logs::Image, logs::CompressedImage> message;
  /// The size the camera's first camera_info declares, when one was read
  /// before this image (0 otherwise): the expected size of a compressed
  /// image whose camera takes its intrinsics from the bag.
  int info_width = 0, info_height = 0;
  /// Why the message's bytes cannot be an image (a raw Image whose data are
  /// short of its step x height, ...): it is skipped and counted like a
  /// CompressedImage that does not decode. Empty for a readable message.
  std::string damaged;
};

struct BagScan {
  JointLog joints;  ///< sorted by header stamp (JointStateCollector)
  /// Per camera, the first camera_info of its topic (every later one was
  /// checked to carry the same intrinsics); nullopt without a topic.
  std::vector<std::optional<logs::CameraInfo>> camera_info;
  std::vector<std::string> warnings;
  std::size_t images = 0;
  std::int64_t first_image_ns = 0, last_image_ns = 0;
};

/// Reads the bag once; `on_image` is called on this thread for each image
/// message (in storage order) and may keep or move the message. Throws
/// InputError for: a message that does not decode, an image encoding or
/// compressed format that cannot be read, a JointState with mismatched
/// names and positions, a camera_info whose intrinsics change (naming the
/// topic and the stamp), no joint sample, an image topic without messages, or
/// joint samples that overlap no image.
BagScan scanBag(logs::BagReader& bag, const BagPlan& plan, const std::function<void(BagImage&&)>& on_image);

/// Fills the intrinsics of each camera that rig.yaml leaves to its
/// camera_info topic. Throws InputError naming the topic when the camera_info
/// cannot be used or has no message. A camera_info that differs from the
/// intrinsics rig.yaml gives is a warning (rig.yaml's are used).
void applyCameraInfo(const BagScan& scan, const BagPlan& plan, const std::string& bag_path, RigConfig* rig,
                     std::vector<std::string>* warnings);

}  // namespace fgcal::apps
