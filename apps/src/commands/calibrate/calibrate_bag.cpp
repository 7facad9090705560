// runCalibrate's load and detect stages for a robot bag (calibrate_stages.hpp):
// the bag is read once, its images decoded and detected on every core while
// the reader goes on (a bounded queue between them, only each image's record
// and corners kept), its joint states (the chain's joints only) and
// camera_info collected on the way.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <mutex>
#include <numeric>

#include "bag/detection_pool.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "commands/calibrate/progress.hpp"
#include "fgcal/apps/bag_messages.hpp"
#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/vision/image_header.hpp"

namespace fgcal::apps::stages {

namespace {

using Message = std::variant<logs::Image, logs::CompressedImage>;

cv::Mat toGray(const Message& m, vision::ExpectedSize expected) {
  if (const auto* raw = std::get_if<logs::Image>(&m)) return imageToGray(*raw);
  return compressedToGray(std::get<logs::CompressedImage>(m), expected);
}

/// The images in stamp order (then rig.yaml's camera order), as a folder's;
/// of two images of one camera with one stamp, the one recorded later. The
/// number dropped.
std::size_t sortAndDeduplicate(std::vector<ImageRecord>& images) {
  std::sort(images.begin(), images.end(), [](const ImageRecord& a, const ImageRecord& b) {
    if (a.stamp_ns != b.stamp_ns) return a.stamp_ns < b.stamp_ns;
    if (a.camera != b.camera) return a.camera < b.camera;
    return a.locator > b.locator;
  });
  const auto end = std::unique(images.begin(), images.end(), [](const ImageRecord& a, const ImageRecord& b) {
    return a.stamp_ns == b.stamp_ns && a.camera == b.camera;
  });
  const auto dropped = static_cast<std::size_t>(images.end() - end);
  images.erase(end, images.end());
  return dropped;
}

/// Images of another size than their camera's (known only now, camera_info read).
void checkSizes(Inputs& in) {
  for (std::size_t i = 0; i < in.images.size(); ++i) {
    const std::size_t c = in.images[i].camera;
    const bool rig_only = in.plan.info_topics[c].empty() || !in.rig.cameras[c].intrinsics_file.empty();
    checkSize(in, i, rig_only ? "rig.yaml says" : "rig.yaml or camera_info says");
  }
}

}  // namespace

Inputs loadBagInputs(const CalibrateOptions& opt) {
  if (opt.rig.empty())
    throw InputError(opt.dataset, "--rig",
                     "a bag needs --rig RIG.yaml: the robot, the board and each camera's topic are not in the bag");
  Inputs in;
  in.from_bag = true;
  in.source = opt.dataset;
  in.rig_path = opt.rig;
  in.rig = loadRigConfig(opt.rig);
  if (!std::filesystem::is_regular_file(in.rig.robot.urdf))
    throw rigFieldError(in.rig, "robot.urdf",
                        "expected an existing URDF file (paths are relative to the rig.yaml's folder), but " +
                            in.rig.robot.urdf + " does not exist");
  selectCameras(&in.rig, opt.cameras, opt.rig);
  in.warnings = in.rig.warnings;
  in.bag = openBagInput(opt.dataset);
  in.bag_path = in.bag->path();
  in.plan = planBag(*in.bag, in.rig);
  in.joints_name = opt.dataset + ": topic " + in.plan.joints_topic;
  return in;
}

Detections detectBag(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log) {
  const std::size_t expected =
      std::accumulate(in.plan.image_counts.begin(), in.plan.image_counts.end(), std::size_t{0});
  Progress progress(log, expected, Progress::isTerminal(log), true);
  Detections det;
  BagScan scan;
  std::mutex mutex;  // in.images, in.details, det
  in.plan.joints_kept = setup.chain.jointNames();
  {
    DetectionPool pool(*setup.detector, opt.threads, [&](std::size_t i, StreamedDetection&& s) {
      progress.detected();
      std::lock_guard<std::mutex> lock(mutex);
      keepDetection(in, i, s, det);
    });
    scan = scanBag(*in.bag, in.plan, [&](BagImage&& im) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        ImageRecord r;
        r.stamp_ns = im.stamp_ns;
        r.locator = im.index;
        r.camera = static_cast<std::uint16_t>(im.camera);
        in.images.push_back(r);
      }
      progress.read();
      // A compressed image is decoded only when its header's size is the
      // camera's: rig.yaml's resolution, else that of the camera_info read
      // so far (else at most vision::kMaxUncheckedPixels); checkSizes counts
      // the others as a wrong image size.
      const CameraConfig& cc = in.rig.cameras[static_cast<std::size_t>(im.camera)];
      vision::ExpectedSize expected;
      if (!cc.intrinsics_from_bag) expected = {cc.resolution[0], cc.resolution[1]};
      else if (im.info_width > 0 && im.info_height > 0) expected = {im.info_width, im.info_height};
      if (!im.damaged.empty()) {  // counted as the pool counts an image that does not decode
        pool.submit([] { return cv::Mat(); }, im.label + ": damaged message: " + im.damaged);
        return;
      }
      auto message = std::make_shared<Message>(std::move(im.message));
      pool.submit([message, expected] { return toGray(*message, expected); }, im.label + ": damaged message: cannot be decoded");
    });
    pool.finish();
  }
  progress.finish();
  in.joints = std::move(scan.joints);
  in.warnings.insert(in.warnings.end(), scan.warnings.begin(), scan.warnings.end());
  applyCameraInfo(scan, in.plan, in.source, &in.rig, &in.warnings);
  if (const std::size_t dropped = sortAndDeduplicate(in.images))
    in.warnings.push_back(in.source + ": " + std::to_string(dropped) +
                          " image message(s) share camera and header stamp with another; the one recorded later "
                          "is used");
  in.images.shrink_to_fit();  // grew message by message
  checkSizes(in);
  // The open reader holds the bag's index (a long recording: ~100 bytes per
  // image); nothing reads the bag again before the report, which reopens it.
  in.bag.reset();
  return det;
}

std::map<std::size_t, cv::Mat> readBagImages(Inputs& in, const std::vector<std::size_t>& images) {
  std::map<std::pair<std::string, std::uint64_t>, std::size_t> wanted;  // (topic, message index) -> image
  std::vector<std::string> topics;
  for (std::size_t i : images) {
    const ImageRecord& r = in.images.at(i);
    wanted[{in.plan.image_topics[r.camera], r.locator}] = i;
    topics.push_back(in.plan.image_topics[r.camera]);
  }
  std::sort(topics.begin(), topics.end());
  topics.erase(std::unique(topics.begin(), topics.end()), topics.end());
  std::map<std::size_t, cv::Mat> out;
  if (wanted.empty()) return out;
  if (!in.bag) in.bag = openBagInput(in.source);  // closed after detection (detectBag)
  const std::string& file = in.bag->path();
  translateLogErrors([&] {
    in.bag->read(topics, [&](const logs::RawMessage& m) {
      const auto it = wanted.find({m.topic->name, m.index});
      if (it == wanted.end()) return true;
      if (logs::messageKind(m.topic->type) == logs::MessageKind::Image)
        out[it->second] = imageToGray(logs::decodeImage(m, file));  // checked when first read
      else
        try {  // detected at this size: another is a changed bag, left out of the report
          const auto& res = in.rig.cameras[in.images.at(it->second).camera].resolution;
          out[it->second] = compressedToGray(logs::decodeCompressedImage(m, file), {res[0], res[1]});
        } catch (const vision::ImageSizeMismatch&) {
        }
      return out.size() < wanted.size();
    });
  });
  return out;
}

}  // namespace fgcal::apps::stages
