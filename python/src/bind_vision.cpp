// Cameras and the ChArUco target from Python: camera models (Kalibr's names)
// that project with Jacobians and unproject, detection of the board in a
// numpy image, PnP with the vertex-jitter covariance, and the board renderer
// (synthetic views for experiments and tests). Detection, PnP and rendering
// release the GIL.
#include <pybind11/numpy.h>

#include "bindings.hpp"
#include "fgcal/vision/board_renderer.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"

namespace fgcal::python {

namespace {

using namespace fgcal::vision;
using Image = py::array_t<std::uint8_t, py::array::c_style>;

// A cv::Mat over a numpy image's pixels (no copy): 8-bit, H x W or H x W x 3 (BGR).
cv::Mat matOf(const py::array& given, Image* keep) {
  if (!given.dtype().is(py::dtype::of<std::uint8_t>()))
    throw py::value_error("image: expected 8-bit pixels (numpy uint8), got dtype " +
                          std::string(py::str(given.dtype())));
  *keep = Image::ensure(given);  // C-contiguous (a copy only when the caller's array is not)
  const Image& a = *keep;
  if (a.ndim() == 2) return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), CV_8UC1,
                                    const_cast<std::uint8_t*>(a.data()));
  if (a.ndim() == 3 && a.shape(2) == 3)
    return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), CV_8UC3,
                   const_cast<std::uint8_t*>(a.data()));
  throw py::value_error("image: expected a grayscale (H x W) or BGR (H x W x 3) array, got " +
                        std::to_string(a.ndim()) + " dimensions" +
                        (a.ndim() == 3 ? " with " + std::to_string(a.shape(2)) + " channels" : std::string()));
}

py::array_t<std::uint8_t> arrayOf(const cv::Mat& gray) {
  if (gray.type() != CV_8UC1) throw std::logic_error("expected an 8-bit grayscale image");
  py::array_t<std::uint8_t> out({gray.rows, gray.cols});
  for (int r = 0; r < gray.rows; ++r) std::copy_n(gray.ptr<std::uint8_t>(r), gray.cols, out.mutable_data(r, 0));
  return out;
}

