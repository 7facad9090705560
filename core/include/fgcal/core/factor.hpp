// The factor interface: a factor names its keys and, in one call, returns its
// raw residual and, when asked, the Jacobian block of each key. Whitening by
// the noise model and robust reweighting are done by the graph, not here
// (except in the optional whitenedNormalEquations fast path, which whitens).
//
// Write a factor either against the raw interface (evaluate) or, for fixed
// types, by deriving from TypedFactor<Dim, T1, T2, ...> and implementing
//   Residual evaluateTyped(const T1&, const T2&, Jacobian<T1>*, Jacobian<T2>*) const
// where each Jacobian pointer may be null (not needed).
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

  Factor(std::vector<Key> keys, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);
  virtual ~Factor() = default;

  const std::vector<Key>& keys() const { return keys_; }
  /// Residual dimension, that of the noise model.
  int dim() const { return dim_; }
  const NoiseModel& noiseModel() const { return *noise_; }
  const NoiseModel::Ptr& noiseModelPtr() const { return noise_; }
  const RobustKernel* robustKernel() const { return robust_.get(); }
  void setRobustKernel(RobustKernel::Ptr robust) { robust_ = std::move(robust); }

  /// vars[i] is the variable of keys()[i]. Writes dim() residual entries. When
  /// jacobians is non-null, each non-null jacobians[i] receives d r / d x_i as
  /// a column-major dim() x vars[i]->dim() block.
  virtual void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const = 0;

  /// Optional fast path of the linearization, for factors whose structure
  /// makes the normal-equation blocks cheaper to form directly than through
  /// J. Writes the whitened residual W r (dim() entries) to `r`. When `g` is
  /// non-null, also writes, with J_i = W dr/dx_i the whitened Jacobian of key
  /// i, the gradient part J_i^T (W r) to g[i] (vars[i]->dim() entries) and the
  /// block J_i^T J_j of every pair i <= j, column-major, to H[k] with k
  /// counting the pairs in the order (0,0), (0,1), ..., (0,n-1), (1,1), ...
  /// Robust reweighting is left to the caller. Returns false, having written
  /// nothing, when the factor has no such path (the default): the graph then
  /// forms J through evaluate() and the noise model. Where it returns true,
  /// its results must equal that path's (test/core checks the library's own),
  /// and `r` must not depend on whether `g` is given: the optimizer compares
  /// costs from residual-only evaluations with those of linearizations.
  virtual bool whitenedNormalEquations(const Variable* const* vars, double* r, double* const* g,
                                       double* const* H) const {
    (void)vars, (void)r, (void)g, (void)H;
    return false;
  }

  /// Optional: whitenedNormalEquations of this factor and of `other` in one
  /// call, for factors whose evaluation is a chain of dependent operations
  /// that two independent evaluations can share (e.g. in the two lanes of SIMD
  /// registers). LinearSystem forms pairs only without a stored J, on graphs
  /// of up to LinearSystemOptions::pair_max_factors factors (16384 unless
  /// set), between factors of at most 16 keys each that
  /// pairsWith() themselves, and then only with the next factor of the same
  /// dynamic type (typeid) in the graph's order, at most 64 places later, for
  /// which pairsWith(other) is true (else the factor goes alone); it calls
  /// whitenedNormalEquationsPair with the arguments whitenedNormalEquations
  /// would get for each (g, H, other_g and other_H all null for residuals
  /// only). It may return false, having written nothing (the graph then calls
  /// whitenedNormalEquations on each); where it returns true, its results
  /// must equal that path's to rounding. Both the choice and the residuals
  /// must depend on the estimates only, not on whether g is given: the
  /// residual-only evaluation repeats the call and must give the same bits.
  virtual bool pairsWith(const Factor& other) const {
    (void)other;
    return false;
  }
  virtual bool whitenedNormalEquationsPair(const Factor& other, const Variable* const* vars,
                                           const Variable* const* other_vars, double* r, double* const* g,
                                           double* const* H, double* other_r, double* const* other_g,
                                           double* const* other_H) const {
    (void)other, (void)vars, (void)other_vars, (void)r, (void)g, (void)H, (void)other_r, (void)other_g,
        (void)other_H;
    return false;
  }

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

/// Compares every Jacobian block of a factor with central differences through
/// each variable's retraction. Empty when all agree.
struct JacobianMismatch {
  std::size_t key_position;
  Key key;
  double max_abs_error;
  double max_abs_entry;
  std::string message;
};
std::vector<JacobianMismatch> checkFactorJacobians(const Factor& factor, const Values& values,
                                                   double step = 1e-6, double tolerance = 1e-5);

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
