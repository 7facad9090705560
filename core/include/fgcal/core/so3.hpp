// SO(3): rotations, with exp/log stable near 0 and near pi, and the Jacobians
// of every operation under the right perturbation R ⊕ w = R * Exp(w).
// Jacobian names read J_out_in: J_result_a is d(result)/d(a) in tangent space.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "fgcal/core/types.hpp"

namespace fgcal {

inline Mat3 hat(const Vec3& w) {
  Mat3 m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

inline Vec3 vee(const Mat3& m) { return Vec3(m(2, 1), m(0, 2), m(1, 0)); }

class SO3 {
 public:
  static constexpr int DoF = 3;

  SO3() : R_(Mat3::Identity()) {}
  /// Takes a rotation matrix as it is; see fromMatrix for a checked version.
  explicit SO3(const Mat3& R) : R_(R) {}
  explicit SO3(const Eigen::Quaterniond& q) : R_(q.normalized().toRotationMatrix()) {}

  /// Checked construction: throws std::invalid_argument when R is not a rotation
  /// within tol (orthonormality and determinant +1); re-orthonormalizes otherwise.
  static SO3 fromMatrix(const Mat3& R, double tol = 1e-6) {
    if (!R.allFinite()) throw std::invalid_argument("rotation matrix holds NaN or inf");
    const double ortho = (R.transpose() * R - Mat3::Identity()).norm();
    if (ortho > tol || std::abs(R.determinant() - 1.0) > tol)
      throw std::invalid_argument("matrix is not a rotation (|R^T R - I| = " + std::to_string(ortho) +
                                  ", det = " + std::to_string(R.determinant()) + ")");
    return SO3(R).normalized();
  }

  static SO3 identity() { return SO3(); }

  /// Exp(w); J_R_w, when given, receives the right Jacobian Jr(w).
  static SO3 exp(const Vec3& w, Mat3* J_R_w = nullptr);
  /// Log(R) in (-pi, pi]; J_w_R, when given, receives Jr^-1(Log R).
  Vec3 log(Mat3* J_w_R = nullptr) const;

  static Mat3 rightJacobian(const Vec3& w);
  static Mat3 rightJacobianInverse(const Vec3& w);
  static Mat3 leftJacobian(const Vec3& w) { return rightJacobian(-w); }
  static Mat3 leftJacobianInverse(const Vec3& w) { return rightJacobianInverse(-w); }

  const Mat3& matrix() const { return R_; }
  Eigen::Quaterniond quaternion() const { return Eigen::Quaterniond(R_); }
  Mat3 adjoint() const { return R_; }

  SO3 inverse(Mat3* J_inv_R = nullptr) const {
    if (J_inv_R) *J_inv_R = -R_;
    return SO3(R_.transpose());
  }

  SO3 compose(const SO3& other, Mat3* J_out_this = nullptr, Mat3* J_out_other = nullptr) const {
    if (J_out_this) *J_out_this = other.R_.transpose();
    if (J_out_other) J_out_other->setIdentity();
    return SO3(R_ * other.R_);
  }
  SO3 operator*(const SO3& other) const { return SO3(R_ * other.R_); }

  /// this^-1 * other.
  SO3 between(const SO3& other, Mat3* J_out_this = nullptr, Mat3* J_out_other = nullptr) const {
    const Mat3 D = R_.transpose() * other.R_;
    if (J_out_this) *J_out_this = -D.transpose();
    if (J_out_other) J_out_other->setIdentity();
    return SO3(D);
  }

  Vec3 act(const Vec3& p, Mat3* J_out_R = nullptr, Mat3* J_out_p = nullptr) const {
    if (J_out_R) *J_out_R = -R_ * hat(p);
    if (J_out_p) *J_out_p = R_;
    return R_ * p;
  }
  Vec3 operator*(const Vec3& p) const { return R_ * p; }

  SO3 plus(const Vec3& w) const { return SO3(R_ * exp(w).R_); }
  /// The w with this ⊕ w = other.
  Vec3 minus(const SO3& other) const { return between(other).log(); }

  SO3 normalized() const {
    Eigen::JacobiSVD<Mat3> svd(R_, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 R = svd.matrixU() * svd.matrixV().transpose();
    if (R.determinant() < 0) {
      Mat3 U = svd.matrixU();
      U.col(2) *= -1.0;
      R = U * svd.matrixV().transpose();
    }
    return SO3(R);
  }

  /// Roll, pitch, yaw (URDF convention: R = Rz(yaw) Ry(pitch) Rx(roll)).
  Vec3 rpy() const;
  static SO3 fromRpy(double roll, double pitch, double yaw);

 private:
  Mat3 R_;
};

// Inline: small, and free of the series (exp, log and the Jacobians are in src/).

inline Vec3 SO3::rpy() const {
  const Mat3& R = R_;
  const double c = std::hypot(R(0, 0), R(1, 0));  // |cos(pitch)|
  const double pitch = std::atan2(-R(2, 0), c);
  if (c <= 1e-12) {  // gimbal lock: only yaw - roll (or yaw + roll) is defined; put it all into yaw
    return Vec3(0.0, pitch, std::atan2(-R(0, 1), R(1, 1)));
  }
  // Near the lock yaw alone is ill-conditioned (R(1,0) and R(0,0) are both
  // tiny), and so is roll from R(2,1), R(2,2): independent errors of ~eps/c in
  // each would not cancel. Taking roll from Rz(yaw)^T R = Ry(pitch) Rx(roll),
  // whose rows 1 are [0 cos(roll) -sin(roll)] at any pitch, makes it absorb
  // yaw's error, so that Rz(yaw) Ry(pitch) Rx(roll) gives R back to ~eps.
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double roll = std::atan2(sy * R(0, 2) - cy * R(1, 2), cy * R(1, 1) - sy * R(0, 1));
  return Vec3(roll, pitch, yaw);
}

inline SO3 SO3::fromRpy(double roll, double pitch, double yaw) {
  const Eigen::AngleAxisd rx(roll, Vec3::UnitX()), ry(pitch, Vec3::UnitY()), rz(yaw, Vec3::UnitZ());
  return SO3((rz * ry * rx).toRotationMatrix());
}

}  // namespace fgcal
