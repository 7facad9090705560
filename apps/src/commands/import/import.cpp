// `fgcal import`: a bag written out as a dataset folder (import.hpp).
#include "fgcal/apps/import.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <ostream>

#include <opencv2/imgcodecs.hpp>

#include "bag/bag_source.hpp"
#include "fgcal/apps/bag_messages.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/rig_config.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

namespace {

/// The folder an import writes into before it is complete; removed unless committed.
class StagingFolder {
 public:
  explicit StagingFolder(const fs::path& final_dir)
      : path_(final_dir.parent_path() / ("." + final_dir.filename().string() + ".import-" + std::to_string(::getpid()))) {
    std::error_code ec;
    fs::remove_all(path_, ec);  // a leftover of a killed run of this process id
    if (!fs::create_directory(path_, ec))
      throw InputError(path_.string(), "", "cannot create the import's temporary folder: " + ec.message());
  }
  ~StagingFolder() {
    if (committed_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  StagingFolder(const StagingFolder&) = delete;
  StagingFolder& operator=(const StagingFolder&) = delete;
  const fs::path& path() const { return path_; }
  void commit(const fs::path& final_dir) {
    std::error_code ec;
    fs::rename(path_, final_dir, ec);  // replaces an empty folder
    if (ec) throw InputError(final_dir.string(), "", "cannot move the imported dataset into place: " + ec.message());
    committed_ = true;
  }

 private:
  fs::path path_;
  bool committed_ = false;
};

void writeBytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw InputError(path.string(), "", "cannot write the image (disk full or no permission?)");
}

/// The final folder, checked: absent or empty, its parent existing.
fs::path checkOutFolder(const std::string& out) {
  if (out.empty()) throw InputError("", "--out", "expected the dataset folder to create");
  const fs::path target = fs::absolute(out).lexically_normal();
  const fs::path dir = target.filename().empty() ? target.parent_path() : target;
  std::error_code ec;
  if (!fs::is_directory(dir.parent_path(), ec))
    throw InputError(out, "--out", "the parent folder " + dir.parent_path().string() + " does not exist; create it first");
  if (fs::exists(dir, ec) && (!fs::is_directory(dir, ec) || !fs::is_empty(dir, ec)))
    throw InputError(out, "", "exists and is not an empty folder; import writes a new dataset folder and never "
                              "replaces one (choose another --out or remove it)");
  return dir;
}

/// Writes one image into <camera>/<stamp>.<ext>; of two with the same stamp
/// the one recorded later (larger index) stays.
class ImageWriter {
 public:
  ImageWriter(fs::path root, const RigConfig& rig) : root_(std::move(root)) {
    for (const auto& c : rig.cameras) {
      names_.push_back(c.name);
      fs::create_directory(root_ / c.name);
    }
    latest_.resize(rig.cameras.size());
  }

  void write(BagImage&& im) {
    auto& seen = latest_[static_cast<std::size_t>(im.camera)];
    const auto it = seen.find(im.stamp_ns);
    if (it != seen.end()) {
      ++duplicates_;
      if (it->second.first > im.index) return;
      fs::remove(it->second.second);
    }
    const fs::path folder = root_ / names_[static_cast<std::size_t>(im.camera)];
    const std::string stem = std::to_string(im.stamp_ns);
    fs::path path;
    if (const auto* c = std::get_if<logs::CompressedImage>(&im.message)) {
      path = folder / (stem + (compressedImageFormat(c->format) == "png" ? ".png" : ".jpg"));
      writeBytes(path, c->data);
    } else {
      path = folder / (stem + ".png");
      bool ok = false;
      try {
        ok = cv::imwrite(path.string(), imageForPng(std::get<logs::Image>(im.message)));
      } catch (const cv::Exception& e) {
        throw InputError(path.string(), "", std::string("cannot write the PNG: ") + e.what());
      }
      if (!ok) throw InputError(path.string(), "", "cannot write the PNG (disk full or no permission?)");
    }
    seen[im.stamp_ns] = {im.index, path};
  }

