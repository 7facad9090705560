// Prior on a camera's intrinsics vector K = [fx fy cx cy, distortion
// coefficients] (the variable CornerFactor estimates): r = K - K0, with the
// prior's per-entry sigmas.
// The variable is the fixed-size vector CornerFactor::insertIntrinsics puts in
// Values (4, 8 or 9 entries).
#pragma once

#include "fgcal/core/factor.hpp"

namespace fgcal {

class IntrinsicsPriorFactor final : public Factor {
 public:
  /// Throws std::invalid_argument unless `sigmas` has the size of `prior`
  /// (4, 8 or 9) and every sigma is finite and > 0.
  IntrinsicsPriorFactor(Key intrinsics, const VecX& prior, const VecX& sigmas);

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const override;
  const VecX& prior() const { return prior_; }

 private:
  VecX prior_;
};

}  // namespace fgcal
