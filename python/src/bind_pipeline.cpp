// The calibration pipeline from Python: simulate, calibrate and evaluate, the
// library calls behind `fgcal simulate`, `fgcal calibrate` and `fgcal
// evaluate`. Keyword options are the command line's options in snake_case
// (--pixel-noise: pixel_noise), plus a few the library alone has; an error
// raises fgcal.InputError or fgcal.DataError with the message the command
// prints (the same exit-code classes). Each call releases the GIL.
#include <filesystem>
#include <functional>
#include <map>

#include <pybind11/functional.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "fgcal/apps/evaluate.hpp"
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
distortion, overwrite, camera_frames=[link, ...]; and supersampling,
image_width, image_height, render_images, cam1_delay_us,
camera_frame_offset_m, camera_frame_offset_rad, progress=f(camera, done, total).
Returns a SimulationSummary. Releases the GIL.
)doc");
}

// ---- evaluate ----

void bindEvaluate(py::module_& m) {
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

  m.def(
      "evaluate",
      [](const std::filesystem::path& calibration, const std::filesystem::path& ground_truth) {
        return runWithoutGil([&] {
          return evaluate(loadCalibrationYaml(calibration.string()), loadGroundTruth(ground_truth.string()));
        });
      },
      py::arg("result"), py::arg("ground_truth_path"),
      "Errors of a calibration (a calibration.yaml path) against a ground_truth.yaml (fgcal evaluate).");
}

}  // namespace

void bindPipeline(py::module_& m) {
  bindSimulate(m);
  bindEvaluate(m);
}

}  // namespace fgcal::python
