// A factor is one measurement's term of the least-squares cost: it names the
// variables (keys) it depends on, a noise model (the measurement's
// covariance) and optionally a robust kernel, and computes its raw residual r
// and, when asked, the Jacobian d r / d x_i of each variable under that
// variable's retraction (for SE3: right perturbation, [w v] order). The graph
// adds 0.5 rho(|W r|^2) to the cost; whitening by the noise model (W) and
// robust reweighting are its business, not the factor's.
//
// For fixed variable types, derive from TypedFactor<Dim, T1, T2, ...> and
// implement one call that returns the residual and fills each Jacobian whose
// pointer is non-null (null: not needed this time):
//
//   // A point p (R^3) at a measured distance from a known anchor.
//   class RangeFactor final : public fgcal::TypedFactor<1, Eigen::Vector3d> {
//    public:
//     RangeFactor(fgcal::Key p, Eigen::Vector3d anchor, double range, double sigma)
//         : TypedFactor({p}, fgcal::NoiseModel::isotropic(1, sigma)), anchor_(anchor), range_(range) {}
//     Residual evaluateTyped(const Eigen::Vector3d& p, Jacobian<Eigen::Vector3d>* J_r_p) const override {
//       const Eigen::Vector3d d = p - anchor_;
//       if (J_r_p) *J_r_p = d.normalized().transpose();  // d|d| / dp
//       return Residual(d.norm() - range_);
//     }
//    private:
//     Eigen::Vector3d anchor_;
//     double range_;
//   };
//
//   graph.emplace<RangeFactor>(fgcal::key('p', 0), anchor, measured_range, 0.01);
//
// Check the Jacobians once with checkFactorJacobians (below) or
// OptimizerOptions::check_jacobians. A factor must be safe to evaluate
// concurrently (const, no shared mutable state) when the optimizer runs on
// several threads. Factors of any variable type, or of a number of keys known
// only at run time, derive from Factor and implement evaluate() directly.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "fgcal/core/noise_model.hpp"
#include "fgcal/core/robust_kernel.hpp"
#include "fgcal/core/values.hpp"

namespace fgcal {

class Factor {
 public:
  using Ptr = std::shared_ptr<Factor>;

  /// Throws std::invalid_argument without keys or without a noise model.
  Factor(std::vector<Key> keys, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);
  virtual ~Factor() = default;

  const std::vector<Key>& keys() const { return keys_; }
  /// Residual dimension, that of the noise model.
  int dim() const { return dim_; }
  const NoiseModel& noiseModel() const { return *noise_; }
  const NoiseModel::Ptr& noiseModelPtr() const { return noise_; }
  const RobustKernel* robustKernel() const { return robust_.get(); }
  void setRobustKernel(RobustKernel::Ptr robust) { robust_ = std::move(robust); }

  /// The one call a factor implements. vars[i] is the variable of keys()[i].
  /// Writes dim() raw (unwhitened) residual entries. When `jacobians` is
  /// non-null, each non-null jacobians[i] receives d r / d x_i as a
  /// column-major dim() x vars[i]->dim() block; a null one is not needed.
  /// The residual must not depend on whether Jacobians are asked for.
  virtual void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const = 0;

  /// Convenience (allocates): the raw residual at `values`, and the Jacobians when asked.
  VecX error(const Values& values, std::vector<MatX>* jacobians = nullptr) const;
  /// 0.5 rho(|W r|^2) at `values`.
  double cost(const Values& values) const;
  /// 0.5 rho(s) for the squared norm s = |W r|^2 of a whitened residual (0.5 s
  /// without a robust kernel): the one cost rule of cost(), linearize and the
  /// optimizer's residual-only evaluation.
  double costOfWhitened(double s) const { return 0.5 * (robust_ ? robust_->rho(s) : s); }
  /// A readable name for messages ("factor 12 on b3, c0").
  virtual std::string describe() const;

 private:
  std::vector<Key> keys_;
  NoiseModel::Ptr noise_;
  int dim_ = 0;  // noise_->dim(), kept here: read for every factor in a structure build
  RobustKernel::Ptr robust_;
};

/// One disagreement found by checkFactorJacobians.
struct JacobianMismatch {
  std::size_t key_position;  // the block's key (for a block of H, its row key)
  Key key;
  double max_abs_error;
  double max_abs_entry;
  std::string message;
};
/// Compares every Jacobian block of evaluate() with central differences
/// through each variable's retraction (a block wrong by more than `tolerance`,
/// relative to 1 + |entry|, is reported). Where the solver linearizes the
/// factor by another path than evaluate() (the library's own SE(3) factors
/// have faster ones), that path's whitened residual, gradient and
/// normal-equation blocks are also compared with those formed from
/// evaluate(), so what is checked is what the solver uses. Empty when all agree.
std::vector<JacobianMismatch> checkFactorJacobians(const Factor& factor, const Values& values,
                                                   double step = 1e-6, double tolerance = 1e-5);

/// A factor on fixed variable types T1, T2, ... with a residual of dimension
/// D (Eigen::Dynamic for one known only at run time): implement
/// evaluateTyped, which receives the variables' values and one Jacobian
/// pointer per variable (D x the variable's tangent dimension), each null
/// when that Jacobian is not needed. See the example at the top of this file.

template <int D, class... Ts>
class TypedFactor : public Factor {
 public:
  using Residual = Eigen::Matrix<double, D, 1>;
  template <class T>
  using Jacobian = Eigen::Matrix<double, D, Manifold<T>::kDim>;

  /// Throws std::invalid_argument unless there is one key per variable type
  /// and the noise model has the residual's dimension D.
  TypedFactor(std::vector<Key> keys, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr)
      : Factor(std::move(keys), std::move(noise), std::move(robust)) {
    if (this->keys().size() != sizeof...(Ts))
      throw std::invalid_argument("a factor on " + std::to_string(sizeof...(Ts)) + " variable(s) got " +
                                  std::to_string(this->keys().size()) + " key(s)");
    if (D != Eigen::Dynamic && dim() != D)
      throw std::invalid_argument("a factor with a residual of dimension " + std::to_string(D) +
                                  " got a noise model of dimension " + std::to_string(dim()));
  }

  /// The residual at xs, and d r / d x_i into each non-null Js[i].
  virtual Residual evaluateTyped(const Ts&... xs, Jacobian<Ts>*... Js) const = 0;

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const final {
    evaluateImpl(vars, residual, jacobians, std::index_sequence_for<Ts...>{});
  }

 private:
  template <std::size_t... I>
  void evaluateImpl(const Variable* const* vars, double* residual, double* const* jacobians,
                    std::index_sequence<I...>) const {
    std::tuple<Jacobian<Ts>...> J;
    const Residual r = evaluateTyped(static_cast<const TypedVariable<Ts>*>(vars[I])->value()...,
                                     (jacobians && jacobians[I] ? &std::get<I>(J) : nullptr)...);
    Eigen::Map<Residual>(residual, dim()) = r;
    if (jacobians) {
      ((jacobians[I] ? (void)(Eigen::Map<Jacobian<Ts>>(jacobians[I], dim(), vars[I]->dim()) = std::get<I>(J))
                     : (void)0),
       ...);
    }
  }
};

}  // namespace fgcal
