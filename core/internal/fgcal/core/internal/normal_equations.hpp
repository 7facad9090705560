// The engine's fast path of a factor type: for factors whose structure makes
// the normal-equation blocks cheaper to form directly than through J (the
// library's SE(3) factors), a stateless object that forms them. It is not
// part of the user's Factor interface: a factor type gets one by registering
// it here (the library's own factors do so in their constructors), and
// LinearSystem looks each factor's dynamic type up once, when it builds its
// structure, never per evaluation. checkFactorJacobians compares what it
// writes with what evaluate() and the noise model give.
#pragma once

#include <typeinfo>

#include "fgcal/core/factor.hpp"

namespace fgcal::internal {

class NormalEquations {
 public:
  virtual ~NormalEquations() = default;

  /// Writes the whitened residual W r (factor.dim() entries) to `r`. When `g`
  /// is non-null (then so is `H`), also writes, with J_i = W dr/dx_i the
  /// whitened Jacobian of key i, J_i^T (W r) to g[i] (vars[i]->dim()
  /// entries) and the block J_i^T J_j of every pair i <= j, column-major, to
  /// H[k], k counting the pairs in the order (0,0), (0,1), ..., (0,n-1),
  /// (1,1), ... Robust reweighting is left to the caller. `r` must not depend
  /// on whether `g` is given: the optimizer compares costs from
  /// residual-only evaluations with those of linearizations.
  virtual void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                        double* const* H) const = 0;

  /// Whether two factors of this type may be evaluated in one call
  /// (whitenedPair), for evaluations that are chains of dependent operations
  /// two independent ones can share (e.g. in the two lanes of SIMD registers).
  virtual bool pairs() const { return false; }
  /// whitened() of a and of b in one call, with the arguments whitened()
  /// would get for each (g_a, H_a, g_b and H_b all null for residuals only).
  /// Its results equal those of whitened() to rounding; its residuals depend
  /// on the estimates only, not on whether g is given (the residual-only
  /// evaluation repeats the call and must give the same bits).
  virtual void whitenedPair(const Factor& a, const Factor& b, const Variable* const* vars_a,
                            const Variable* const* vars_b, double* r_a, double* const* g_a, double* const* H_a,
                            double* r_b, double* const* g_b, double* const* H_b) const {
    whitened(a, vars_a, r_a, g_a, H_a);
    whitened(b, vars_b, r_b, g_b, H_b);
  }
};

/// Makes `path` the fast path of every factor whose dynamic type is `type`.
/// `path` must outlive every linearization (a function-local static).
/// Registering the same path again does nothing; another path for a type
/// that has one throws std::logic_error.
void registerNormalEquations(const std::type_info& type, const NormalEquations& path);

/// The fast path registered for `type`, or nullptr (the factor is then
/// linearized through evaluate() and its noise model).
const NormalEquations* normalEquationsFor(const std::type_info& type);

}  // namespace fgcal::internal
