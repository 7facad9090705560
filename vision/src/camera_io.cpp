// OpenCV FileStorage calibration files -> CameraModel.
#include "fgcal/vision/camera_io.hpp"

#include <fstream>

#include <opencv2/core.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

CameraModel readOpenCvCamera(const std::string& path, int width, int height) {
  // Checked first: OpenCV would also log its own error line for a missing file.
  if (!std::ifstream(path).good()) throw VisionError("cannot open camera file '" + path + "'");
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw VisionError("cannot read camera file '" + path +
                      "': not an OpenCV FileStorage file (a YAML file needs a '%YAML:1.0' first "
                      "line): " + e.what());
  }
  if (!fs.isOpened()) throw VisionError("cannot open camera file '" + path + "'");
  const auto fail = [&](const std::string& field, const std::string& what) {
    return VisionError(path + ": " + field + ": " + what);
  };
  cv::Mat K, D;
  try {
    fs["camera_matrix"] >> K;
    fs["distortion_coefficients"] >> D;
  } catch (const cv::Exception& e) {
    throw fail("camera_matrix / distortion_coefficients", std::string("unreadable: ") + e.what());
  }
  if (K.empty() || K.rows != 3 || K.cols != 3)
    throw fail("camera_matrix", "expected a 3x3 matrix");
  K.convertTo(K, CV_64F);
  if (K.at<double>(0, 1) != 0.0) throw fail("camera_matrix", "skew is not supported (K[0][1] != 0)");
  std::vector<double> d;
  if (!D.empty()) {
    if (D.rows != 1 && D.cols != 1) throw fail("distortion_coefficients", "expected a vector");
    D.convertTo(D, CV_64F);
    d.assign(D.begin<double>(), D.end<double>());
  }
  if (d.size() > 5) {
    for (size_t i = 5; i < d.size(); ++i)
      if (d[i] != 0.0)
        throw fail("distortion_coefficients",
                   "only [k1 k2 p1 p2 k3] is supported; coefficient " + std::to_string(i + 1) +
                       " of " + std::to_string(d.size()) + " is not zero");
    d.resize(5);
  }
  if (d.size() == 5 && d[4] == 0.0) d.resize(4);
  if (!d.empty() && d.size() != 4 && d.size() != 5)
    throw fail("distortion_coefficients",
               "expected 4 or 5 values, got " + std::to_string(d.size()));
  const bool has_size = !fs["image_width"].empty() && !fs["image_height"].empty();
  if (has_size) {
    width = static_cast<int>(fs["image_width"]);
    height = static_cast<int>(fs["image_height"]);
  } else if (width <= 0 || height <= 0) {
    throw fail("image_width / image_height",
               "missing; pass the resolution to readOpenCvCamera(path, width, height)");
  }
  const Distortion model = d.empty() ? Distortion::None : Distortion::RadTan;
  try {
    return CameraModel(Projection::Pinhole, model, K.at<double>(0, 0), K.at<double>(1, 1),
                       K.at<double>(0, 2), K.at<double>(1, 2), d, width, height);
  } catch (const VisionError& e) {
    throw VisionError(path + ": " + e.what());
  }
}

}  // namespace fgcal::vision
