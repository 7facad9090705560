// Marginal covariances of chosen variables at an estimate: blocks of H^-1
// obtained by solving H X = E for the columns E of those variables with the
// sparse factorization, never by inverting H densely. Covariances are in each
// variable's tangent space at the estimate (for SE3: [w v], right perturbation).
// Or, for a few variables of a large graph, by eliminating the others one at
// a time (Marginals::reducedCovariances).
#pragma once

#include <memory>
#include <stdexcept>
#include <vector>

#include "fgcal/core/factor_graph.hpp"

namespace fgcal {

/// Thrown when the information matrix is singular: the message names the variable.
class DegenerateSystem : public std::runtime_error {
 public:
  DegenerateSystem(const std::string& what, std::vector<Key> keys)
      : std::runtime_error(what), keys_(std::move(keys)) {}
  const std::vector<Key>& keys() const { return keys_; }

 private:
  std::vector<Key> keys_;
};

class Marginals {
 public:
  /// Linearizes at `estimate` and factorizes (`graph` must outlive this object). Variables in `fixed` are
  /// constants (zero covariance; asking for them throws std::invalid_argument).
  Marginals(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& fixed = {});
  ~Marginals();
  Marginals(Marginals&&) noexcept;
  Marginals& operator=(Marginals&&) noexcept;

  MatX covariance(Key k) const;
  /// The joint covariance of `keys`, blocks in the given order.
  MatX jointCovariance(const std::vector<Key>& keys) const;

  /// Marginal covariances of a few variables of a large graph, without
  /// factorizing the whole system. Meant for graphs where most variables
  /// (e.g. one board pose per instant) each touch only a handful of factors:
  /// every variable that is neither in `keep` nor in `fixed` is eliminated in
  /// turn (its information folded into the kept variables'), then the kept
  /// variables' information is inverted. `fixed` lists variables held at
  /// their value in `estimate` (not estimated: they contribute no
  /// uncertainty). The memory is that of the kept variables' joint
  /// information, not of the graph. Returns the covariance of each of `keep`
  /// at `estimate`, in `keep`'s order and in each variable's tangent space (as
  /// covariance() gives it); equal to the whole system's Marginals up to
  /// rounding.
  /// Preconditions, std::invalid_argument (a std::logic_error) when broken:
  /// each factor touches at most one eliminated variable; the factors of one
  /// eliminated variable follow each other in the graph; no factor has a
  /// robust kernel; every key of `keep` has a value.
  /// DegenerateSystem, naming the variable, when an eliminated variable's
  /// information or the kept variables' is not positive definite (a
  /// direction the factors do not constrain).
  static std::vector<MatX> reducedCovariances(const FactorGraph& graph, const Values& estimate,
                                              const std::vector<Key>& keep, const std::vector<Key>& fixed = {});
  /// As reducedCovariances, the joint covariance of `keep` instead: their
  /// blocks in that order, cross-covariances included.
  static MatX reducedJointCovariance(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& keep,
                                     const std::vector<Key>& fixed = {});

 private:
  struct Impl;  // the linearized system and its factorization
  std::unique_ptr<Impl> impl_;
};

}  // namespace fgcal
