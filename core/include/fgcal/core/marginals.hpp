// Marginal covariances of chosen variables at an estimate: blocks of H^-1
// obtained by solving H X = E for the columns E of those variables with the
// sparse factorization, never by inverting H densely. Covariances are in each
// variable's tangent space at the estimate (for SE3: [w v], right perturbation).
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

 private:
  struct Impl;  // the linearized system and its factorization
  std::unique_ptr<Impl> impl_;
};

}  // namespace fgcal
