// How the library's own factors and the noise model's whitening loops read W
// without a copy: its upper triangle as NoiseModel stores it, column by
// column, W(i, k) for i <= k at index k (k + 1) / 2 + i (zero off the
// diagonal of a diagonal model).
#pragma once

#include "fgcal/core/noise_model.hpp"

namespace fgcal::internal {

struct NoiseModelAccess {
  /// dim() (dim() + 1) / 2 entries.
  static const double* upperTriangle(const NoiseModel& noise) { return noise.upper_.get(); }
  /// The index of W(i, k), i <= k, in upperTriangle().
  static constexpr int upperIndex(int i, int k) { return k * (k + 1) / 2 + i; }
};

}  // namespace fgcal::internal
