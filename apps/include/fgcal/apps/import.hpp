// `fgcal import BAG --rig RIG.yaml --out DATASET`: a robot bag written out as
// a dataset folder (docs/formats.md), so that it can be looked
// at, edited, shared without the bag, or calibrated again.
//
// - Images are named by their header stamp: a CompressedImage is stored byte
//   for byte as recorded, <stamp>.jpg or <stamp>.png; a raw Image as a PNG
//   whose decoded rows are the message's pixels (bag_messages.hpp,
//   imageForPng: mono8/mono16 exactly, colour with its colours right, Bayer
//   demosaiced). Of two images of one camera with the same stamp the one
//   recorded later is kept.
// - joints.csv holds every joint sample (sorted by header stamp; messages of
//   one stamp merged, see JointStateCollector) and every joint of the topic.
// - rig.yaml is rig.yaml as read, with the intrinsics written as numbers
//   (from rig.yaml, its intrinsics_file or the bag's camera_info), the topics
//   kept (so it also serves as --rig for the bag) and the URDF path relative
//   to the new folder.
// The folder is written under a temporary name beside DATASET and renamed into
// place at the end: an error leaves nothing behind. DATASET must not exist or
// be an empty folder.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace fgcal::apps {

struct ImportOptions {
  std::string bag;  ///< ROS 1 .bag, ROS 2 bag folder or .mcap file
  std::string rig;  ///< rig.yaml naming each camera's topic
  std::string out;  ///< the dataset folder to create
};

struct ImportResult {
  std::string out;                              ///< the folder written, absolute
  std::map<std::string, std::size_t> images;    ///< per camera, images written
  std::size_t joint_samples = 0;
  std::vector<std::string> warnings;
};

/// Throws InputError (exit 2) naming the file, topic and message for bad input
/// (see bag_source.hpp), an existing non-empty --out, or a file that cannot
/// be written; nothing is left behind then.
ImportResult runImport(const ImportOptions& options, std::ostream& log);

}  // namespace fgcal::apps
