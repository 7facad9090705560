// The calibration pipeline from Python: simulate, calibrate and evaluate, the
// library calls behind `fgcal simulate`, `fgcal calibrate` and `fgcal
// evaluate`. Keyword options are the command line's options in snake_case
// (--pixel-noise: pixel_noise), plus a few the library alone has; an error
// raises fgcal.InputError or fgcal.DataError with the message the command
// prints (the same exit-code classes). Each call releases the GIL.
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>

#include <pybind11/functional.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"

namespace fgcal::python {

namespace {

using namespace fgcal::apps;

// ---- Keyword options: a table from name to setter per options struct, so
// that an option the library gains is one line here. ----

template <class O>
using Setter = std::function<void(O&, const py::handle&)>;
template <class O>
using OptionTable = std::vector<std::pair<std::string, Setter<O>>>;

template <class O, class T>
std::pair<std::string, Setter<O>> field(const std::string& name, T O::*member) {
  return {name, [member](O& o, const py::handle& v) { o.*member = v.cast<T>(); }};
}

template <class O>
void applyOptions(O& options, const py::kwargs& kwargs, const OptionTable<O>& table, const std::string& function) {
  for (const auto& item : kwargs) {
    const std::string name = py::str(item.first);
    const auto it = std::find_if(table.begin(), table.end(), [&](const auto& e) { return e.first == name; });
    if (it == table.end()) {
      std::string known;
      for (const auto& e : table) known += (known.empty() ? "" : ", ") + e.first;
      throw py::type_error(function + "() got an unexpected keyword argument '" + name + "' (options: " + known + ")");
    }
    try {
      it->second(options, item.second);
    } catch (const py::cast_error&) {
      throw py::type_error(function + "(): option '" + name + "' cannot take " +
                           std::string(py::str(py::type::of(item.second).attr("__name__"))) + " " +
                           std::string(py::repr(item.second)));
    }
  }
}

// Runs a library call without the GIL; its exceptions become the Python
// exceptions of the command line's exit codes (a Python callback's own
// exception passes through as it is).
template <class F>
auto runWithoutGil(F&& f) -> decltype(f()) {
  try {
    py::gil_scoped_release release;
    return f();
  } catch (const py::error_already_set&) {
    throw;
  } catch (const std::exception& e) {
    raiseAsCommandLine(e);
  }
}

// ---- simulate ----

const OptionTable<SimulationOptions>& simulationTable() {
  using S = SimulationOptions;
  static const OptionTable<S> table = {
      // The command line's options (fgcal simulate --help).
      field("urdf", &S::urdf_path),
      field("base_link", &S::base_link),
      field("marker_link", &S::marker_link),
      field("cameras", &S::cameras),
      field("frames", &S::frames),
      field("seed", &S::seed),
      field("pixel_noise", &S::pixel_noise),
      field("encoder_noise", &S::encoder_noise),
      {"mount_error",
       [](S& o, const py::handle& v) {
         const auto mm_deg = v.cast<std::pair<double, double>>();
         o.mount_error_m = mm_deg.first * 1e-3;
         o.mount_error_rad = mm_deg.second * M_PI / 180.0;
       }},
      field("distortion", &S::distortion),
      field("overwrite", &S::overwrite),
      field("camera_frames", &S::camera_frames),
      field("camera_delay_ms", &S::camera_delay_ms),
      field("joint_offsets", &S::joint_offsets_rad),
      {"intrinsics_error",
       [](S& o, const py::handle& v) {
         const auto pct_px = v.cast<std::pair<double, double>>();
         o.intrinsics_error_pct = pct_px.first;
         o.intrinsics_error_px = pct_px.second;
       }},
      field("fov_deg", &S::fov_deg),
      {"leg_origin_error",
       [](S& o, const py::handle& v) {
         const auto mm_deg = v.cast<std::pair<double, double>>();
         o.leg_origin_error_m = mm_deg.first * 1e-3;
         o.leg_origin_error_rad = mm_deg.second * M_PI / 180.0;
       }},
      {"backlash",  // a number for every joint of the marker chain, or {joint: rad}
       [](S& o, const py::handle& v) {
         if (py::isinstance<py::dict>(v)) {
           o.joint_backlash_rad = v.cast<std::map<std::string, double>>();
         } else {
           o.backlash_rad = v.cast<double>();
         }
       }},
      field("encoder_resolution", &S::encoder_resolution_rad),
      field("readout_ms", &S::readout_ms),
      field("exposure_ms", &S::exposure_ms),
      // The library's alone (fgcal/apps/simulator.hpp).
      field("supersampling", &S::supersampling),
      field("image_width", &S::image_width),
      field("image_height", &S::image_height),
      field("render_images", &S::render_images),
      field("cam1_delay_us", &S::cam1_delay_us),
      field("camera_frame_offset_m", &S::camera_frame_offset_m),
      field("camera_frame_offset_rad", &S::camera_frame_offset_rad),
      field("progress", &S::progress),
  };
  return table;
}

void bindSimulate(py::module_& m) {
  py::class_<SimulatedCameraSummary>(m, "SimulatedCamera")
      .def_readonly("name", &SimulatedCameraSummary::name)
      .def_readonly("images", &SimulatedCameraSummary::images)
      .def_readonly("board_in_view", &SimulatedCameraSummary::board_in_view)
      .def_property_readonly("T_base_cam", [](const SimulatedCameraSummary& c) { return c.T_base_cam.matrix(); });
  py::class_<SimulationSummary>(m, "SimulationSummary")
      .def_readonly("images_written", &SimulationSummary::images_written)
      .def_readonly("instants", &SimulationSummary::instants)
      .def_readonly("joint_samples", &SimulationSummary::joint_samples)
      .def_readonly("cameras", &SimulationSummary::cameras)
      .def_readonly("per_camera", &SimulationSummary::per_camera)
      .def_readonly("fraction_all_in_view", &SimulationSummary::fraction_all_in_view)
      .def_readonly("board_rotation_range_deg", &SimulationSummary::board_rotation_range_deg)
      .def_readonly("board_rotation_std_deg", &SimulationSummary::board_rotation_std_deg)
      .def_property_readonly("T_link_marker", [](const SimulationSummary& s) { return s.T_link_marker.matrix(); })
      .def_readonly("seconds", &SimulationSummary::seconds);

  m.def(
      "simulate",
      [](const std::filesystem::path& out, const py::kwargs& kwargs) {
        SimulationOptions o;
        o.out_dir = out.string();
        applyOptions(o, kwargs, simulationTable(), "simulate");
        return runWithoutGil([&] { return simulateDataset(o); });
      },
      py::arg("out"), R"doc(
Writes a synthetic dataset with ground truth into the folder `out` (fgcal
simulate): rig.yaml, joints.csv, robot.urdf, images, ground_truth.yaml.
Options as the command line's, in snake_case: urdf, base_link, marker_link,
cameras, frames, seed, pixel_noise, encoder_noise, mount_error=(mm, deg),
distortion, overwrite, camera_frames=[link, ...], camera_delay_ms={camera: ms},
joint_offsets={joint: rad}, intrinsics_error=(pct, px), fov_deg,
leg_origin_error=(mm, deg), backlash=rad or {joint: rad}, encoder_resolution=rad,
readout_ms={camera: ms}, exposure_ms; and supersampling,
image_width, image_height, render_images, cam1_delay_us,
camera_frame_offset_m, camera_frame_offset_rad, progress=f(camera, done, total).
Returns a SimulationSummary. Releases the GIL.
)doc");
}

// ---- evaluate ----

void bindEvaluationTypes(py::module_& m) {
  py::class_<PoseError>(m, "PoseError",
                        "Errors of a pose against the truth: per axis as in Table I (mm, deg), totals and NEES.")
      .def_readonly("x_mm", &PoseError::x_mm)
      .def_readonly("y_mm", &PoseError::y_mm)
      .def_readonly("z_mm", &PoseError::z_mm)
      .def_readonly("roll_deg", &PoseError::roll_deg)
      .def_readonly("pitch_deg", &PoseError::pitch_deg)
      .def_readonly("yaw_deg", &PoseError::yaw_deg)
      .def_readonly("translation_mm", &PoseError::translation_mm)
      .def_readonly("rotation_deg", &PoseError::rotation_deg)
      .def_readonly("nees", &PoseError::nees, "e^T Sigma^-1 e: about 6 on average when the covariance is honest.");
  py::class_<Evaluation>(m, "Evaluation")
      .def_readonly("cameras", &Evaluation::cameras, "Camera name -> PoseError.")
      .def_readonly("mount", &Evaluation::mount, "The board mount's PoseError, None when the truth lacks it.")
      .def("table", &formatEvaluationTable, "The table `fgcal evaluate` prints.")
      .def("__str__", &formatEvaluationTable);
}

// ---- calibrate ----

/// One image with a board pose: its fiducial factor at the solution.
struct ImageResidual {
  std::string camera;
  std::int64_t stamp_ns = 0;  // the image's stamp (a folder dataset: <camera>/<stamp_ns>.<ext>)
  bool used = false;
  std::string rejected;  // the chi-square gate's reason, empty when not rejected
  SE3 T_cam_marker;       // PnP, with its covariance
  Mat6 covariance = Mat6::Zero();
  double chi2 = std::numeric_limits<double>::quiet_NaN();
  Vec6 residual = Vec6::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// A camera's result with its corner residuals.
struct CameraCalibration {
  CameraResult result;
  MatX corner_residuals_px = MatX(0, 2);
};

/// What calibrate() returns: the library's result with the per-image
/// residuals and the cameras in rig order.
struct Calibration {
  CalibrateResult run;
  std::vector<CameraCalibration> cameras;
  std::vector<ImageResidual> images;
};

// The per-image residuals of the final solve: r = Log(Z^-1 X^-1 L) of each
// image's fiducial factor (RelativePoseFactor: Z = T_cam_marker from PnP, X
// the camera's pose, L the board pose of its instant), [w v].
std::vector<ImageResidual> imageResiduals(const CalibrationProblemInput& problem, const CalibrationSolution& sol) {
  std::map<std::string, SE3> camera_pose;
  for (const CameraEstimate& c : sol.cameras) camera_pose[c.name] = c.T_base_cam;
  std::map<std::size_t, std::string> rejected;
  for (const RejectedObservation& r : sol.rejected) rejected[r.observation] = r.reason;
  std::vector<ImageResidual> out;
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const BoardObservation& o = problem.observations[i];
    ImageResidual r;
    r.camera = problem.camera_names.at(static_cast<std::size_t>(o.camera));
    r.stamp_ns = o.stamp_ns;
    r.T_cam_marker = o.T_cam_marker;
    r.covariance = o.covariance;
    r.used = i < sol.used.size() && sol.used[i];
    if (rejected.count(i)) r.rejected = rejected[i];
    if (i < sol.fiducial_chi2.size()) r.chi2 = sol.fiducial_chi2[i];
    const int instant = i < sol.instant_of.size() ? sol.instant_of[i] : -1;
    const auto X = camera_pose.find(r.camera);
    if (instant >= 0 && X != camera_pose.end())
      r.residual = (o.T_cam_marker.inverse() * X->second.inverse() *
                    sol.instant_estimates.at(static_cast<std::size_t>(instant)).T_base_marker)
                       .log();
    out.push_back(std::move(r));
  }
  return out;
}

// method= and estimate= as the command line takes them: no method is pnp,
// or corners when the intrinsics are estimated (an explicit pnp with them is
// refused by the library, saying why); estimate is a list of names or one
// comma-separated string, parsed by the command's parser (its messages).
Method methodOf(const std::optional<std::string>& method, const EstimateSet& estimate) {
  if (method) return methodFromString(*method);
  return estimate.intrinsics ? Method::Corners : Method::Pnp;
}

std::string estimateList(const py::handle& v) {
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  std::string list;
  for (const std::string& name : v.cast<std::vector<std::string>>()) list += (list.empty() ? "" : ",") + name;
  return list;
}

struct CalibrateCall {
  CalibrateOptions options;
  std::string estimate;  // --estimate's comma-separated names
  bool verbose = false;
};

const OptionTable<CalibrateCall>& calibrateTable() {
  using C = CalibrateCall;
  auto option = [](auto member) {
    return [member](C& c, const py::handle& v) { c.options.*member = v.cast<std::decay_t<decltype(c.options.*member)>>(); };
  };
  auto output = [](auto member) {
    return [member](C& c, const py::handle& v) { c.options.robot_outputs.*member = v.cast<std::filesystem::path>().string(); };
  };
  static const OptionTable<C> table = {
      // The command line's options (fgcal calibrate --help).
      {"output", [](C& c, const py::handle& v) { c.options.output = v.cast<std::filesystem::path>().string(); }},
      {"cameras",
       [](C& c, const py::handle& v) {
         if (py::isinstance<py::str>(v)) {  // "a,b" as on the command line
           std::stringstream ss(v.cast<std::string>());
           c.options.cameras.clear();
           for (std::string name; std::getline(ss, name, ',');)
             if (!name.empty()) c.options.cameras.push_back(name);
         } else {
           c.options.cameras = v.cast<std::vector<std::string>>();
         }
       }},
      {"single_camera", option(&CalibrateOptions::single_camera)},
      {"fix_mount", option(&CalibrateOptions::fix_mount)},
      {"threads", option(&CalibrateOptions::threads)},
      {"pnp_covariance_scale", option(&CalibrateOptions::pnp_covariance_scale)},
      {"report", option(&CalibrateOptions::report)},
      {"report_dir", [](C& c, const py::handle& v) { c.options.report_dir = v.cast<std::filesystem::path>().string(); }},
      {"urdf_out", output(&RobotOutputOptions::urdf_out)},
      {"kalibr_out", output(&RobotOutputOptions::kalibr_out)},
      {"tf_out",  // a path, or a list of paths (--tf-out given more than once)
       [](C& c, const py::handle& v) {
         c.options.robot_outputs.tf_outs.clear();
         if (py::isinstance<py::str>(v) || !py::isinstance<py::sequence>(v))
           c.options.robot_outputs.tf_outs.push_back(v.cast<std::filesystem::path>().string());
         else
           for (const py::handle& p : v)
             c.options.robot_outputs.tf_outs.push_back(p.cast<std::filesystem::path>().string());
       }},
      {"estimate", [](C& c, const py::handle& v) { c.estimate = estimateList(v); }},
      // The module's own.
      {"verbose", [](C& c, const py::handle& v) { c.verbose = v.cast<bool>(); }},
  };
  return table;
}

Calibration calibrate(const std::filesystem::path& input, const std::optional<std::filesystem::path>& rig,
                      const std::optional<std::string>& method, const py::kwargs& kwargs) {
  CalibrateCall call;
  call.options.dataset = input.string();
  if (rig) call.options.rig = rig->string();
  call.options.output.clear();  // nothing written unless output= is given
  applyOptions(call, kwargs, calibrateTable(), "calibrate");
  call.options.write_files = !call.options.output.empty();
  try {
    call.options.estimate = parseEstimateSet(call.estimate);
    call.options.method = methodOf(method, call.options.estimate);
  } catch (const InputError& e) {
    raiseAsCommandLine(e);
  }
  return runWithoutGil([&] {
    call.options.trace.problem = true;
    call.options.trace.report_data = true;
    std::ostringstream quiet;
    Calibration c;
    c.run = runCalibrate(call.options, call.verbose ? static_cast<std::ostream&>(std::cerr) : quiet);
    CalibrationProblemInput problem = std::move(*c.run.trace.problem);
    ReportData report = std::move(*c.run.trace.report_data);
    c.run.trace = {};
    for (ReportCamera& rc : report.cameras) {
      CameraCalibration cam;
      cam.result = std::move(rc.result);
      cam.corner_residuals_px.resize(static_cast<Eigen::Index>(rc.residuals_px.size()), 2);
      for (std::size_t i = 0; i < rc.residuals_px.size(); ++i)
        cam.corner_residuals_px.row(static_cast<Eigen::Index>(i)) = rc.residuals_px[i].transpose();
      c.cameras.push_back(std::move(cam));
    }
    c.images = imageResiduals(problem, c.run.solution);
    return c;
  });
}

// None for what was not estimated.
py::object optionalVector(const std::vector<double>& v) {
  if (v.empty()) return py::none();
  return py::cast(Eigen::Map<const VecX>(v.data(), static_cast<Eigen::Index>(v.size())).eval());
}

// F1 or F2, from calibration.yaml's info (solve: "F1 (each camera alone)").
std::string solveOf(const CalibrationOutput& out) {
  for (const auto& [key, value] : out.info)
    if (key == "solve") return value.substr(0, 2);
  return "";
}

py::dict camerasOf(const Calibration& c) {
  py::dict d;
  for (const CameraCalibration& cam : c.cameras) d[py::str(cam.result.name)] = py::cast(cam);
  return d;
}

/// One camera's result.
void bindCameraCalibration(py::module_& m) {
  py::class_<CameraCalibration>(m, "CameraCalibration", "One camera's calibration, as calibration.yaml holds it.")
      .def_property_readonly("name", [](const CameraCalibration& c) { return c.result.name; })
      .def_property_readonly("T_base_cam", [](const CameraCalibration& c) { return c.result.T_base_cam.matrix(); })
      .def_property_readonly("covariance", [](const CameraCalibration& c) { return c.result.covariance; },
                             "6x6, [w v], right perturbation of T_base_cam.")
      .def_property_readonly(
          "sigma_mm_deg", [](const CameraCalibration& c) { return sigmaMmDeg(c.result.T_base_cam, c.result.covariance); },
          "1-sigma [x y z] mm, [roll pitch yaw] deg.")
      .def_property_readonly("xyz_rpy", [](const CameraCalibration& c) { return c.result.T_base_cam.xyzRpy(); })
      .def_property_readonly("images_used", [](const CameraCalibration& c) { return c.result.images_used; })
      .def_property_readonly("rms_reprojection_px", [](const CameraCalibration& c) { return c.result.rms_reprojection_px; })
      .def_property_readonly("images_skipped", [](const CameraCalibration& c) { return c.result.images_skipped; },
                             "Reason -> count.")
      .def_property_readonly(
          "intrinsics", [](const CameraCalibration& c) { return optionalVector(c.result.intrinsics); },
          "Estimated [fx fy cx cy] (estimate=['intrinsics']), else None.")
      .def_property_readonly("intrinsics_sigma",
                             [](const CameraCalibration& c) { return optionalVector(c.result.intrinsics_sigma); })
      .def_property_readonly(
          "distortion_coeffs", [](const CameraCalibration& c) { return optionalVector(c.result.distortion_coeffs); },
          "Estimated distortion coefficients (rig.yaml's distortion_model), else None.")
      .def_property_readonly("distortion_coeffs_sigma", [](const CameraCalibration& c) {
        return optionalVector(c.result.distortion_coeffs_sigma);
      })
      .def_property_readonly(
          "time_offset_ms", [](const CameraCalibration& c) { return c.result.time_offset_ms; },
          "Estimated (estimate=['time-offset']): an image stamped t was exposed at t + offset; else None.")
      .def_property_readonly("time_offset_sigma_ms", [](const CameraCalibration& c) { return c.result.time_offset_sigma_ms; })
      .def_property_readonly(
          "readout_ms", [](const CameraCalibration& c) { return c.result.readout_ms; },
          "A rolling shutter's readout (first row's exposure start to the last's): estimated "
          "(estimate=['rolling-shutter'], with readout_sigma_ms), or rig.yaml's readout_ms held (sigma None); else None.")
      .def_property_readonly("readout_sigma_ms", [](const CameraCalibration& c) { return c.result.readout_sigma_ms; })
      .def_property_readonly("readout_observed", [](const CameraCalibration& c) { return c.result.readout_observed; },
                             "False when the data do not tell the estimated readout (the prior's value is reported).")
      .def_property_readonly(
          "sigma_from_urdf_mm_deg", [](const CameraCalibration& c) { return c.result.sigma_from_urdf_mm_deg; },
          "With robot.kinematic_sigma: how much of sigma_mm_deg the URDF's tolerance adds; else None.")
      .def_readonly("corner_residuals_px", &CameraCalibration::corner_residuals_px,
                    "Predicted - detected pixel of every corner of the images used (n x 2), the board posed by the "
                    "kinematics and the estimated mount and camera.")
      .def("__repr__", [](const CameraCalibration& c) { return "<CameraCalibration " + c.result.name + ">"; });
}

/// The mount, joint offsets and backlash, the kinematic origins, the relative poses.
void bindResultParts(py::module_& m) {
  py::class_<MountResult>(m, "MountCalibration", "The board mount T_link_marker.")
      .def_property_readonly("T_link_marker", [](const MountResult& r) { return r.T_link_marker.matrix(); })
      .def_readonly("covariance", &MountResult::covariance, "Zero when it was held fixed.")
      .def_readonly("estimated", &MountResult::estimated)
      .def_property_readonly("sigma_mm_deg",
                             [](const MountResult& r) { return sigmaMmDeg(r.T_link_marker, r.covariance); });

  py::class_<JointOffsetResult>(m, "JointOffset", "A joint's estimated zero offset: it stood at its reading + offset.")
      .def_readonly("joint", &JointOffsetResult::joint)
      .def_readonly("offset_rad", &JointOffsetResult::offset_rad)
      .def_readonly("sigma_rad", &JointOffsetResult::sigma_rad, "Marginal 1-sigma.")
      .def_readonly("observed", &JointOffsetResult::observed,
                    "False: the data do not observe it; offset and sigma are the prior's.")
      .def("__repr__", [](const JointOffsetResult& j) { return "<JointOffset " + j.joint + ">"; });

  py::class_<OriginResult>(m, "KinematicOrigin",
                           "A joint origin's correction (robot.kinematic_sigma): the URDF's origin times "
                           "Exp(correction), [wx wy wz vx vy vz].")
      .def_readonly("joint", &OriginResult::joint)
      .def_readonly("correction", &OriginResult::correction)
      .def_readonly("sigma", &OriginResult::sigma, "Marginal 1-sigma.")
      .def_readonly("observed", &OriginResult::observed, "Per component: False when it rests on the prior.")
      .def("__repr__", [](const OriginResult& o) { return "<KinematicOrigin " + o.joint + ">"; });

  py::class_<RelativePoseResult>(m, "RelativePose", "The pose of camera b in camera a, with its own covariance.")
      .def_readonly("a", &RelativePoseResult::a)
      .def_readonly("b", &RelativePoseResult::b)
      .def_property_readonly("T_a_b", [](const RelativePoseResult& r) { return r.T_a_b.matrix(); })
      .def_readonly("covariance", &RelativePoseResult::covariance, "6x6 [w v], right perturbation of T_a_b.")
      .def_property_readonly("sigma_mm_deg",
                             [](const RelativePoseResult& r) { return sigmaMmDeg(r.T_a_b, r.covariance); })
      .def("__repr__", [](const RelativePoseResult& r) { return "<RelativePose T_" + r.a + "_" + r.b + ">"; });
}

/// The quality block.
void bindQuality(py::module_& m) {
  py::class_<Finding>(m, "Finding", "One quality finding (docs/outputs.md, quality).")
      .def_readonly("check", &Finding::check, "A stable id, e.g. board_scale, mount_prior, joint_sign.")
      .def_property_readonly("severity", [](const Finding& f) { return std::string(toString(f.severity)); },
                             "note, check or unusable.")
      .def_readonly("fields", &Finding::fields, "rig.yaml fields or inputs to check, e.g. target.square_size.")
      .def_readonly("message", &Finding::message)
      .def_property_readonly(
          "estimate",
          [](const Finding& f) {
            py::dict d;
            for (const auto& [k, v] : f.estimate) d[py::str(k)] = v;
            return d;
          },
          "What the data suggest instead: name -> value as calibration.yaml writes it (text).")
      .def_readonly("command", &Finding::command, "The fgcal command that applies the fix, or ''.")
      .def("__repr__", [](const Finding& f) { return "<Finding " + std::string(toString(f.severity)) + " " + f.check + ">"; });

  py::class_<Quality>(m, "Quality", "The result's verdict on itself and its findings.")
      .def_property_readonly("verdict", [](const Quality& q) { return std::string(toString(q.verdict)); },
                             "ok, check or unusable.")
      .def_readonly("findings", &Quality::findings)
      .def("__repr__", [](const Quality& q) {
        return "<Quality " + std::string(toString(q.verdict)) + ", " + std::to_string(q.findings.size()) + " finding(s)>";
      });
}

/// Per-image residuals and the stage timings.
void bindRunParts(py::module_& m) {
  py::class_<ImageResidual>(m, "ImageResidual", "An image with a board pose, and its fiducial factor at the solution.")
      .def_readonly("camera", &ImageResidual::camera)
      .def_readonly("stamp_ns", &ImageResidual::stamp_ns)
      .def_readonly("used", &ImageResidual::used)
      .def_readonly("rejected", &ImageResidual::rejected, "The outlier gate's reason; empty when not rejected.")
      .def_property_readonly("T_cam_marker", [](const ImageResidual& r) { return r.T_cam_marker.matrix(); },
                             "The board pose from PnP.")
      .def_readonly("covariance", &ImageResidual::covariance,
                    "Its PnP covariance (6x6, [w v]), before pnp_covariance_scale.")
      .def_readonly("chi2", &ImageResidual::chi2,
                    "|W r|^2 against pnp_covariance_scale times its PnP covariance, in the last solve that had it.")
      .def_readonly("residual", &ImageResidual::residual,
                    "r = Log(T_cam_marker^-1 T_base_cam^-1 T_base_marker), [w v]; NaN when its instant was not solved.")
      .def("__repr__", [](const ImageResidual& r) {
        return "<ImageResidual " + r.camera + " " + std::to_string(r.stamp_ns) + (r.used ? "" : " (not used)") + ">";
      });

  py::class_<CalibrateTimings>(m, "CalibrateTimings", "Wall-clock seconds of the stages.")
      .def_readonly("load", &CalibrateTimings::load)
      .def_readonly("detection", &CalibrateTimings::detection)
      .def_readonly("decode", &CalibrateTimings::decode)
      .def_readonly("kinematics", &CalibrateTimings::kinematics)
      .def_readonly("solve", &CalibrateTimings::solve)
      .def_readonly("optimizer", &CalibrateTimings::optimizer)
      .def_readonly("output", &CalibrateTimings::output)
      .def_readonly("total", &CalibrateTimings::total)
      .def_readonly("report", &CalibrateTimings::report);
}

/// What calibrate() returns.
void bindCalibration(py::module_& m) {
  py::class_<Calibration>(m, "Calibration", "What calibrate() returns.")
      .def_property_readonly("cameras", &camerasOf, "Camera name -> CameraCalibration, in rig order.")
      .def_property_readonly("mount", [](const Calibration& c) { return c.run.output.mount; })
      .def_property_readonly("method", [](const Calibration& c) { return c.run.output.method; },
                             "pnp (a PnP pose factor per image) or corners (a factor per detected corner).")
      .def_property_readonly(
          "solve", [](const Calibration& c) { return solveOf(c.run.output); },
          "F1 (every camera alone) or F2 (jointly).")
      .def_property_readonly("estimated", [](const Calibration& c) { return c.run.output.estimated; },
                             "What was estimated beyond the poses and the mount (estimate=).")
      .def_property_readonly("joint_offsets", [](const Calibration& c) { return c.run.output.joint_offsets; },
                             "JointOffset of every movable joint of the marker chain (estimate=['joint-offsets']).")
      .def_property_readonly("backlash", [](const Calibration& c) { return c.run.output.backlash; },
                             "JointOffset of every movable joint of the marker chain, offset_rad holding the gear's "
                             "play (estimate=['backlash']).")
      .def_property_readonly("kinematic_origins",
                             [](const Calibration& c) { return c.run.output.kinematic_origins; },
                             "KinematicOrigin of every movable joint of the marker chain (robot.kinematic_sigma).")
      .def_property_readonly("relative_poses", [](const Calibration& c) { return c.run.output.relative_poses; },
                             "RelativePose of every pair of cameras, in rig order.")
      .def_property_readonly("instants", [](const Calibration& c) { return c.run.solution.instants; })
      .def_readonly("images", &Calibration::images, "Per image with a board pose: ImageResidual.")
      .def_property_readonly(
          "rejected",
          [](const Calibration& c) {
            py::list l;
            for (const RejectedImage& r : c.run.rejected) l.append(py::make_tuple(r.image, r.reason));
            return l;
          },
          "(image, reason) of the outliers the chi-square gate removed.")
      .def_property_readonly("quality", [](const Calibration& c) { return c.run.output.quality; },
                             "The verdict (ok, check, unusable) and findings; unusable: nothing was written.")
      .def_property_readonly("warnings", [](const Calibration& c) { return c.run.warnings; })
      .def_property_readonly("summary", [](const Calibration& c) { return c.run.summary; },
                             "The summary `fgcal calibrate` prints.")
      .def_property_readonly("info", [](const Calibration& c) { return c.run.output.info; },
                             "(key, value) pairs of calibration.yaml's info.")
      .def_property_readonly(
          "solves",
          [](const Calibration& c) {
            py::list l;
            for (std::size_t i = 0; i < c.run.solution.solves.size(); ++i)
              l.append(py::make_tuple(i < c.run.solution.solve_labels.size() ? c.run.solution.solve_labels[i] : "",
                                      c.run.solution.solves[i]));
            return l;
          },
          "(label, OptimizerResult) of every solve, in the order they ran; the last is the final one.")
      .def_property_readonly("evaluation", [](const Calibration& c) { return c.run.evaluation; },
                             "Errors against the dataset's ground_truth.yaml, None without one.")
      .def_property_readonly("ground_truth_path", [](const Calibration& c) { return c.run.ground_truth_path; })
      .def_property_readonly("yaml_path", [](const Calibration& c) { return c.run.yaml_path; })
      .def_property_readonly("urdf_path", [](const Calibration& c) { return c.run.urdf_path; })
      .def_property_readonly("report_path", [](const Calibration& c) { return c.run.report_path; })
      .def_property_readonly("robot_output_paths", [](const Calibration& c) { return c.run.robot_output_paths; })
      .def_property_readonly("timings", [](const Calibration& c) { return c.run.timings; })
      .def(
          "yaml", [](const Calibration& c) { return formatCalibrationYaml(c.run.output); },
          "The text of calibration.yaml for this result.")
      .def("__repr__", [](const Calibration& c) {
        return "<Calibration " + c.run.output.method + " " + solveOf(c.run.output) + ", " + std::to_string(c.cameras.size()) + " camera(s), " +
               std::to_string(c.run.solution.instants) + " instants>";
      });
}

void bindCalibrate(py::module_& m) {
  bindCameraCalibration(m);
  bindResultParts(m);
  bindQuality(m);
  bindRunParts(m);
  bindCalibration(m);
  m.def("calibrate", &calibrate, py::arg("dataset_or_bag"), py::arg("rig") = py::none(), py::arg("method") = py::none(),
        R"doc(
Calibrates the cameras (fgcal calibrate) from a dataset folder or a robot bag
(a ROS 1 .bag, a ROS 2 bag folder or an .mcap file; rig= is required for a
bag). method: 'pnp' (a PnP pose factor per image, the paper's method) or
'corners' (a reprojection factor per detected corner); None: pnp, or corners
when estimate has intrinsics. Options as the command line's, in snake_case:
output (calibration.yaml; nothing is written without it), cameras (a list or
'a,b'), single_camera (F1), fix_mount, threads, pnp_covariance_scale,
estimate (a list of 'time-offset', 'joint-offsets', 'intrinsics', or one
comma-separated string), report (False: no HTML report beside the output),
report_dir, urdf_out, kalibr_out, tf_out (a path, or a list of paths); and
verbose (progress and summary to stderr, as the command prints them). Returns a Calibration; raises
InputError / DataError with the command's message. Releases the GIL.
)doc");
}

void bindEvaluate(py::module_& m) {
  m.def(
      "evaluate",
      [](const Calibration& result, const std::filesystem::path& ground_truth) {
        return runWithoutGil([&] { return evaluate(result.run.output, loadGroundTruth(ground_truth.string())); });
      },
      py::arg("result"), py::arg("ground_truth_path"),
      "Errors of a calibration (what calibrate() returned) against a ground_truth.yaml.");
  m.def(
      "evaluate",
      [](const std::filesystem::path& calibration, const std::filesystem::path& ground_truth) {
        return runWithoutGil([&] {
          return evaluate(loadCalibrationYaml(calibration.string()), loadGroundTruth(ground_truth.string()));
        });
      },
      py::arg("result"), py::arg("ground_truth_path"),
      "Errors of a calibration.yaml against a ground_truth.yaml (fgcal evaluate).");
}

}  // namespace

void bindPipeline(py::module_& m) {
  bindSimulate(m);
  bindEvaluationTypes(m);
  bindCalibrate(m);
  bindEvaluate(m);
}

}  // namespace fgcal::python