  std::size_t duplicates() const { return duplicates_; }
  std::size_t count(std::size_t camera) const { return latest_[camera].size(); }

 private:
  fs::path root_;
  std::vector<std::string> names_;
  std::vector<std::map<std::int64_t, std::pair<std::uint64_t, fs::path>>> latest_;
  std::size_t duplicates_ = 0;
};

}  // namespace

ImportResult runImport(const ImportOptions& opt, std::ostream& log) {
  if (opt.rig.empty()) throw InputError(opt.bag, "--rig", "import needs --rig RIG.yaml naming each camera's topic");
  RigConfig rig = loadRigConfig(opt.rig);
  if (!fs::is_regular_file(rig.robot.urdf))
    throw rigFieldError(rig, "robot.urdf",
                        "expected an existing URDF file (paths are relative to the rig.yaml's folder), but " +
                            rig.robot.urdf + " does not exist");
  const fs::path final_dir = checkOutFolder(opt.out);
  auto bag = openBagInput(opt.bag);
  const BagPlan plan = planBag(*bag, rig);
  std::size_t expected = 0;
  for (auto n : plan.image_counts) expected += n;
  log << "fgcal import: " << opt.bag << " (" << bag->format() << "): " << expected << " image messages from "
      << rig.cameras.size() << " camera(s), joint states on " << plan.joints_topic << "\n";

  ImportResult res;
  StagingFolder staging(final_dir);
  ImageWriter images(staging.path(), rig);
  std::size_t written = 0;
  const std::size_t step = std::max<std::size_t>(expected / 10, 1);
  std::vector<std::string> damaged;  // a raw Image whose bytes do not fit its header has no PNG to be
  BagScan scan = scanBag(*bag, plan, [&](BagImage&& im) {
    if (!im.damaged.empty()) {
      damaged.push_back(im.label + ": " + im.damaged);
      ++written;
      return;
    }
    images.write(std::move(im));
    if (++written % step == 0 || written == expected) log << "  wrote " << written << "/" << expected << " images\n";
  });
  res.warnings = scan.warnings;
  if (!damaged.empty()) {
    std::string w = std::to_string(damaged.size()) + " damaged image message(s) skipped, not written: ";
    for (std::size_t k = 0; k < damaged.size() && k < 5; ++k) w += (k ? "; " : "") + damaged[k];
    if (damaged.size() > 5) w += "; and " + std::to_string(damaged.size() - 5) + " more";
    res.warnings.push_back(w);
  }
  if (images.duplicates())
    res.warnings.push_back(opt.bag + ": " + std::to_string(images.duplicates()) +
                           " image message(s) share camera and header stamp with another; the one recorded later "
                           "is kept");
  applyCameraInfo(scan, plan, opt.bag, &rig, &res.warnings);

  writeJointsCsv((staging.path() / "joints.csv").string(), scan.joints.names, scan.joints.stamps_ns,
                 scan.joints.positions);
  for (auto& c : rig.cameras) c.intrinsics_file.clear();  // the numbers themselves, whatever their source
  {
    std::ofstream out(staging.path() / "rig.yaml", std::ios::binary);
    out << writeRigConfig(rig, final_dir.string());
    out.close();
    if (!out) throw InputError((staging.path() / "rig.yaml").string(), "", "cannot write rig.yaml");
  }
  staging.commit(final_dir);

  res.out = final_dir.string();
  res.joint_samples = scan.joints.stamps_ns.size();
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) res.images[rig.cameras[c].name] = images.count(c);
  log << "  wrote " << res.out << ": ";
  for (std::size_t c = 0; c < rig.cameras.size(); ++c)
    log << (c ? ", " : "") << res.images[rig.cameras[c].name] << " images of " << rig.cameras[c].name;
  log << ", " << res.joint_samples << " joint samples\n";
  for (const auto& w : res.warnings) log << "  warning: " << w << "\n";
  return res;
}

}  // namespace fgcal::apps
