// Gaussian noise models: a residual r with covariance Sigma is whitened to
// W r with W^T W = Sigma^-1, so that every factor contributes 0.5 |W r|^2.
// Built from a full covariance, a full information matrix, per-axis sigmas or
// one sigma; anything that is not symmetric positive definite is rejected.
#pragma once

#include <memory>
#include <stdexcept>

#include <Eigen/Core>

#include "fgcal/core/types.hpp"

namespace fgcal {

/// Thrown for a covariance or information matrix that cannot define a noise model.
class InvalidNoiseModel : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class NoiseModel {
 public:
  using Ptr = std::shared_ptr<const NoiseModel>;

  /// Sigma must be square, finite, symmetric (relative 1e-9) and positive definite.
  static Ptr fromCovariance(const MatX& covariance);
  static Ptr fromInformation(const MatX& information);
  /// Per-axis standard deviations, all finite and > 0.
  static Ptr diagonal(const VecX& sigmas);
  static Ptr isotropic(int dim, double sigma);

  int dim() const { return static_cast<int>(sqrt_information_.rows()); }
  bool isDiagonal() const { return diagonal_; }

  /// W, an upper-triangular square root of the information: W^T W = Sigma^-1.
  const MatX& sqrtInformation() const { return sqrt_information_; }
  MatX information() const { return sqrt_information_.transpose() * sqrt_information_; }
  MatX covariance() const;

  /// r <- W r for a residual of dim() entries.
  void whitenResidual(double* r) const;
  /// J <- W J for a dim() x cols column-major block whose columns are `stride` apart.
  void whitenJacobian(double* J, int cols, int stride) const;

  VecX whiten(const VecX& r) const {
    VecX out = r;
    whitenResidual(out.data());
    return out;
  }

 private:
  NoiseModel(MatX sqrt_information, bool diagonal)
      : sqrt_information_(std::move(sqrt_information)), diag_(sqrt_information_.diagonal()), diagonal_(diagonal) {}
  MatX sqrt_information_;
  VecX diag_;
  bool diagonal_;
};

}  // namespace fgcal
