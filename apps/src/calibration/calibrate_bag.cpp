// runCalibrate's load and detect stages for a robot bag (calibrate_stages.hpp):
// the bag is read once, its images decoded and detected on every core while
// the reader goes on (a bounded queue between them, only detections kept),
// its joint states and camera_info collected on the way; then the camera
// models from the final intrinsics and PnP.
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <memory>
#include <numeric>
#include <thread>

#include "../bag/detection_pool.hpp"
#include "calibrate_stages.hpp"
#include "fgcal/apps/bag_messages.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/vision/pnp.hpp"
#include "progress.hpp"

namespace fgcal::apps::stages {

namespace {

using Message = std::variant<logs::Image, logs::CompressedImage>;

cv::Mat toGray(const Message& m) {
  if (const auto* raw = std::get_if<logs::Image>(&m)) return imageToGray(*raw);
  return compressedToGray(std::get<logs::CompressedImage>(m));
}

/// Runs fn(i) for i < n on `threads` threads (0: every core).
template <class F>
void parallelFor(std::size_t n, int threads, F&& fn) {
  unsigned k = threads > 0 ? static_cast<unsigned>(threads) : std::max(1u, std::thread::hardware_concurrency());
  k = static_cast<unsigned>(std::min<std::size_t>(k, std::max<std::size_t>(n, 1)));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) fn(i);
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < k; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

/// What is kept of an image message besides its detection.
struct ImageMeta {
  int camera;
  std::int64_t stamp_ns;
  std::uint64_t index;
  std::string label;
};

/// The images in stamp order (then rig.yaml's camera order), as a folder's;
/// of two images of one camera with one stamp, the one recorded later.
std::vector<std::size_t> stampOrder(const std::vector<ImageMeta>& meta) {
  std::vector<std::size_t> order(meta.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (meta[a].stamp_ns != meta[b].stamp_ns) return meta[a].stamp_ns < meta[b].stamp_ns;
    if (meta[a].camera != meta[b].camera) return meta[a].camera < meta[b].camera;
    return meta[a].index > meta[b].index;
  });
  std::vector<std::size_t> kept;
  for (std::size_t k : order) {
    const ImageMeta& m = meta[k];
    if (!kept.empty() && meta[kept.back()].stamp_ns == m.stamp_ns && meta[kept.back()].camera == m.camera) continue;
    kept.push_back(k);
  }
  return kept;
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
    throw InputError(opt.rig, "robot.urdf",
                     "expected an existing URDF file (paths are relative to the rig.yaml's folder), but " +
                         in.rig.robot.urdf + " does not exist");
  selectCameras(&in.rig, opt.cameras, opt.rig);
  in.warnings = in.rig.warnings;
  in.bag = openBagInput(opt.dataset);
  in.plan = planBag(*in.bag, in.rig, opt.rig);
  in.joints_name = opt.dataset + ": topic " + in.plan.joints_topic;
  return in;
}

Detections detectBag(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log,
                     std::vector<vision::CameraModel>* models) {
  const std::size_t expected =
      std::accumulate(in.plan.image_counts.begin(), in.plan.image_counts.end(), std::size_t{0});
  Progress progress(log, expected, Progress::isTerminal(log), true);
  std::vector<ImageMeta> meta;
  std::vector<StreamedDetection> streamed;
  BagScan scan;
  {
    DetectionPool pool(*setup.detector, opt.threads, 0, [&] { progress.detected(); });
    scan = scanBag(*in.bag, in.plan, [&](BagImage&& im) {
      meta.push_back(ImageMeta{im.camera, im.stamp_ns, im.index, im.label});
      progress.read();
      auto message = std::make_shared<Message>(std::move(im.message));
      pool.submit([message] { return toGray(*message); }, im.label + ": cannot be decoded");
    });
    streamed = pool.finish();
  }
  progress.finish();
  in.joints = std::move(scan.joints);
  in.warnings.insert(in.warnings.end(), scan.warnings.begin(), scan.warnings.end());
  applyCameraInfo(scan, in.plan, in.source, &in.rig, &in.warnings);

  const std::vector<std::size_t> kept = stampOrder(meta);
  if (kept.size() < meta.size())
    in.warnings.push_back(in.source + ": " + std::to_string(meta.size() - kept.size()) +
                          " image message(s) share camera and header stamp with another; the one recorded later "
                          "is used");

  *models = cameraModels(in);
  Detections det;
  det.frames.resize(kept.size());
  det.wrong_size.resize(kept.size());
  in.images.clear();
  in.message_index.clear();
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const ImageMeta& m = meta[kept[i]];
    in.images.push_back(ImageEntry{in.rig.cameras[static_cast<std::size_t>(m.camera)].name, m.stamp_ns, m.label});
    in.message_index.push_back(m.index);
  }
  for (const auto& s : streamed) det.decode_seconds += s.decode_seconds;
  parallelFor(kept.size(), opt.threads, [&](std::size_t i) {
    const ImageMeta& m = meta[kept[i]];
    StreamedDetection& s = streamed[kept[i]];
    const CameraConfig& cc = in.rig.cameras[static_cast<std::size_t>(m.camera)];
    if (s.width > 0 && (s.width != cc.resolution[0] || s.height != cc.resolution[1])) {
      det.wrong_size[i] = std::to_string(s.width) + "x" + std::to_string(s.height) + ", " +
                          (in.plan.info_topics[static_cast<std::size_t>(m.camera)].empty() ||
                                   !cc.intrinsics_file.empty()
                               ? "rig.yaml says "
                               : "rig.yaml or camera_info says ") +
                          std::to_string(cc.resolution[0]) + "x" + std::to_string(cc.resolution[1]);
      return;
    }
    vision::FrameResult& fr = det.frames[i];
    fr.detection = std::move(s.detection);
    if (!fr.detection.ok()) return;
    vision::PnpOptions pnp;  // as detectFolder's
    pnp.pixel_sigma = cc.pixel_sigma;
    pnp.sigma_source = vision::PnpOptions::SigmaSource::Larger;
    try {
      fr.pose = vision::estimatePose((*models)[static_cast<std::size_t>(m.camera)], fr.detection, pnp);
    } catch (const std::exception& e) {
      fr.pose_error = e.what();
    }
  });
  return det;
}

std::map<std::size_t, cv::Mat> readBagImages(Inputs& in, const std::vector<std::size_t>& images) {
  std::map<std::pair<std::string, std::uint64_t>, std::size_t> wanted;  // (topic, message index) -> image
  std::vector<std::string> topics;
  for (std::size_t i : images) {
    const auto c = static_cast<std::size_t>(in.rig.cameraIndex(in.images.at(i).camera));
    wanted[{in.plan.image_topics[c], in.message_index.at(i)}] = i;
    topics.push_back(in.plan.image_topics[c]);
  }
  std::sort(topics.begin(), topics.end());
  topics.erase(std::unique(topics.begin(), topics.end()), topics.end());
  std::map<std::size_t, cv::Mat> out;
  if (wanted.empty()) return out;
  const std::string& file = in.bag->path();
  translateLogErrors([&] {
    in.bag->read(topics, [&](const logs::RawMessage& m) {
      const auto it = wanted.find({m.topic->name, m.index});
      if (it == wanted.end()) return true;
      if (logs::messageKind(m.topic->type) == logs::MessageKind::Image)
        out[it->second] = imageToGray(logs::decodeImage(m, file));  // checked when first read
      else
        out[it->second] = compressedToGray(logs::decodeCompressedImage(m, file));
      return out.size() < wanted.size();
    });
  });
  return out;
}

}  // namespace fgcal::apps::stages
