// The one Jacobian checker every test uses: compares an analytic Jacobian with
// central differences through the retraction and says which block is wrong.
//
//   CHECK_JACOBIAN(J_analytic, [&](const SE3& a) { return a.compose(b); }, a);
//
#pragma once

#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "fgcal/core/numerical_jacobian.hpp"

namespace fgcal::test {

struct JacobianComparison {
  bool ok = true;
  double max_abs_error = 0.0;
  std::string message;  // empty when ok
};

/// Compares analytic vs numeric entry by entry with tolerance
/// tol * (1 + |numeric entry|) and reports the worst entry and block size.
JacobianComparison compareJacobians(const MatX& analytic, const MatX& numeric, double tol = 1e-6,
                                    const std::string& what = "Jacobian");

template <class In, class F>
JacobianComparison checkJacobian(const MatX& analytic, F&& f, const In& x, double tol = 1e-6,
                                 const std::string& what = "Jacobian") {
  return compareJacobians(analytic, numericalJacobian(std::forward<F>(f), x), tol, what);
}

/// Samples used at every check: identity, near identity, near pi, random.
std::vector<SE3> se3TestPoints(unsigned seed = 7, int random_count = 10);

}  // namespace fgcal::test

#define CHECK_JACOBIAN(analytic, f, x)                                               \
  do {                                                                               \
    const auto fgcal_cmp_ = ::fgcal::test::checkJacobian((analytic), (f), (x));      \
    INFO(fgcal_cmp_.message);                                                        \
    CHECK(fgcal_cmp_.ok);                                                            \
  } while (0)