template <int N>
MatX rowsOf(const std::vector<Eigen::Matrix<double, N, 1>>& v) {
  MatX out(static_cast<Eigen::Index>(v.size()), N);
  for (std::size_t i = 0; i < v.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return out;
}

template <int N>
std::vector<Eigen::Matrix<double, N, 1>> vectorsOf(const MatX& m, const char* what) {
  if (m.cols() != N)
    throw py::value_error(std::string(what) + ": expected an array of shape (n, " + std::to_string(N) + "), got " +
                          std::to_string(m.cols()) + " columns");
  std::vector<Eigen::Matrix<double, N, 1>> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[static_cast<std::size_t>(i)] = m.row(i).transpose();
  return out;
}

PnpOptions pnpOptions(double pixel_sigma, const std::string& sigma_source, int max_iterations) {
  PnpOptions o;
  o.pixel_sigma = pixel_sigma;
  o.max_iterations = max_iterations;
  if (sigma_source == "pixel_sigma") o.sigma_source = PnpOptions::SigmaSource::PixelSigma;
  else if (sigma_source == "residuals") o.sigma_source = PnpOptions::SigmaSource::Residuals;
  else if (sigma_source == "larger") o.sigma_source = PnpOptions::SigmaSource::Larger;
  else throw py::value_error("sigma_source: expected 'pixel_sigma', 'residuals' or 'larger', got '" + sigma_source + "'");
  return o;
}

CornerRefinement refinementFromString(const std::string& s) {
  if (s == "corner_subpix") return CornerRefinement::CornerSubPix;
  if (s == "subtract_half_pixel") return CornerRefinement::SubtractHalfPixel;
  if (s == "none") return CornerRefinement::None;
  throw py::value_error("refinement: expected 'corner_subpix', 'subtract_half_pixel' or 'none', got '" + s + "'");
}

void bindCamera(py::module_& m) {
  py::class_<CameraModel>(m, "CameraModel", R"doc(
A camera model with Kalibr's names: camera_model 'pinhole', distortion_model
'radtan' [k1 k2 p1 p2 (k3)], 'equidistant' [k1 k2 k3 k4] or 'none' [].
Pixels in the pixel-centre convention of cv::projectPoints.
)doc")
      .def(py::init([](const std::vector<double>& intrinsics, const std::vector<int>& resolution,
                       const std::string& distortion_model, const std::vector<double>& distortion_coeffs,
                       const std::string& camera_model) {
             return CameraModel::fromKalibr(camera_model, distortion_model, intrinsics, distortion_coeffs,
                                            resolution);
           }),
           py::arg("intrinsics"), py::arg("resolution"), py::arg("distortion_model") = "none",
           py::arg("distortion_coeffs") = std::vector<double>{}, py::arg("camera_model") = "pinhole",
           "intrinsics [fx, fy, cx, cy], resolution [width, height]; InputError for values that do not fit.")
      .def(
          "project",
          [](const CameraModel& c, const Vec3& p, bool jacobian) -> py::object {
            Mat23 J;
            const auto uv = c.project(p, jacobian ? &J : nullptr);
            if (!uv) return py::none();
            if (!jacobian) return py::cast(Vec2(*uv));
            return py::make_tuple(Vec2(*uv), J);
          },
          py::arg("p_cam"), py::arg("jacobian") = false,
          "Pixel of a point in the camera frame, None behind the camera; with jacobian=True, (uv, d uv / d p) (2x3).")
      .def(
          "project_points",
          [](const CameraModel& c, const MatX& points) {
            const auto ps = vectorsOf<3>(points, "points");
            MatX out(points.rows(), 2);
            for (std::size_t i = 0; i < ps.size(); ++i) {
              const auto uv = c.project(ps[i]);
              out.row(static_cast<Eigen::Index>(i)) =
                  uv ? Eigen::RowVector2d(uv->transpose()) : Eigen::RowVector2d::Constant(std::nan(""));
            }
            return out;
          },
          py::arg("points"), "Pixels (n x 2) of points (n x 3) in the camera frame; NaN rows behind the camera.")
      .def(
          "unproject",
          [](const CameraModel& c, const Vec2& uv) -> py::object {
            const auto b = c.unproject(uv);
            return b ? py::cast(Vec3(*b)) : py::none();
          },
          py::arg("uv"), "Unit bearing of a pixel; None where the distortion cannot be inverted.")
      .def(
          "distort",
          [](const CameraModel& c, const Vec2& xy, bool jacobian) -> py::object {
            Mat2 J;
            const Vec2 d = c.distort(xy, &J);
            if (!jacobian) return py::cast(d);
            return py::make_tuple(d, J);
          },
          py::arg("xy"), py::arg("jacobian") = false,
          "Distorted normalized coordinates; with jacobian=True, (xy_d, d xy_d / d xy).")
      .def(
          "undistort",
          [](const CameraModel& c, const Vec2& xy) -> py::object {
            const auto u = c.undistort(xy);
            return u ? py::cast(Vec2(*u)) : py::none();
          },
          py::arg("xy_distorted"))
      .def_property_readonly("K", &CameraModel::K)
      .def_property_readonly("fx", &CameraModel::fx)
      .def_property_readonly("fy", &CameraModel::fy)
      .def_property_readonly("cx", &CameraModel::cx)
      .def_property_readonly("cy", &CameraModel::cy)
      .def_property_readonly("distortion_coeffs", &CameraModel::coeffs)
      .def_property_readonly("distortion_model", [](const CameraModel& c) { return toString(c.distortion()); })
      .def_property_readonly("camera_model", [](const CameraModel& c) { return toString(c.projection()); })
      .def_property_readonly("width", &CameraModel::width)
      .def_property_readonly("height", &CameraModel::height)
      .def("__repr__", [](const CameraModel& c) {
        return "<CameraModel " + toString(c.projection()) + "/" + toString(c.distortion()) + " " +
               std::to_string(c.width()) + "x" + std::to_string(c.height()) + ">";
      });
}

void bindTarget(py::module_& m) {
  py::class_<CharucoTarget>(m, "CharucoTarget",
                            "A ChArUco board as rig.yaml's target block describes it (metres, OpenCV dictionary "
                            "name); its frame is OpenCV 4.6's board frame.")
      .def(py::init([](int squares_x, int squares_y, double square_size, double marker_size,
                       const std::string& dictionary) {
             CharucoTarget t{squares_x, squares_y, square_size, marker_size, dictionary};
             t.validate();
             return t;
           }),
           py::arg("squares_x") = 5, py::arg("squares_y") = 7, py::arg("square_size") = 0.04,
           py::arg("marker_size") = 0.03, py::arg("dictionary") = "DICT_4X4_50")
      .def_readonly("squares_x", &CharucoTarget::squares_x)
      .def_readonly("squares_y", &CharucoTarget::squares_y)
      .def_readonly("square_size", &CharucoTarget::square_size)
      .def_readonly("marker_size", &CharucoTarget::marker_size)
      .def_readonly("dictionary", &CharucoTarget::dictionary)
      .def_property_readonly("corner_count", &CharucoTarget::cornerCount)
      .def(
          "corner_positions", [](const CharucoTarget& t) { return rowsOf<3>(t.cornerPositions()); },
          "Board-frame positions of the ChArUco corners (n x 3), row = corner id.")
      .def(
          "draw", [](const CharucoTarget& t, int px_per_square, int margin_px) {
            return arrayOf(drawTarget(t, px_per_square, margin_px));
          },
          py::arg("px_per_square") = 100, py::arg("margin_px") = 20, "OpenCV's drawing of the board (uint8).");
}

void bindDetection(py::module_& m) {
  py::class_<CharucoDetection>(m, "CharucoDetection")
      .def_property_readonly("status", [](const CharucoDetection& d) { return toString(d.status); })
      .def_property_readonly("ok", &CharucoDetection::ok)
      .def_readonly("message", &CharucoDetection::message, "Why the view was rejected (empty when ok).")
      .def_readonly("source", &CharucoDetection::source)
      .def_readonly("marker_ids", &CharucoDetection::marker_ids)
      .def_readonly("ids", &CharucoDetection::ids, "ChArUco corner ids, increasing.")
      .def_property_readonly(
          "corners", [](const CharucoDetection& d) { return rowsOf<2>(d.corners); }, "Pixels (n x 2).")
      .def_property_readonly(
          "object_points", [](const CharucoDetection& d) { return rowsOf<3>(d.object_points); },
          "Board-frame points (n x 3), same order as ids.")
      .def_readonly("width", &CharucoDetection::width)
      .def_readonly("height", &CharucoDetection::height)
      .def("__repr__", [](const CharucoDetection& d) {
        return "<CharucoDetection " + toString(d.status) + ", " + std::to_string(d.ids.size()) + " corners>";
      });

  py::class_<CharucoDetector>(m, "CharucoDetector",
                              "ChArUco detection with sub-pixel corners in the pixel-centre convention.")
      .def(py::init([](const CharucoTarget& target, int min_corners, const std::string& refinement,
                       double refine_blur_sigma, double collinear_fraction) {
             DetectorOptions o;
             o.min_corners = min_corners;
             o.refinement = refinementFromString(refinement);
             o.refine_blur_sigma = refine_blur_sigma;
             o.collinear_fraction = collinear_fraction;
             return CharucoDetector(target, o);
           }),
           py::arg("target"), py::arg("min_corners") = 6, py::arg("refinement") = "corner_subpix",
           py::arg("refine_blur_sigma") = 1.0, py::arg("collinear_fraction") = 0.25)
      .def_property_readonly("target", &CharucoDetector::target)
      .def(
          "detect",
          [](const CharucoDetector& d, const py::array& image) {
            Image keep;
            const cv::Mat mat = matOf(image, &keep);
            py::gil_scoped_release release;
            return d.detect(mat);
          },
          py::arg("image"),
          "Detection in a numpy image (uint8, H x W gray or H x W x 3 BGR). A rejected view comes back with "
          "status and message, never an exception. Releases the GIL.")
      .def(
          "detect_file",
          [](const CharucoDetector& d, const std::string& path) {
            py::gil_scoped_release release;
            return d.detectFile(path);
          },
          py::arg("path"), "Detection in an image file (read as grayscale). Releases the GIL.");
}

void bindPnp(py::module_& m) {
  py::class_<PoseEstimate>(m, "PoseEstimate")
      .def_property_readonly("T_cam_marker", [](const PoseEstimate& p) { return p.T_cam_marker.matrix(); })
      .def_readonly("covariance", &PoseEstimate::covariance,
                    "6x6, [w v], right perturbation of T_cam_marker: sigma^2 (J^T J)^-1.")
      .def_readonly("JtJ", &PoseEstimate::JtJ)
      .def_readonly("sigma_px", &PoseEstimate::sigma_px)
      .def_readonly("residual_sigma_px", &PoseEstimate::residual_sigma_px)
      .def_readonly("rms_px", &PoseEstimate::rms_px)
      .def_property_readonly(
          "residuals", [](const PoseEstimate& p) { return rowsOf<2>(p.residuals); },
          "project(T P_i) - uv_i per corner (n x 2).")
      .def_readonly("iterations", &PoseEstimate::iterations)
      .def_readonly("converged", &PoseEstimate::converged);

  m.def(
      "estimate_pose",
      [](const CameraModel& camera, const CharucoDetection& detection, double pixel_sigma,
         const std::string& sigma_source, int max_iterations) {
        const PnpOptions o = pnpOptions(pixel_sigma, sigma_source, max_iterations);
        py::gil_scoped_release release;
        return estimatePose(camera, detection, o);
      },
      py::arg("camera"), py::arg("detection"), py::arg("pixel_sigma") = 0.5, py::arg("sigma_source") = "pixel_sigma",
      py::arg("max_iterations") = 50,
      "T_cam_marker of a detection, with the vertex-jitter covariance. InputError when the detection is not ok. "
      "Releases the GIL.");
  m.def(
      "estimate_pose",
      [](const CameraModel& camera, const MatX& object_points, const MatX& pixels, double pixel_sigma,
         const std::string& sigma_source, int max_iterations) {
        const PnpOptions o = pnpOptions(pixel_sigma, sigma_source, max_iterations);
        const auto P = vectorsOf<3>(object_points, "object_points");
        const auto uv = vectorsOf<2>(pixels, "pixels");
        py::gil_scoped_release release;
        return estimatePose(camera, P, uv, o);
      },
      py::arg("camera"), py::arg("object_points"), py::arg("pixels"), py::arg("pixel_sigma") = 0.5,
      py::arg("sigma_source") = "pixel_sigma", py::arg("max_iterations") = 50,
      "T_cam_marker from matched board points (n x 3) and pixels (n x 2), n >= 4.");
}

void bindRendering(py::module_& m) {
  m.def(
      "render_board",
      [](const CameraModel& camera, const CharucoTarget& target, const Mat4& T_cam_marker, int supersampling,
         double blur_sigma, double noise_sigma, std::uint64_t seed, double corner_jitter_m) {
        RenderOptions o;
        o.supersampling = supersampling;
        o.blur_sigma = blur_sigma;
        o.noise_sigma = noise_sigma;
        o.seed = seed;
        o.corner_jitter_m = corner_jitter_m;
        o.jitter_seed = seed;
        const SE3 T = toSE3(T_cam_marker, "T_cam_marker");
        cv::Mat image;
        {
          py::gil_scoped_release release;
          image = renderBoard(camera, target, T, o);
        }
        return arrayOf(image);
      },
      py::arg("camera"), py::arg("target"), py::arg("T_cam_marker"), py::arg("supersampling") = 4,
      py::arg("blur_sigma") = 0.0, py::arg("noise_sigma") = 0.0, py::arg("seed") = 0,
      py::arg("corner_jitter_m") = 0.0,
      "The grayscale image (uint8, height x width) the camera sees of the board at T_cam_marker: supersampled, "
      "with optional blur, intensity noise and corner (vertex) jitter in metres. Releases the GIL.");
}

}  // namespace

void bindVision(py::module_& m) {
  bindCamera(m);
  bindTarget(m);
  bindDetection(m);
  bindPnp(m);
  bindRendering(m);
}

}  // namespace fgcal::python
