// Marginal covariances of kept variables with every other variable
// eliminated one at a time by Schur complement (Marginals::reducedCovariances
// in marginals.hpp). Each eliminated block and the kept information are
// factored by Eigen's LDL^T, as the calibration's covariances always were
// (their bits stay those of every earlier release), and judged by the
// library's pivot rule (pivot_rule.hpp): a rounding-level pivot is a direction
// the data do not constrain.
#include <algorithm>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "fgcal/core/internal/pivot_rule.hpp"
#include "fgcal/core/marginals.hpp"

namespace fgcal {

namespace {

/// The information being reduced: the kept variables' block S, and the one
/// variable being eliminated with its own block and its coupling to S.
class Reduction {
 public:
  Reduction(const Values& values, const std::vector<Key>& keep, const std::vector<Key>& fixed)
      : keep_(keep), fixed_(fixed) {
    for (Key k : keep) {
      if (!values.exists(k))
        throw std::invalid_argument("Marginals::reducedCovariances: kept variable " + keyToString(k) +
                                    " has no value");
      offset_.push_back(size_);
      size_ += values.variable(k).dim();
    }
    S_ = MatX::Zero(size_, size_);
  }

  /// One factor's whitened Jacobian blocks, by key (fixed keys left out).
  void add(const Factor& f, const std::vector<MatX>& J) {
    const std::vector<Key>& keys = f.keys();
    Key elim = 0;
    int elim_slot = -1;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (isFixed(keys[i]) || keptIndex(keys[i]) >= 0) continue;
      if (elim_slot >= 0)
        throw std::invalid_argument("Marginals::reducedCovariances: a factor touches two eliminated variables (" +
                                    keyToString(elim) + ", " + keyToString(keys[i]) + ")");
      elim = keys[i];
      elim_slot = static_cast<int>(i);
    }
    if (elim_slot >= 0) startElimination(elim, static_cast<int>(J[static_cast<std::size_t>(elim_slot)].cols()));
    for (std::size_t a = 0; a < keys.size(); ++a) {
      if (isFixed(keys[a])) continue;
      const int ka = keptIndex(keys[a]);
      for (std::size_t b = 0; b < keys.size(); ++b) {
        if (isFixed(keys[b])) continue;
        const int kb = keptIndex(keys[b]);
        if (ka >= 0 && kb >= 0)
          S_.block(offset_[ka], offset_[kb], J[a].cols(), J[b].cols()).noalias() += J[a].transpose() * J[b];
        else if (ka < 0 && kb < 0)
          Hee_.noalias() += J[a].transpose() * J[b];
        else if (ka < 0)
          Her_.middleCols(offset_[kb], J[b].cols()).noalias() += J[a].transpose() * J[b];
      }
    }
  }

  /// The kept variables' joint covariance: S^-1 after the last elimination.
  MatX jointCovariance() {
    finishElimination();
    const Eigen::LDLT<MatX> ldlt(S_);
    if (const int failed = refusedPivot(ldlt, S_); failed >= 0) {
      const Key k = keep_[static_cast<std::size_t>(
          std::upper_bound(offset_.begin(), offset_.end(), failed) - offset_.begin() - 1)];
      throw DegenerateSystem("cannot compute the marginal covariances: the kept variables' information is not "
                             "positive definite at variable " + keyToString(k) +
                             " (a direction the data do not constrain)",
                             {k});
    }
    return ldlt.solve(MatX::Identity(size_, size_));
  }

  /// Each kept variable's block of jointCovariance().
  std::vector<MatX> covariances() {
    const MatX cov = jointCovariance();
    std::vector<MatX> out;
    for (std::size_t k = 0; k < keep_.size(); ++k) {
      const int d = (k + 1 < keep_.size() ? offset_[k + 1] : size_) - offset_[k];
      out.push_back(cov.block(offset_[k], offset_[k], d, d));
    }
    return out;
  }

