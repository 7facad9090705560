// RelativePoseFactor's construction and the solver's fast path for it.
#include "fgcal/factors/relative_pose_factor.hpp"

#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/factors/internal/whitened_log.hpp"

namespace fgcal {

RelativePoseFactor::RelativePoseFactor(Key a, Key b, const SE3& measured, NoiseModel::Ptr noise,
                                       RobustKernel::Ptr robust)
    : TypedFactor({a, b}, std::move(noise), std::move(robust)), measured_inverse_(measured.inverse()) {
  registerFastPath();
}

void RelativePoseFactor::registerFastPath() {
  // H and g straight from the 6x6 block of the B side: with U = W Jlog and
  // Ad = Ad(D^-1) (D = A^-1 B), so that J_A = -U Ad,
  //   H_BB = U^T U,  H_AB = -Ad^T H_BB,  H_AA = Ad^T H_BB Ad,
  //   g_B = U^T W r,  g_A = -Ad^T g_B,
  // without whitening J_A or forming J_A^T J_A and J_A^T J_B from it. Two
  // at once: the B sides' blocks by whitenedLogBlockPair, the A sides' from
  // them as above.
  struct FastPath final : internal::NormalEquations {
    static const SE3& pose(const Variable* v) { return static_cast<const TypedVariable<SE3>*>(v)->value(); }
    void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      const auto& f = static_cast<const RelativePoseFactor&>(factor);
      const SE3 D = pose(vars[0]).between(pose(vars[1]));
      if (!detail::whitenedLogBlock(f.noiseModel(), f.measured_inverse_.compose(D), r, g ? g[1] : nullptr,
                                    g ? H[2] : nullptr))
        return;
      detail::inverseAdjointSide(D, H[2], g[1], H[0], H[1], g[0]);
    }
    bool pairs() const override { return true; }
    void whitenedPair(const Factor& a, const Factor& b, const Variable* const* vars_a, const Variable* const* vars_b,
                      double* r_a, double* const* g_a, double* const* H_a, double* r_b, double* const* g_b,
                      double* const* H_b) const override {
      const auto& fa = static_cast<const RelativePoseFactor&>(a);
      const auto& fb = static_cast<const RelativePoseFactor&>(b);
      const SE3 D_a = pose(vars_a[0]).between(pose(vars_a[1]));
      const SE3 D_b = pose(vars_b[0]).between(pose(vars_b[1]));
      detail::whitenedLogBlockPair(fa.noiseModel(), fa.measured_inverse_.compose(D_a), fb.noiseModel(),
                                   fb.measured_inverse_.compose(D_b), r_a, g_a ? g_a[1] : nullptr,
                                   g_a ? H_a[2] : nullptr, r_b, g_b ? g_b[1] : nullptr, g_b ? H_b[2] : nullptr);
      if (!g_a) return;
      detail::inverseAdjointSide(D_a, H_a[2], g_a[1], H_a[0], H_a[1], g_a[0]);
      detail::inverseAdjointSide(D_b, H_b[2], g_b[1], H_b[0], H_b[1], g_b[0]);
    }
  };
  static const FastPath path;
  static const bool registered = (internal::registerNormalEquations(typeid(RelativePoseFactor), path), true);
  (void)registered;
}

}  // namespace fgcal
