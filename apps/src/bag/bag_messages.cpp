// Image, CameraInfo and JointState messages into the calibration's inputs
// (bag_messages.hpp).
#include "fgcal/apps/bag_messages.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "io/text_format.hpp"

namespace fgcal::apps {

namespace {

struct EncodingInfo {
  const char* name;
  int cv_type;    // of the message's pixels
  int bayer_bgr;  // cv::COLOR_Bayer..2BGR code, or -1
};

// ROS's Bayer names give the colours of the first two pixels of the first
// row; OpenCV names its codes after the second and third pixels of the
// second row, so ROS "rggb" is OpenCV "BG" (OpenCV's documentation, "Bayer").
const EncodingInfo kEncodings[] = {
    {"mono8", CV_8UC1, -1},
    {"mono16", CV_16UC1, -1},
    {"rgb8", CV_8UC3, -1},
    {"bgr8", CV_8UC3, -1},
    {"rgba8", CV_8UC4, -1},
    {"bgra8", CV_8UC4, -1},
    {"bayer_rggb8", CV_8UC1, cv::COLOR_BayerBG2BGR},
    {"bayer_bggr8", CV_8UC1, cv::COLOR_BayerRG2BGR},
    {"bayer_gbrg8", CV_8UC1, cv::COLOR_BayerGR2BGR},
    {"bayer_grbg8", CV_8UC1, cv::COLOR_BayerGB2BGR},
};

const EncodingInfo* findEncoding(const std::string& name) {
  for (const auto& e : kEncodings)
    if (name == e.name) return &e;
  return nullptr;
}

/// A view of the message's pixels (no copy; valid while `image` lives). mono16
/// is byte-swapped into a copy when the message is big-endian.
cv::Mat pixels(const logs::Image& image, const EncodingInfo& e) {
  cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), e.cv_type,
               const_cast<std::uint8_t*>(image.data.data()), image.step);
  if (e.cv_type != CV_16UC1 || !image.is_bigendian) return view;
  cv::Mat swapped(view.rows, view.cols, CV_16UC1);
  for (int r = 0; r < view.rows; ++r) {
    const std::uint8_t* src = view.ptr<std::uint8_t>(r);
    auto* dst = swapped.ptr<std::uint16_t>(r);
    for (int c = 0; c < view.cols; ++c)
      dst[c] = static_cast<std::uint16_t>((src[2 * c] << 8) | src[2 * c + 1]);
  }
  return swapped;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

}  // namespace

const std::vector<std::string>& supportedImageEncodings() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : kEncodings) v.push_back(e.name);
    return v;
  }();
  return names;
}

std::string imageProblem(const logs::Image& image) {
  const EncodingInfo* e = findEncoding(image.encoding);
  if (!e)
    return "image encoding '" + image.encoding + "' cannot be read; expected one of " +
           detail::joinNames(supportedImageEncodings());
  if (image.width == 0 || image.height == 0)
    return "empty image (" + std::to_string(image.width) + "x" + std::to_string(image.height) + ")";
  if (image.width > (1u << 16) || image.height > (1u << 16))
    return "image size " + std::to_string(image.width) + "x" + std::to_string(image.height) +
           " is beyond 65536 pixels a side";
  const std::size_t row = static_cast<std::size_t>(image.width) * CV_ELEM_SIZE(e->cv_type);
  if (image.step < row)
    return "step " + std::to_string(image.step) + " is shorter than a row of " + std::to_string(image.width) + " " +
           image.encoding + " pixels (" + std::to_string(row) + " bytes)";
  const std::size_t need = static_cast<std::size_t>(image.step) * (image.height - 1) + row;
  if (image.data.size() < need)
    return "data holds " + std::to_string(image.data.size()) + " bytes, but step " + std::to_string(image.step) +
           " x height " + std::to_string(image.height) + " needs " + std::to_string(need);
  return "";
}

cv::Mat imageToGray(const logs::Image& image) {
  const EncodingInfo& e = *findEncoding(image.encoding);
  const cv::Mat px = pixels(image, e);
  cv::Mat grey;
  if (e.bayer_bgr >= 0) {
    cv::Mat bgr;
    cv::cvtColor(px, bgr, e.bayer_bgr);
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  } else if (image.encoding == "mono8") {
    grey = px.clone();
  } else if (image.encoding == "mono16") {
    grey.create(px.rows, px.cols, CV_8UC1);
    for (int r = 0; r < px.rows; ++r) {
      const auto* src = px.ptr<std::uint16_t>(r);
      auto* dst = grey.ptr<std::uint8_t>(r);
      for (int c = 0; c < px.cols; ++c) dst[c] = static_cast<std::uint8_t>(src[c] >> 8);
    }
  } else if (image.encoding == "rgb8") {
    cv::cvtColor(px, grey, cv::COLOR_RGB2GRAY);
  } else if (image.encoding == "bgr8") {
    cv::cvtColor(px, grey, cv::COLOR_BGR2GRAY);
  } else if (image.encoding == "rgba8") {
    cv::cvtColor(px, grey, cv::COLOR_RGBA2GRAY);
  } else {  // bgra8
    cv::cvtColor(px, grey, cv::COLOR_BGRA2GRAY);
  }
  return grey;
}

