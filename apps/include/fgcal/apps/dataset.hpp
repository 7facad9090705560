// A dataset folder (docs/formats.md): rig.yaml, joints.csv and one
// image folder per camera named <stamp_ns>.png|jpg|jpeg (Kalibr's layout).
// loadDataset reads the two text files and lists the images; it does not
// decode them (the vision module does, in parallel, later).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/rig_config.hpp"

namespace fgcal::apps {

struct ImageEntry {
  std::string camera;  ///< camera name (= folder name)
  int64_t stamp_ns = 0;
  std::string path;  ///< full path of the image file
};

struct Dataset {
  std::string root;  ///< the dataset folder, absolute
  RigConfig rig;     ///< only the selected cameras, in rig.yaml order
  JointLog joints;
  /// Every image of the selected cameras, sorted by stamp, then by the
  /// camera's position in rig.yaml.
  std::vector<ImageEntry> images;
  /// rig.yaml's and joints.csv's warnings plus the dataset's own (skipped
  /// files), each naming its file or folder.
  std::vector<std::string> warnings;
};

/// Reads DIR/rig.yaml and DIR/joints.csv and lists DIR/<camera>/ for the
/// cameras in `camera_subset` (every camera of rig.yaml when empty).
/// InputError when: DIR is missing or not a folder; rig.yaml or joints.csv is
/// missing or invalid; the URDF named by rig.yaml does not exist; a subset name
/// is not a camera of rig.yaml (the defined ones are listed); a camera folder
/// is missing; a camera folder holds no image; two images of one camera share
/// a stamp (e.g. 17.png and 17.jpg). Other files in a camera folder are skipped
/// and counted in a warning.
/// `rig_file`, when given, is read instead of DIR/rig.yaml (its relative paths
/// are relative to its own folder). With `read_joints` false, joints.csv is
/// only checked to exist and `joints` stays empty (a caller that keeps only
/// part of it reads it with loadJointsCsv and a filter).
Dataset loadDataset(const std::string& dir, const std::vector<std::string>& camera_subset = {},
                    const std::string& rig_file = "", bool read_joints = true);

/// Keeps only the cameras named in `camera_subset` (all when empty), in
/// rig.yaml order; InputError naming `rig_path` and listing the defined
/// cameras when one is not defined.
void selectCameras(RigConfig* rig, const std::vector<std::string>& camera_subset, const std::string& rig_path);

/// True for "<digits>.png|jpg|jpeg" (extension in any case); stamp_ns receives
/// the stamp.
bool parseImageFileName(const std::string& file_name, int64_t* stamp_ns);

}  // namespace fgcal::apps
