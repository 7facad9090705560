// What the binding files of the fgcal Python module share: one bind function
// per area (each in its own translation unit, since pybind11 units are slow to
// compile), the conversions between numpy arrays and fgcal's types, and the
// module's exception classes.
//
// numpy is imported only when an array is converted, never at module import:
// `import fgcal; fgcal.__version__` works in a Python without numpy.
#pragma once

#include <string>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "fgcal/core/se3.hpp"

namespace fgcal::python {

namespace py = pybind11;

void bindGeometry(py::module_& m);    // bind_geometry.cpp: fgcal.so3, fgcal.se3, keys
void bindGraph(py::module_& m);       // bind_graph.cpp: values, noise, kernels, factors, graph, optimize, marginals
void bindKinematics(py::module_& m);  // bind_kinematics.cpp: RobotModel, KinematicChain
void bindVision(py::module_& m);      // bind_vision.cpp: cameras, ChArUco detection, PnP, rendering
void bindPipeline(py::module_& m);    // bind_pipeline.cpp: simulate, calibrate, evaluate

/// A rigid transform from a 4x4 matrix, checked (rotation block orthonormal
/// with determinant +1 and last row [0 0 0 1], within `tol`) and taken as it
/// is, without re-orthonormalizing: results keep the caller's bits. Throws
/// std::invalid_argument (ValueError) naming `what` otherwise.
SE3 toSE3(const Mat4& T, const char* what, double tol = 1e-6);
/// The same for a rotation matrix.
SO3 toSO3(const Mat3& R, const char* what, double tol = 1e-6);

/// The module's exception classes (set up in module.cpp): fgcal.Error, and its
/// subclasses InputError (also a ValueError: bad input, the command line's
/// exit code 2) and DataError (also a RuntimeError: data that cannot support
/// a result, exit code 1).
struct Errors {
  py::handle error, input_error, data_error;
};
const Errors& errors();

/// Raises the Python exception that the command line's exit code for `e`
/// stands for (fgcal::apps::exitCodeFor: 2 InputError, 1 DataError), with
/// e.what() as its message, exactly what `fgcal` prints after "fgcal: error: ".
/// An InputError also carries .file, .location and .detail.
[[noreturn]] void raiseAsCommandLine(const std::exception& e);

}  // namespace fgcal::python
