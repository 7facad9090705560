// A prior on SE(3) whose evaluate() is right but whose fast path, a
// registered internal one, takes Log's Jacobian to be the identity (a common
// shortcut, exact only at a zero residual): what checkFactorJacobians and
// OptimizerOptions::check_jacobians must catch, since the solver uses the
// fast path, not evaluate().
#pragma once

#include "fgcal/core/factor.hpp"
#include "fgcal/core/internal/normal_equations.hpp"

namespace fgcal::test {

class SloppyPrior final : public TypedFactor<6, SE3> {
 public:
  SloppyPrior(Key k, const SE3& measured, NoiseModel::Ptr noise)
      : TypedFactor({k}, std::move(noise)), measured_(measured) {
    static const FastPath path;
    internal::registerNormalEquations(typeid(SloppyPrior), path);
  }
  Residual evaluateTyped(const SE3& X, Jacobian<SE3>* J) const override {
    Mat6 Jlog;
    const Vec6 r = measured_.between(X).log(J ? &Jlog : nullptr);
    if (J) *J = Jlog;
    return r;
  }

 private:
  struct FastPath final : internal::NormalEquations {
    void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      const auto& f = static_cast<const SloppyPrior&>(factor);
      const SE3& X = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
      Eigen::Map<Vec6> rw(r);
      rw = f.measured_.between(X).log();
      f.noiseModel().whitenResidual(r);
      if (!g) return;
      const Mat6 W = f.noiseModel().sqrtInformation();  // J taken as W I
      Eigen::Map<Vec6> g0(g[0]);
      Eigen::Map<Mat6> H00(H[0]);
      g0 = W.transpose() * rw;
      H00 = W.transpose() * W;
    }
  };
  SE3 measured_;
};

}  // namespace fgcal::test
