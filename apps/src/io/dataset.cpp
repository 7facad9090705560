// Dataset folder reader (see dataset.hpp).
#include "fgcal/apps/dataset.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <map>
#include <system_error>

#include "fgcal/apps/errors.hpp"
#include "io/text_format.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

bool parseImageFileName(const std::string& name, int64_t* stamp_ns) {
  const std::size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0) return false;
  std::string ext = name.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (ext != "png" && ext != "jpg" && ext != "jpeg") return false;
  const std::string stem = name.substr(0, dot);
  if (!std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  int64_t v = 0;
  const auto res = std::from_chars(stem.data(), stem.data() + stem.size(), v);
  if (res.ec != std::errc() || res.ptr != stem.data() + stem.size()) return false;  // also rejects overflow
  if (stamp_ns) *stamp_ns = v;
  return true;
}

namespace {

bool isDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

}  // namespace

void selectCameras(RigConfig* rig, const std::vector<std::string>& camera_subset, const std::string& rig_path) {
  if (camera_subset.empty()) return;
  std::vector<std::string> defined;
  for (const auto& c : rig->cameras) defined.push_back(c.name);
  for (const auto& want : camera_subset)
    if (rig->cameraIndex(want) < 0)
      throw InputError(rig_path, "--cameras",
                       "expected cameras that " + rig_path + " defines, got '" + want + "'" +
                           closestNote(want, defined, "cameras") + rig->lineSuffix("cameras"));
  std::vector<CameraConfig> kept;
  for (auto& c : rig->cameras)
    if (std::find(camera_subset.begin(), camera_subset.end(), c.name) != camera_subset.end())
      kept.push_back(std::move(c));
  rig->cameras = std::move(kept);
}

namespace {

/// The dataset's files, checked to exist.
struct DatasetFiles {
  fs::path root, rig, joints;
};
DatasetFiles findDatasetFiles(const std::string& dir, const std::string& rig_file) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw InputError(dir, "", "dataset folder not found; expected a folder holding rig.yaml, joints.csv and one image "
                              "folder per camera");
  if (!isDir(dir))
    throw InputError(dir, "", "expected a dataset folder (rig.yaml, joints.csv, <camera>/...), got a file");
  DatasetFiles f;
  f.root = fs::absolute(dir).lexically_normal();
  f.rig = rig_file.empty() ? f.root / "rig.yaml" : fs::path(rig_file);
  if (!isFile(f.rig))
    throw InputError(f.rig.string(), "",
                     rig_file.empty() ? "not found; every dataset folder needs rig.yaml (docs/formats.md)"
                                      : "not found; --rig names the rig.yaml to use instead of the dataset's");
  f.joints = f.root / "joints.csv";
  if (!isFile(f.joints))
    throw InputError(f.joints.string(), "",
                     "not found; every dataset folder needs joints.csv (header stamp_ns,<joint>,...)");
  return f;
}

/// rig.yaml, its URDF checked to exist, its cameras narrowed to the subset.
/// A folder has no CameraInfo to fill intrinsics the rig leaves to a bag.
RigConfig loadFolderRig(const fs::path& rig_path, const std::vector<std::string>& camera_subset) {
  RigConfig rig = loadRigConfig(rig_path.string());
  if (!isFile(rig.robot.urdf))
    throw rigFieldError(rig, "robot.urdf",
                        "expected an existing URDF file (paths are relative to the dataset folder), but " +
                            rig.robot.urdf + " does not exist");
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const CameraConfig& c = rig.cameras[i];
    const bool wanted =
        camera_subset.empty() || std::find(camera_subset.begin(), camera_subset.end(), c.name) != camera_subset.end();
    if (wanted && c.intrinsics_from_bag)
      throw rigFieldError(rig, cameraField(c.name, "intrinsics"),
                          "missing; camera '" + c.name + "' takes its intrinsics from camera_info_topic " +
                              c.camera_info_topic +
                              ", which only a bag has; a dataset folder needs intrinsics [fx, fy, cx, cy] (with "
                              "distortion_model, distortion_coeffs, resolution) or an intrinsics_file in rig.yaml");
  }
  selectCameras(&rig, camera_subset, rig_path.string());
  return rig;
}

/// A camera's images by stamp; a warning for entries not named <stamp_ns>.png|jpg|jpeg.
std::map<int64_t, std::string> listCameraImages(const fs::path& folder, const std::string& camera,
                                                std::vector<std::string>* warnings) {
  if (!isDir(folder))
    throw InputError(folder.string(), "",
                     "image folder of camera '" + camera + "' (defined in rig.yaml) not found; expected " +
                         "<stamp_ns>.png|jpg images in it");
  std::map<int64_t, std::string> by_stamp;
  std::size_t skipped = 0;
  std::vector<std::string> skipped_examples;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string fname = it->path().filename().string();
    int64_t stamp = 0;
    if (!it->is_regular_file(ec) || !parseImageFileName(fname, &stamp)) {
      ++skipped;
      if (skipped_examples.size() < 3) skipped_examples.push_back(fname);
      continue;
    }
    const auto [pos, inserted] = by_stamp.emplace(stamp, it->path().string());
    if (!inserted)
      throw InputError(folder.string(), "",
                       "expected one image per stamp, got two for stamp " + std::to_string(stamp) + ": " +
                           fs::path(pos->second).filename().string() + " and " + fname);
  }
  if (ec) throw InputError(folder.string(), "", "cannot list the folder: " + ec.message());
  if (by_stamp.empty())
    throw InputError(folder.string(), "",
                     "no images of camera '" + camera + "'; expected files named <stamp_ns>.png, .jpg or .jpeg" +
                         (skipped ? " (found only " + std::to_string(skipped) + " other entries, e.g. " +
                                        detail::joinNames(skipped_examples) + ")"
                                  : std::string(" (the folder is empty)")));
  if (skipped)
    warnings->push_back(folder.string() + ": skipped " + std::to_string(skipped) + " entr" +
                        (skipped == 1 ? "y" : "ies") + " not named <stamp_ns>.png|jpg|jpeg (e.g. " +
                        detail::joinNames(skipped_examples) + ")");
  return by_stamp;
}

}  // namespace

Dataset loadDataset(const std::string& dir, const std::vector<std::string>& camera_subset,
                    const std::string& rig_file, bool read_joints) {
  const DatasetFiles files = findDatasetFiles(dir, rig_file);
  Dataset ds;
  ds.root = files.root.string();
  RigConfig rig = loadFolderRig(files.rig, camera_subset);
  ds.warnings = rig.warnings;
  if (read_joints) {
    ds.joints = loadJointsCsv(files.joints.string());
    ds.warnings.insert(ds.warnings.end(), ds.joints.warnings.begin(), ds.joints.warnings.end());
  }
  std::map<std::string, int> order;
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) order[rig.cameras[i].name] = static_cast<int>(i);
  for (const CameraConfig& cam : rig.cameras)
    for (const auto& [stamp, path] : listCameraImages(files.root / cam.name, cam.name, &ds.warnings))
      ds.images.push_back(ImageEntry{cam.name, stamp, path});
  std::sort(ds.images.begin(), ds.images.end(), [&](const ImageEntry& a, const ImageEntry& b) {
    if (a.stamp_ns != b.stamp_ns) return a.stamp_ns < b.stamp_ns;
    return order.at(a.camera) < order.at(b.camera);
  });
  ds.rig = std::move(rig);
  return ds;
}

}  // namespace fgcal::apps
