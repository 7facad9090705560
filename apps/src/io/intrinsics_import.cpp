// Kalibr / ROS / OpenCV intrinsics importer (see intrinsics_import.hpp).
#include "fgcal/apps/intrinsics_import.hpp"

#include <algorithm>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"
#include "io/text_format.hpp"
#include "io/yaml_read.hpp"

namespace fgcal::apps {

using detail::YNode;

namespace {

// Kalibr: one camera per camN key, fields named as in rig.yaml.
CameraConfig readKalibrCamera(const YNode& n, const std::string& name) {
  n.requireMap("a Kalibr camera (camera_model, distortion_model, intrinsics, distortion_coeffs, resolution)");
  CameraConfig c;
  c.name = name;
  const YNode cm = n.at("camera_model", "one of: " + detail::joinNames(supportedCameraModels()));
  c.camera_model = cm.string();
  const auto& models = supportedCameraModels();
  if (std::find(models.begin(), models.end(), c.camera_model) == models.end())
    cm.fail("expected one of: " + detail::joinNames(models) + " (fgcal's camera models); got " + cm.found());
  const YNode dm = n.at("distortion_model", "one of: " + detail::joinNames(supportedDistortionModels()));
  c.distortion_model = dm.string();
  const int ncoeff = distortionCoeffCount(c.distortion_model);
  if (ncoeff < 0)
    dm.fail("expected one of: " + detail::joinNames(supportedDistortionModels()) + " (fgcal's distortion models); got " +
            dm.found());
  const YNode in = n.at("intrinsics", "[fx, fy, cx, cy]");
  if (in.listSize("4 numbers [fx, fy, cx, cy]") != 4)
    in.fail("expected 4 numbers [fx, fy, cx, cy], got " + in.found());
  for (std::size_t i = 0; i < 4; ++i) c.intrinsics[i] = i < 2 ? in[i].positive() : in[i].number();
  const YNode dc = n.at("distortion_coeffs", std::to_string(ncoeff) + " numbers");
  c.distortion_coeffs = dc.numbers();
  if (c.distortion_coeffs.size() != static_cast<std::size_t>(ncoeff))
    dc.fail("expected " + std::to_string(ncoeff) + " numbers for distortion_model " + c.distortion_model + ", got " +
            std::to_string(c.distortion_coeffs.size()));
  const YNode res = n.at("resolution", "[width, height]");
  if (res.listSize("2 integers [width, height]") != 2) res.fail("expected 2 integers [width, height], got " + res.found());
  c.resolution = {res[0].integer(1), res[1].integer(1)};
  return c;
}

// An OpenCV/ROS matrix: {rows, cols, data} (OpenCV adds dt and a tag).
Eigen::MatrixXd readCvMatrix(const YNode& n) {
  n.requireMap("a matrix {rows, cols, data}");
  const int rows = n.at("rows", "the number of rows").integer(1);
  const int cols = n.at("cols", "the number of columns").integer(1);
  const YNode d = n.at("data", "rows x cols numbers, row-major");
  const std::vector<double> v = d.numbers();
  if (v.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols))
    d.fail("expected " + std::to_string(rows * cols) + " numbers (rows x cols = " + std::to_string(rows) + " x " +
           std::to_string(cols) + "), got " + std::to_string(v.size()));
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) m(r, c) = v[static_cast<std::size_t>(r * cols + c)];
  return m;
}

