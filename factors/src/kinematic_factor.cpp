// KinematicFactor's construction and the solver's fast path for it.
#include "fgcal/factors/kinematic_factor.hpp"

#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/factors/internal/whitened_log.hpp"

namespace fgcal {

KinematicFactor::KinematicFactor(Key board, Key mount, const SE3& T_base_link, NoiseModel::Ptr noise,
                                 RobustKernel::Ptr robust)
    : TypedFactor({board, mount}, std::move(noise), std::move(robust)), T_link_base_(T_base_link.inverse()) {
  registerFastPath();
}

void KinematicFactor::registerFastPath() {
  // H and g straight from the board side's block (J_L = Jr^-1 of the
  // residual) and, for the mount (D = M^-1 (T_base_link L), J_M = -J_L
  // Ad(D^-1)), from that block through Ad, as for RelativePoseFactor.
  struct FastPath final : internal::NormalEquations {
    static const SE3& pose(const Variable* v) { return static_cast<const TypedVariable<SE3>*>(v)->value(); }
    void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      const auto& f = static_cast<const KinematicFactor&>(factor);
      const SE3 D = pose(vars[1]).between(f.T_link_base_.compose(pose(vars[0])));
      if (!detail::whitenedLogBlock(f.noiseModel(), D, r, g ? g[0] : nullptr, g ? H[0] : nullptr)) return;
      Mat6 H_ML;  // the mount's rows, the board's columns; the factor's pair (0, 1) is its transpose
      detail::inverseAdjointSide(D, H[0], g[0], H[2], H_ML.data(), g[1]);
      Eigen::Map<Mat6> H_LM(H[1]);
      H_LM = H_ML.transpose();
    }
  };
  static const FastPath path;
  static const bool registered = (internal::registerNormalEquations(typeid(KinematicFactor), path), true);
  (void)registered;
}

}  // namespace fgcal
