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

namespace internal {
struct NoiseModelAccess;  // the solver's own factors whiten from the stored triangle (core/internal)
}

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

  int dim() const { return dim_; }
  bool isDiagonal() const { return diagonal_; }

  /// W, an upper-triangular square root of the information: W^T W = Sigma^-1.
  MatX sqrtInformation() const;
  MatX information() const;
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
  friend struct internal::NoiseModelAccess;
  struct Shared;  // built by make_shared: the object and its count in one allocation
  NoiseModel(const MatX& W, bool diagonal);  // W read from its upper triangle

  // A graph of a long recording holds one model per factor (10^5 and more):
  // W's upper triangle packed column by column, 6x6 in 216 bytes with the object.
  std::unique_ptr<double[]> upper_;
  int dim_ = 0;
  bool diagonal_ = false;
};

}  // namespace fgcal
