// Robust kernels rho(s) on the squared whitened residual s = |W r|^2, applied
// by iteratively reweighted least squares: each linearization scales the
// whitened residual and Jacobian by sqrt(rho'(s)).
#pragma once

#include <memory>
#include <string>

namespace fgcal {

class RobustKernel {
 public:
  using Ptr = std::shared_ptr<const RobustKernel>;
  virtual ~RobustKernel() = default;
  /// rho(s); rho(s) ~ s for small s so that unit-variance inliers cost as usual.
  virtual double rho(double s) const = 0;
  /// rho'(s), the IRLS weight.
  virtual double weight(double s) const = 0;
  virtual std::string name() const = 0;
};

/// Quadratic inside k, linear outside. Throws std::invalid_argument unless k > 0.
RobustKernel::Ptr huber(double k);
/// rho = k^2 log(1 + s/k^2).
RobustKernel::Ptr cauchy(double k);
/// Redescending: residuals beyond k get zero weight.
RobustKernel::Ptr tukey(double k);

}  // namespace fgcal