cv::Mat imageForPng(const logs::Image& image) {
  const EncodingInfo& e = *findEncoding(image.encoding);
  const cv::Mat px = pixels(image, e);
  cv::Mat out;
  if (e.bayer_bgr >= 0)
    cv::cvtColor(px, out, e.bayer_bgr);
  else if (image.encoding == "rgb8")
    cv::cvtColor(px, out, cv::COLOR_RGB2BGR);
  else if (image.encoding == "rgba8")
    cv::cvtColor(px, out, cv::COLOR_RGBA2BGRA);
  else
    out = px.clone();  // mono8, mono16 (native order), bgr8, bgra8
  return out;
}

std::string compressedImageFormat(const std::string& format) {
  const std::string f = lower(format);
  if (f.find("compresseddepth") != std::string::npos) return "";
  // "<encoding>; <container> compressed [<encoding>]" or the bare container.
  const auto semi = f.find(';');
  std::string rest = trim(semi == std::string::npos ? f : f.substr(semi + 1));
  rest = rest.substr(0, rest.find(' '));
  if (rest == "jpeg" || rest == "jpg") return "jpeg";
  if (rest == "png") return "png";
  return "";
}

cv::Mat compressedToGray(const logs::CompressedImage& image, vision::ExpectedSize expected) {
  if (image.data.empty()) return cv::Mat();
  // A damaged stream gives an empty image: the caller counts it as unreadable.
  return vision::decodeGrayChecked(image.data.data(), image.data.size(), expected);
}

