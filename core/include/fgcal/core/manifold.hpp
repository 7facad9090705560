// The manifold contract, written once: for every variable type T,
// Manifold<T> gives its tangent dimension, plus (retraction x ⊕ d) and minus
// (the d with x ⊕ d = y). Adding a variable type to fgcal means specializing
// this template; the optimizer never needs to change.
#pragma once

#include <Eigen/Core>

#include "fgcal/core/se3.hpp"

namespace fgcal {

template <class T>
struct Manifold;  // specialize: kDim (or Eigen::Dynamic), dim(x), plus(x, d), minus(x, y)

template <>
struct Manifold<SE3> {
  static constexpr int kDim = 6;
  static int dim(const SE3&) { return 6; }
  template <class D>
  static SE3 plus(const SE3& x, const Eigen::MatrixBase<D>& d) {
    return x.plus(Vec6(d));
  }
  static Vec6 minus(const SE3& x, const SE3& y) { return x.minus(y); }
};

template <>
struct Manifold<SO3> {
  static constexpr int kDim = 3;
  static int dim(const SO3&) { return 3; }
  template <class D>
  static SO3 plus(const SO3& x, const Eigen::MatrixBase<D>& d) {
    return x.plus(Vec3(d));
  }
  static Vec3 minus(const SO3& x, const SO3& y) { return x.minus(y); }
};

/// R^n, fixed or dynamic size: plus and minus are + and -.
template <int N>
struct Manifold<Eigen::Matrix<double, N, 1>> {
  using V = Eigen::Matrix<double, N, 1>;
  static constexpr int kDim = N;
  static int dim(const V& x) { return static_cast<int>(x.size()); }
  template <class D>
  static V plus(const V& x, const Eigen::MatrixBase<D>& d) {
    return x + d;
  }
  static V minus(const V& x, const V& y) { return y - x; }
};

}  // namespace fgcal
