// The fgcal Python module (fgcal._fgcal, re-exported by the package fgcal):
// the exception classes, the translation of the library's exceptions into
// them, and the bind functions of each area.
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/vision/vision_error.hpp"

namespace fgcal::python {

namespace {
Errors g_errors;

py::handle newException(const char* name, const char* doc, py::handle bases) {
  PyObject* type = PyErr_NewExceptionWithDoc(name, doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  return type;  // one reference kept for the life of the process, like every exception type
}

// Sets `type` as the current Python exception, with `message` and the attributes given.
void setError(py::handle type, const std::string& message, const py::dict& attributes = {}) {
  py::object exc = py::reinterpret_borrow<py::object>(type)(message);
  for (const auto& item : attributes) exc.attr(item.first) = item.second;
  PyErr_SetObject(type.ptr(), exc.ptr());
}

// An InputError with what it names as attributes (.file, .location, .detail).
void setInputError(const apps::InputError& e) {
  py::dict attrs;
  attrs["file"] = e.file();
  attrs["location"] = e.location();
  attrs["detail"] = e.detail();
  setError(g_errors.input_error, e.what(), attrs);
}
}  // namespace

const Errors& errors() { return g_errors; }

SE3 toSE3(const Mat4& T, const char* what, double tol) {
  try {
    SE3::fromMatrix(T, tol);  // the check only; the value is taken as given
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(what) + ": " + e.what());
  }
  return SE3(T);
}

SO3 toSO3(const Mat3& R, const char* what, double tol) {
  try {
    SO3::fromMatrix(R, tol);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(what) + ": " + e.what());
  }
  return SO3(R);
}

void raiseAsCommandLine(const std::exception& e) {
  if (const auto* in = dynamic_cast<const apps::InputError*>(&e))
    setInputError(*in);
  else
    setError(apps::exitCodeFor(e) == 2 ? g_errors.input_error : g_errors.data_error, e.what());
  throw py::error_already_set();
}

}  // namespace fgcal::python

PYBIND11_MODULE(_fgcal, m) {
  namespace py = pybind11;
  using namespace fgcal::python;
  m.doc() = "fgcal's C++ library: the factor-graph solver, robot kinematics, cameras and the calibration pipeline";

  g_errors.error = newException("fgcal.Error", "Base class of the errors fgcal raises for its own reasons.",
                                PyExc_Exception);
  g_errors.input_error = newException(
      "fgcal.InputError",
      "Bad input or usage (the fgcal command's exit code 2): the message names the file, the field or line, and "
      "what was expected. Also a ValueError.",
      py::make_tuple(g_errors.error, py::handle(PyExc_ValueError)));
  g_errors.data_error = newException(
      "fgcal.DataError",
      "Valid input that cannot support a result (the fgcal command's exit code 1): too few detections, no "
      "convergence, ...; the message says why. Also a RuntimeError.",
      py::make_tuple(g_errors.error, py::handle(PyExc_RuntimeError)));
  m.attr("Error") = g_errors.error;
  m.attr("InputError") = g_errors.input_error;
  m.attr("DataError") = g_errors.data_error;

  // Library exceptions thrown outside the pipeline's own translation
  // (bind_pipeline.cpp), by class: a robot description, joint values or
  // camera parameters the caller gave are bad input.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const fgcal::apps::InputError& e) {
      setInputError(e);
    } catch (const fgcal::apps::DataError& e) {
      PyErr_SetString(g_errors.data_error.ptr(), e.what());
    } catch (const fgcal::kinematics::KinematicsError& e) {
      PyErr_SetString(g_errors.input_error.ptr(), e.what());
    } catch (const fgcal::vision::VisionError& e) {
      PyErr_SetString(g_errors.input_error.ptr(), e.what());
    }
  });

  bindGeometry(m);
  bindGraph(m);
  bindKinematics(m);
  bindVision(m);
  bindPipeline(m);
}
