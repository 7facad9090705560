#include "fgcal/core/marginals.hpp"

namespace fgcal {

Marginals::Marginals(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& fixed)
    : system_(std::make_unique<LinearSystem>(graph, estimate, fixed,
                                             LinearSystemOptions{false, /*store_jacobian=*/false, 1})) {
  system_->linearize(estimate);
  SolverStatus st = cholesky_.analyze(system_->hessianUpper());
  if (st.ok()) st = cholesky_.factorize(system_->hessianUpper());
  if (!st.ok()) {
    std::vector<Key> keys;
    std::string msg = "cannot compute marginals: " + st.message;
    if (st.failed_column >= 0) {
      keys.push_back(system_->keyOfColumn(st.failed_column));
      msg += " (variable " + keyToString(keys.back()) + " is not constrained by the factors)";
    }
    throw DegenerateSystem(msg, keys);
  }
}

MatX Marginals::covariance(Key k) const { return jointCovariance({k}); }

MatX Marginals::jointCovariance(const std::vector<Key>& keys) const {
  std::vector<CscMatrix::Index> cols;
  std::vector<int> dims;
  int total = 0;
  for (Key k : keys) {
    const auto c0 = system_->columnOf(k);
    if (c0 < 0)
      throw std::invalid_argument("variable " + keyToString(k) + " is held constant or not in the graph: no marginal");
    cols.push_back(c0);
    dims.push_back(system_->dofOf(k));
    total += dims.back();
  }
  MatX E = MatX::Zero(system_->numColumns(), total);
  int c = 0;
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (int d = 0; d < dims[i]; ++d) E(cols[i] + d, c++) = 1.0;
  MatX X;
  const SolverStatus st = cholesky_.solve(E, X);
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
