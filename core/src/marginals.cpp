#include "fgcal/core/marginals.hpp"

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"

namespace fgcal {

struct Marginals::Impl {
  Impl(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& fixed)
      : system(graph, estimate, fixed, LinearSystemOptions{false, /*store_jacobian=*/false, 1}) {}
  LinearSystem system;
  SparseCholesky cholesky;
};

Marginals::~Marginals() = default;
Marginals::Marginals(Marginals&&) noexcept = default;
Marginals& Marginals::operator=(Marginals&&) noexcept = default;

Marginals::Marginals(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& fixed)
    : impl_(std::make_unique<Impl>(graph, estimate, fixed)) {
  LinearSystem& system = impl_->system;
  SparseCholesky& cholesky = impl_->cholesky;
  system.linearize(estimate);
  SolverStatus st = cholesky.analyze(system.hessianUpper());
  if (st.ok()) st = cholesky.factorize(system.hessianUpper());
  if (!st.ok()) {
    std::vector<Key> keys;
    std::string msg = "cannot compute marginals: " + st.message;
    if (st.failed_column >= 0) {
      keys.push_back(system.keyOfColumn(st.failed_column));
      msg += " (variable " + keyToString(keys.back()) + " is not constrained by the factors)";
    }
    throw DegenerateSystem(msg, keys);
  }
}

MatX Marginals::covariance(Key k) const { return jointCovariance({k}); }

MatX Marginals::jointCovariance(const std::vector<Key>& keys) const {
  const LinearSystem& system = impl_->system;
  const SparseCholesky& cholesky = impl_->cholesky;
  std::vector<CscMatrix::Index> cols;
  std::vector<int> dims;
  int total = 0;
  for (Key k : keys) {
    const auto c0 = system.columnOf(k);
    if (c0 < 0)
      throw std::invalid_argument("variable " + keyToString(k) + " is held constant or not in the graph: no marginal");
    cols.push_back(c0);
    dims.push_back(system.dofOf(k));
    total += dims.back();
  }
  MatX E = MatX::Zero(system.numColumns(), total);
  int c = 0;
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (int d = 0; d < dims[i]; ++d) E(cols[i] + d, c++) = 1.0;
  MatX X;
  const SolverStatus st = cholesky.solve(E, X);
  if (!st.ok()) throw std::runtime_error("marginal covariance solve failed: " + st.message);
  MatX out(total, total);
  int r = 0;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    out.middleRows(r, dims[i]) = X.middleRows(cols[i], dims[i]);
    r += dims[i];
  }
  return 0.5 * (out + out.transpose());
}

}  // namespace fgcal
