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

  int dim() const { return dim_; }
  bool isDiagonal() const { return diagonal_; }

  /// W, an upper-triangular square root of the information: W^T W = Sigma^-1.
  MatX sqrtInformation() const;
  /// W's upper triangle as stored, column by column: W(i, k) for i <= k at
  /// index k (k + 1) / 2 + i, dim() (dim() + 1) / 2 entries (zero off the
  /// diagonal of a diagonal model). For loops that whiten without a copy.
  const double* upperTriangle() const { return upper_.get(); }
  /// The index of W(i, k), i <= k, in upperTriangle().
  static constexpr int upperIndex(int i, int k) { return k * (k + 1) / 2 + i; }
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
  struct Token {  // lets make_shared build one in a single allocation with its count
    explicit Token() = default;
  };

 public:
  /// Use the factories above; W is read from its upper triangle.
  NoiseModel(Token, const MatX& W, bool diagonal);

 private:
  // A graph of a long recording holds one model per factor (10^5 and more):
  // the packed triangle and the object in two allocations, 6x6 in 216 bytes.
  std::unique_ptr<double[]> upper_;
  int dim_ = 0;
  bool diagonal_ = false;
};

}  // namespace fgcal
