// fgcal.so3 and fgcal.se3: rotations and rigid transforms as numpy 3x3 and
// 4x4 matrices, with the library's conventions (docs/outputs.md): SE(3)
// tangent vectors [wx wy wz vx vy vz], right perturbation T ⊕ xi = T Exp(xi),
// Jacobians d(out)/d(in) in those tangent spaces. And the keys that name
// variables.
#include "bindings.hpp"
#include "fgcal/core/key.hpp"

namespace fgcal::python {

namespace {

// Python's tuple of an operation's result and its Jacobians, or the result
// alone when they were not asked for.
template <class Out, class... J>
py::object resultWith(bool jacobians, const Out& out, const J&... js) {
  if (!jacobians) return py::cast(out);
  return py::make_tuple(out, js...);
}

void bindSO3(py::module_& so3) {
  so3.doc() =
      "Rotations as numpy 3x3 matrices. Tangent vectors w are rotation vectors (axis * angle), perturbation on "
      "the right: R ⊕ w = R Exp(w). With jacobians=True a function also returns d(out)/d(in) in those tangent "
      "spaces. Matrices are checked (orthonormal, det +1, within 1e-6) and used as given.";
  so3.def(
      "exp",
      [](const Vec3& w, bool jacobians) {
        Mat3 J;
        const SO3 R = SO3::exp(w, &J);
        return resultWith(jacobians, R.matrix(), J);
      },
      py::arg("w"), py::arg("jacobians") = false,
      "Exp(w); with jacobians=True, (R, Jr(w)), Jr the right Jacobian.");
  so3.def(
      "log",
      [](const Mat3& R, bool jacobians) {
        Mat3 J;
        const Vec3 w = toSO3(R, "R").log(&J);
        return resultWith(jacobians, w, J);
      },
      py::arg("R"), py::arg("jacobians") = false,
      "Log(R) with angle in [0, pi]; with jacobians=True, (w, Jr^-1(w)).");
  so3.def(
      "compose",
      [](const Mat3& A, const Mat3& B, bool jacobians) {
        Mat3 JA, JB;
        const SO3 C = toSO3(A, "A").compose(toSO3(B, "B"), &JA, &JB);
        return resultWith(jacobians, C.matrix(), JA, JB);
      },
      py::arg("A"), py::arg("B"), py::arg("jacobians") = false,
      "A B; with jacobians=True, (A B, d/dA, d/dB).");
  so3.def(
      "inverse",
      [](const Mat3& R, bool jacobians) {
        Mat3 J;
        const SO3 inv = toSO3(R, "R").inverse(&J);
        return resultWith(jacobians, inv.matrix(), J);
      },
      py::arg("R"), py::arg("jacobians") = false, "R^-1; with jacobians=True, (R^-1, d/dR).");
  so3.def(
      "between",
      [](const Mat3& A, const Mat3& B, bool jacobians) {
        Mat3 JA, JB;
        const SO3 D = toSO3(A, "A").between(toSO3(B, "B"), &JA, &JB);
        return resultWith(jacobians, D.matrix(), JA, JB);
      },
      py::arg("A"), py::arg("B"), py::arg("jacobians") = false,
      "A^-1 B; with jacobians=True, (A^-1 B, d/dA, d/dB).");
  so3.def(
      "act",
      [](const Mat3& R, const Vec3& p, bool jacobians) {
        Mat3 JR, Jp;
        const Vec3 q = toSO3(R, "R").act(p, &JR, &Jp);
        return resultWith(jacobians, q, JR, Jp);
      },
      py::arg("R"), py::arg("p"), py::arg("jacobians") = false,
      "R p; with jacobians=True, (R p, d/dR, d/dp).");
  so3.def(
      "plus", [](const Mat3& R, const Vec3& w) { return toSO3(R, "R").plus(w).matrix(); }, py::arg("R"),
      py::arg("w"), "R Exp(w).");
  so3.def(
      "minus", [](const Mat3& A, const Mat3& B) { return toSO3(A, "A").minus(toSO3(B, "B")); }, py::arg("A"),
      py::arg("B"), "The w with A ⊕ w = B: Log(A^-1 B).");
  so3.def(
      "adjoint", [](const Mat3& R) { return toSO3(R, "R").adjoint(); }, py::arg("R"),
      "Ad(R) = R: R Exp(w) R^-1 = Exp(Ad(R) w).");
  so3.def("hat", &hat, py::arg("w"), "The skew-symmetric matrix of w: hat(w) p = w x p.");
  so3.def("vee", &vee, py::arg("W"), "The vector of a skew-symmetric matrix (inverse of hat).");
  so3.def("right_jacobian", &SO3::rightJacobian, py::arg("w"));
  so3.def("right_jacobian_inverse", &SO3::rightJacobianInverse, py::arg("w"));
  so3.def("left_jacobian", &SO3::leftJacobian, py::arg("w"));
  so3.def("left_jacobian_inverse", &SO3::leftJacobianInverse, py::arg("w"));
  so3.def(
      "rpy", [](const Mat3& R) { return toSO3(R, "R").rpy(); }, py::arg("R"),
      "[roll, pitch, yaw] with R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's convention).");
  so3.def(
      "from_rpy", [](double roll, double pitch, double yaw) { return SO3::fromRpy(roll, pitch, yaw).matrix(); },
      py::arg("roll"), py::arg("pitch"), py::arg("yaw"), "Rz(yaw) Ry(pitch) Rx(roll).");
}

/// The SE(3) Jacobians of a tangent vector, and the URDF xyz-rpy and R, t forms of a pose.
void bindSE3Jacobians(py::module_& se3) {
  se3.def("right_jacobian", &SE3::rightJacobian, py::arg("xi"));
  se3.def("right_jacobian_inverse", &SE3::rightJacobianInverse, py::arg("xi"));
  se3.def("left_jacobian", &SE3::leftJacobian, py::arg("xi"));
  se3.def("left_jacobian_inverse", &SE3::leftJacobianInverse, py::arg("xi"));
  se3.def(
      "xyz_rpy", [](const Mat4& T) { return toSE3(T, "T").xyzRpy(); }, py::arg("T"),
      "[x, y, z, roll, pitch, yaw], what a URDF <origin xyz rpy> holds.");
  se3.def(
      "from_xyz_rpy", [](const Vec3& xyz, const Vec3& rpy) { return SE3::fromXyzRpy(xyz, rpy).matrix(); },
      py::arg("xyz"), py::arg("rpy"), "The transform of a URDF <origin xyz rpy>.");
  se3.def(
      "from_rotation_translation",
      [](const Mat3& R, const Vec3& t) { return SE3(toSO3(R, "R"), t).matrix(); }, py::arg("R"), py::arg("t"),
      "The 4x4 [[R t] [0 1]].");
}

void bindSE3(py::module_& se3) {
  se3.doc() =
      "Rigid transforms as numpy 4x4 matrices. T_a_b maps points of frame b into frame a. Tangent vectors are "
      "[wx wy wz vx vy vz] (rotation first), perturbation on the right: T ⊕ xi = T Exp(xi). With jacobians=True "
      "a function also returns d(out)/d(in) in those tangent spaces. Matrices are checked (rotation block "
      "orthonormal with det +1, last row [0 0 0 1], within 1e-6) and used as given.";
  se3.def(
      "exp",
      [](const Vec6& xi, bool jacobians) {
        Mat6 J;
        const SE3 T = SE3::exp(xi, &J);
        return resultWith(jacobians, T.matrix(), J);
      },
      py::arg("xi"), py::arg("jacobians") = false,
      "Exp([w v]); with jacobians=True, (T, Jr(xi)), Jr the right Jacobian.");
  se3.def(
      "log",
      [](const Mat4& T, bool jacobians) {
        Mat6 J;
        const Vec6 xi = toSE3(T, "T").log(&J);
        return resultWith(jacobians, xi, J);
      },
      py::arg("T"), py::arg("jacobians") = false, "Log(T) as [w v]; with jacobians=True, (xi, Jr^-1(xi)).");
  se3.def(
      "compose",
      [](const Mat4& A, const Mat4& B, bool jacobians) {
        Mat6 JA, JB;
        const SE3 C = toSE3(A, "A").compose(toSE3(B, "B"), &JA, &JB);
        return resultWith(jacobians, C.matrix(), JA, JB);
      },
      py::arg("A"), py::arg("B"), py::arg("jacobians") = false,
      "A B; with jacobians=True, (A B, d/dA, d/dB).");
  se3.def(
      "inverse",
      [](const Mat4& T, bool jacobians) {
        Mat6 J;
        const SE3 inv = toSE3(T, "T").inverse(&J);
        return resultWith(jacobians, inv.matrix(), J);
      },
      py::arg("T"), py::arg("jacobians") = false, "T^-1; with jacobians=True, (T^-1, d/dT = -Ad(T)).");
  se3.def(
      "between",
      [](const Mat4& A, const Mat4& B, bool jacobians) {
        Mat6 JA, JB;
        const SE3 D = toSE3(A, "A").between(toSE3(B, "B"), &JA, &JB);
        return resultWith(jacobians, D.matrix(), JA, JB);
      },
      py::arg("A"), py::arg("B"), py::arg("jacobians") = false,
      "A^-1 B; with jacobians=True, (A^-1 B, d/dA, d/dB).");
  se3.def(
      "act",
      [](const Mat4& T, const Vec3& p, bool jacobians) {
        Mat36 JT;
        Mat3 Jp;
        const Vec3 q = toSE3(T, "T").act(p, &JT, &Jp);
        return resultWith(jacobians, q, JT, Jp);
      },
      py::arg("T"), py::arg("p"), py::arg("jacobians") = false,
      "R p + t; with jacobians=True, (T p, d/dT (3x6), d/dp (3x3)).");
  se3.def(
      "plus", [](const Mat4& T, const Vec6& xi) { return toSE3(T, "T").plus(xi).matrix(); }, py::arg("T"),
      py::arg("xi"), "T Exp(xi).");
  se3.def(
      "minus", [](const Mat4& A, const Mat4& B) { return toSE3(A, "A").minus(toSE3(B, "B")); }, py::arg("A"),
      py::arg("B"), "The xi with A ⊕ xi = B: Log(A^-1 B), [w v].");
  se3.def(
      "adjoint", [](const Mat4& T) { return toSE3(T, "T").adjoint(); }, py::arg("T"),
      "Ad(T) in [w v] order, [[R 0] [t^ R  R]]: T Exp(xi) T^-1 = Exp(Ad(T) xi).");
  bindSE3Jacobians(se3);
}

}  // namespace

void bindGeometry(py::module_& m) {
  py::module_ so3 = m.def_submodule("so3");
  bindSO3(so3);
  py::module_ se3 = m.def_submodule("se3");
  bindSE3(se3);

  m.def(
      "key",
      [](const std::string& symbol, std::uint64_t index) {
        if (symbol.size() != 1) throw std::invalid_argument("key(): the symbol must be one character, got '" + symbol + "'");
        if (index > 0x00FFFFFFFFFFFFFFull) throw std::invalid_argument("key(): the index must be below 2^56");
        return key(symbol[0], index);
      },
      py::arg("symbol"), py::arg("index"),
      "The key of a variable: a character and an index packed in 64 bits, e.g. key('c', 0).");
  m.def(
      "key_symbol", [](Key k) { return std::string(1, keySymbol(k)); }, py::arg("key"));
  m.def("key_index", &keyIndex, py::arg("key"));
  m.def("key_to_string", &keyToString, py::arg("key"), "'c0', 'b1234'; a key without a printable symbol as its number.");
}

}  // namespace fgcal::python