 private:
  /// The first column (in A's order) whose pivot D(j) of A = P^T L D L^T P the
  /// library's rule refuses, or -1. A's diagonal is A's own, before pivoting.
  static int refusedPivot(const Eigen::LDLT<MatX>& ldlt, const MatX& A) {
    if (ldlt.info() != Eigen::Success) return 0;
    const Eigen::VectorXd d = ldlt.transpositionsP().transpose() * ldlt.vectorD();  // D(j) in A's order
    for (Eigen::Index j = 0; j < A.rows(); ++j)
      if (!detail::pivotAccepted(d(j), A(j, j))) return static_cast<int>(j);
    return -1;
  }

  bool isFixed(Key k) const { return std::find(fixed_.begin(), fixed_.end(), k) != fixed_.end(); }
  int keptIndex(Key k) const {
    const auto it = std::find(keep_.begin(), keep_.end(), k);
    return it == keep_.end() ? -1 : static_cast<int>(it - keep_.begin());
  }

  void startElimination(Key k, int dim) {
    if (eliminating_ && k == current_) return;
    finishElimination();
    // done_ is sorted; usually keys come in increasing order and the check is one comparison.
    if (!done_.empty() && k <= done_.back() && std::binary_search(done_.begin(), done_.end(), k))
      throw std::invalid_argument("Marginals::reducedCovariances: the factors of eliminated variable " +
                                  keyToString(k) + " do not follow each other in the graph");
    current_ = k;
    eliminating_ = true;
    Hee_ = MatX::Zero(dim, dim);
    Her_ = MatX::Zero(dim, size_);
  }

  /// S -= Her^T Hee^-1 Her for the variable being eliminated.
  void finishElimination() {
    if (!eliminating_) return;
    const Eigen::LDLT<MatX> ldlt(Hee_);
    if (refusedPivot(ldlt, Hee_) >= 0)
      throw DegenerateSystem("cannot compute the marginal covariances: variable " + keyToString(current_) +
                                 " is not constrained by the factors",
                             {current_});
    S_.noalias() -= Her_.transpose() * ldlt.solve(Her_);
    if (done_.empty() || current_ > done_.back()) done_.push_back(current_);
    else done_.insert(std::upper_bound(done_.begin(), done_.end(), current_), current_);
    eliminating_ = false;
  }

  const std::vector<Key>& keep_;
  const std::vector<Key>& fixed_;
  std::vector<int> offset_;
  int size_ = 0;
  MatX S_, Hee_, Her_;
  Key current_ = 0;
  bool eliminating_ = false;
  std::vector<Key> done_;
};

template <class Result>
Result reduce(const FactorGraph& graph, const Values& values, const std::vector<Key>& keep,
              const std::vector<Key>& fixed, Result (Reduction::*finish)()) {
  Reduction reduction(values, keep, fixed);
  std::vector<MatX> J;
  for (const auto& f : graph) {
    if (f->robustKernel())
      throw std::invalid_argument("Marginals::reducedCovariances: robust kernels are not supported (" +
                                  f->describe() + ")");
    f->error(values, &J);
    for (MatX& block : J)
      f->noiseModel().whitenJacobian(block.data(), static_cast<int>(block.cols()), static_cast<int>(block.rows()));
    reduction.add(*f, J);
  }
  return (reduction.*finish)();
}

}  // namespace

std::vector<MatX> Marginals::reducedCovariances(const FactorGraph& graph, const Values& estimate,
                                                const std::vector<Key>& keep, const std::vector<Key>& fixed) {
  return reduce(graph, estimate, keep, fixed, &Reduction::covariances);
}

MatX Marginals::reducedJointCovariance(const FactorGraph& graph, const Values& estimate, const std::vector<Key>& keep,
                                       const std::vector<Key>& fixed) {
  return reduce(graph, estimate, keep, fixed, &Reduction::jointCovariance);
}

}  // namespace fgcal