// OpenCV's coefficient order: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]].
// Only the first four are in fgcal's radtan model; the rest must be zero.
std::vector<double> radtanFromOpenCv(const YNode& where, const std::vector<double>& d) {
  static const char* kNames[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tx", "ty"};
  const std::size_t n = d.size();
  if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
    where.fail("expected 4, 5, 8, 12 or 14 OpenCV distortion coefficients (k1 k2 p1 p2 [k3 ...]), got " +
               std::to_string(n));
  for (std::size_t i = 4; i < n; ++i)
    if (d[i] != 0.0)
      where.fail(std::string("coefficient ") + kNames[i] + " = " + detail::formatDouble(d[i]) +
                 " is not zero, but fgcal's radtan model has only [k1, k2, p1, p2]; re-calibrate the intrinsics "
                 "with k3 fixed to 0 (OpenCV flag CALIB_FIX_K3) or with Kalibr's pinhole-radtan");
  return {d[0], d[1], d[2], d[3]};
}

CameraConfig readOpenCvOrRos(const YNode& root, const std::string& default_name) {
  CameraConfig c;
  const YNode cname = root.maybe("camera_name");
  c.name = cname.node.IsDefined() ? cname.string() : default_name;
  const YNode km = root.at("camera_matrix", "the 3x3 camera matrix {rows, cols, data}");
  const Eigen::MatrixXd K = readCvMatrix(km);
  if (K.rows() != 3 || K.cols() != 3)
    km.fail("expected a 3x3 camera matrix, got " + std::to_string(K.rows()) + "x" + std::to_string(K.cols()));
  if (K(0, 1) != 0.0 || K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
    km.fail("expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew), got another matrix");
  if (!(K(0, 0) > 0.0 && K(1, 1) > 0.0)) km.fail("expected fx > 0 and fy > 0");
  c.intrinsics = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};

  const YNode dn = root.at("distortion_coefficients", "the distortion coefficients {rows, cols, data}");
  const Eigen::MatrixXd D = readCvMatrix(dn);
  const std::vector<double> d(D.data(), D.data() + D.size());  // a row or a column: same order
  const YNode dm = root.maybe("distortion_model");
  const std::string model = dm.node.IsDefined() ? dm.string() : "plumb_bob";  // OpenCV files: OpenCV's own model
  if (model == "plumb_bob" || model == "rational_polynomial") {
    c.distortion_model = "radtan";
    c.distortion_coeffs = radtanFromOpenCv(dn, d);
  } else if (model == "equidistant" || model == "fisheye") {
    if (d.size() != 4) dn.fail("expected 4 coefficients [k1, k2, k3, k4] for " + model + ", got " + std::to_string(d.size()));
    c.distortion_model = "equidistant";
    c.distortion_coeffs = d;
  } else {
    dm.fail("expected plumb_bob, rational_polynomial or equidistant, got " + dm.found());
  }
  const YNode w = root.maybe("image_width"), h = root.maybe("image_height");
  if (!w.node.IsDefined() || !h.node.IsDefined())
    root.fail("expected image_width and image_height (the resolution the intrinsics belong to); this file lacks "
              "them: add them, or write the camera into rig.yaml by hand");
  c.resolution = {w.integer(1), h.integer(1)};
  return c;
}

}  // namespace

std::vector<CameraConfig> parseIntrinsics(const std::string& text, const std::string& file, double pixel_sigma,
                                          const std::string& default_name) {
  if (!(pixel_sigma > 0.0))
    throw InputError(file, "", "pixel_sigma for the imported cameras must be > 0, got " + detail::formatDouble(pixel_sigma));
  const YNode root = detail::parseYaml(text, file);
  root.requireMap("a Kalibr camchain (cam0: ...), a ROS camera_info or an OpenCV calibration file");
  std::vector<CameraConfig> cams;
  if (root.has("camera_matrix")) {
    cams.push_back(readOpenCvOrRos(root, default_name));
  } else {
    for (auto it = root.node.begin(); it != root.node.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "";
      const bool camN = key.size() > 3 && key.compare(0, 3, "cam") == 0 &&
                        std::all_of(key.begin() + 3, key.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
      if (camN) cams.push_back(readKalibrCamera(YNode{it->second, file, key}, key));
    }
    if (cams.empty())
      root.fail("expected a Kalibr camchain (keys cam0, cam1, ...), a ROS camera_info or an OpenCV calibration "
                "file (key camera_matrix); found neither");
  }
  for (auto& c : cams) c.pixel_sigma = pixel_sigma;
  return cams;
}

std::vector<CameraConfig> importIntrinsics(const std::string& path, double pixel_sigma,
                                           const std::string& default_name) {
  return parseIntrinsics(readTextFile(path, "intrinsics file"), path, pixel_sigma, default_name);
}

}  // namespace fgcal::apps
