// Central-difference Jacobians through the retraction, for any pair of
// manifold types: column i is (f(x) ⊖ f(x ⊕ h e_i) - f(x) ⊖ f(x ⊕ -h e_i)) / 2h.
// Used by the tests of every group operation and factor, and by the
// optimizer's check_jacobians option.
#pragma once

#include <Eigen/Core>

#include "fgcal/core/manifold.hpp"

namespace fgcal {

template <class In, class F>
MatX numericalJacobian(F&& f, const In& x, double h = 1e-6) {
  using Out = std::decay_t<decltype(f(x))>;
  const Out y0 = f(x);
  const int n = Manifold<In>::dim(x);
  const int m = Manifold<Out>::dim(y0);
  MatX J(m, n);
  VecX d = VecX::Zero(n);
  for (int i = 0; i < n; ++i) {
    d[i] = h;
    const auto yp = Manifold<Out>::minus(y0, f(Manifold<In>::plus(x, d)));
    d[i] = -h;
    const auto ym = Manifold<Out>::minus(y0, f(Manifold<In>::plus(x, d)));
    d[i] = 0.0;
    J.col(i) = (yp - ym) / (2.0 * h);
  }
  return J;
}

}  // namespace fgcal