std::string intrinsicsFromCameraInfo(const logs::CameraInfo& info, CameraConfig* camera) {
  const auto& K = info.k;
  if (K[1] != 0.0 || K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0)
    return "expected K = [fx, 0, cx, 0, fy, cy, 0, 0, 1] (no skew), got another matrix";
  if (!(K[0] > 0.0 && K[4] > 0.0 && std::isfinite(K[0]) && std::isfinite(K[4]) && std::isfinite(K[2]) &&
        std::isfinite(K[5])))
    return "expected fx > 0 and fy > 0 in K (a camera_info of zeros means the camera was never calibrated)";
  if (info.width == 0 || info.height == 0)
    return "width and height are 0; expected the resolution the intrinsics belong to";
  if (info.binning_x > 1 || info.binning_y > 1)
    return "binning " + std::to_string(info.binning_x) + "x" + std::to_string(info.binning_y) +
           " is not supported; expected 0 or 1 (the images at the calibrated resolution)";
  for (double d : info.d)
    if (!std::isfinite(d)) return "D holds a NaN or inf coefficient";
  static const char* kNames[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"};
  const std::vector<double>& d = info.d;
  std::string model;
  std::vector<double> coeffs;
  if (info.distortion_model == "plumb_bob" || info.distortion_model == "rational_polynomial") {
    const std::size_t most = info.distortion_model == "plumb_bob" ? 5 : 8;
    if (!d.empty() && (d.size() < 4 || d.size() > most))
      return "expected 4 to " + std::to_string(most) + " coefficients in D for " + info.distortion_model + ", got " +
             std::to_string(d.size());
    for (std::size_t i = 4; i < d.size(); ++i)
      if (d[i] != 0.0)
        return std::string("D's ") + kNames[i] + " = " + detail::formatDouble(d[i]) +
               " is not zero, but fgcal's radtan model has only [k1, k2, p1, p2]";
    model = "radtan";
    coeffs = d.empty() ? std::vector<double>(4, 0.0) : std::vector<double>(d.begin(), d.begin() + 4);
  } else if (info.distortion_model == "equidistant") {
    if (d.size() != 4)
      return "expected 4 coefficients [k1, k2, k3, k4] in D for equidistant, got " + std::to_string(d.size());
    model = "equidistant";
    coeffs = d;
  } else {
    return "distortion_model '" + info.distortion_model + "' is not supported; expected plumb_bob, "
           "rational_polynomial (k3..k6 zero) or equidistant";
  }
  camera->distortion_model = model;
  camera->distortion_coeffs = coeffs;
  camera->intrinsics = {K[0], K[4], K[2], K[5]};
  camera->resolution = {static_cast<int>(info.width), static_cast<int>(info.height)};
  return "";
}

bool sameIntrinsics(const logs::CameraInfo& a, const logs::CameraInfo& b) {
  return a.k == b.k && a.d == b.d && a.distortion_model == b.distortion_model && a.width == b.width &&
         a.height == b.height && a.binning_x == b.binning_x && a.binning_y == b.binning_y;
}

JointStateCollector::JointStateCollector(std::vector<std::string> keep) : keep_(std::move(keep)) {}

std::string JointStateCollector::add(const logs::JointState& m, std::uint64_t storage_index) {
  if (m.position.empty() && !m.name.empty()) {
    ++without_positions_;
    return "";
  }
  if (m.position.size() != m.name.size())
    return "expected one position per joint name, got " + std::to_string(m.name.size()) + " names and " +
           std::to_string(m.position.size()) + " positions";
  scratch_.clear();
  for (std::size_t i = 0; i < m.name.size(); ++i) {
    const auto [it, added] = column_of_.emplace(m.name[i], static_cast<int>(names_.size()));
    if (added) {
      names_.push_back(m.name[i]);
      const auto k = std::find(keep_.begin(), keep_.end(), m.name[i]);
      kept_column_.push_back(keep_.empty() ? it->second
                             : k == keep_.end() ? -1
                                                : static_cast<int>(k - keep_.begin()));
    }
    if (std::find(scratch_.begin(), scratch_.end(), it->second) != scratch_.end())
      return "joint '" + m.name[i] + "' is named twice in one message";
    scratch_.push_back(it->second);
  }
  samples_.push_back({m.header.stamp_ns, storage_index, static_cast<std::uint32_t>(positions_.size())});
  for (std::size_t i = 0; i < scratch_.size(); ++i) {
    const int column = kept_column_[static_cast<std::size_t>(scratch_[i])];
    if (column < 0) continue;
    columns_.push_back(static_cast<std::uint32_t>(column));
    positions_.push_back(std::isfinite(m.position[i]) ? m.position[i] : std::nan(""));
  }
  return "";
}

JointLog JointStateCollector::finish(std::size_t* duplicates) const {
  std::vector<std::size_t> order(samples_.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Sample &sa = samples_[a], &sb = samples_[b];
    return sa.stamp_ns != sb.stamp_ns ? sa.stamp_ns < sb.stamp_ns : sa.index < sb.index;
  });
  // The table's columns: every joint, or the kept ones that were seen.
  const std::size_t width = keep_.empty() ? names_.size() : keep_.size();
  JointLog log;
  log.names = keep_.empty() ? names_ : keep_;
  std::size_t rows = 0;
  for (std::size_t k = 0; k < order.size(); ++k)
    if (k == 0 || samples_[order[k]].stamp_ns != samples_[order[k - 1]].stamp_ns) ++rows;
  Eigen::MatrixXd positions(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(width));
  log.stamps_ns.reserve(rows);
  Eigen::RowVectorXd current = Eigen::RowVectorXd::Constant(static_cast<Eigen::Index>(width), std::nan(""));
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t s = order[k];
    const std::size_t end = s + 1 < samples_.size() ? samples_[s + 1].begin : positions_.size();
    // Later messages of the same stamp overwrite the joints they carry (sorted by index).
    for (std::size_t j = samples_[s].begin; j < end; ++j) current[columns_[j]] = positions_[j];
    const bool last_of_stamp = k + 1 == order.size() || samples_[order[k + 1]].stamp_ns != samples_[s].stamp_ns;
    if (!last_of_stamp) continue;
    positions.row(static_cast<Eigen::Index>(log.stamps_ns.size())) = current;
    log.stamps_ns.push_back(samples_[s].stamp_ns);
  }
  if (duplicates) *duplicates = samples_.size() - rows;
  if (keep_.empty()) {
    log.positions = std::move(positions);
    return log;
  }
  // Only the kept joints that were seen: a chain joint the bag lacks is then
  // missing from the table as it would be from a joints.csv.
  std::vector<Eigen::Index> seen;
  log.names.clear();
  for (std::size_t c = 0; c < keep_.size(); ++c)
    if (column_of_.count(keep_[c])) {
      seen.push_back(static_cast<Eigen::Index>(c));
      log.names.push_back(keep_[c]);
    }
  log.positions = positions(Eigen::all, seen);
  log.source_names = names_;
  return log;
}

}  // namespace fgcal::apps
