// The whitened Jacobian J kept in compressed columns (store_jacobian): its
// pattern, the normal equations formed from it, and J x.
#include "fgcal/core/internal/linear_system.hpp"

#include "normal_equation_blocks.hpp"

namespace fgcal {

using detail::accumulateBlock;
using detail::StridedMap;

void LinearSystem::buildJacobianPattern(const FactorGraph& graph) {
  // Rows touching each free variable; every column of a variable has the same
  // row pattern, so a block's columns are evenly strided.
  std::vector<Index> rows_of_var(num_values_, 0);
  for (std::size_t f = 0; f < graph.size(); ++f)
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
      if (slots_[s].col0 >= 0) rows_of_var[slots_[s].value_index] += graph[f].dim();

  J_.rows = num_rows_;
  J_.cols = num_cols_;
  J_.colptr.assign(num_cols_ + 1, 0);
  std::vector<Index> var_base(num_values_, 0);
  for (std::size_t vi : col_order_) {
    const Index c0 = var_col0_[vi];
    var_base[vi] = J_.colptr[c0];
    for (int c = 0; c < var_dof_[vi]; ++c) J_.colptr[c0 + c + 1] = J_.colptr[c0 + c] + rows_of_var[vi];
  }
  const Index nnz = J_.colptr[num_cols_];
  J_.rowind.resize(nnz);
  J_.values.assign(nnz, 0.0);

  std::vector<Index> fill(num_values_, 0);  // rows already placed per variable
  slot_in_j_.assign(slots_.size(), {-1, 0});
  for (std::size_t f = 0; f < graph.size(); ++f) {
    const int d = graph[f].dim();
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s) {
      const Slot& slot = slots_[s];
      if (slot.col0 < 0) continue;
      const std::size_t vi = slot.value_index;
      SlotInJ& at = slot_in_j_[s];
      at.start = var_base[vi] + fill[vi];
      at.stride = rows_of_var[vi];
      for (int c = 0; c < slot.dof; ++c)
        for (int r = 0; r < d; ++r) J_.rowind[at.start + c * at.stride + r] = factor_row_[f] + r;
      fill[vi] += d;
    }
  }
}

void LinearSystem::formNormalEquations() {
  if (!options_.store_jacobian)
    throw std::logic_error("formNormalEquations needs a LinearSystem built with store_jacobian");
  std::fill(H_.values.begin(), H_.values.end(), 0.0);
  h_values_zero_ = false;
  g_.setZero(num_cols_);
  double* H = H_.values.data();
  const double* Jv = J_.values.data();
  for (std::size_t pos = 0; pos < schedule_.size(); ++pos) {
    const std::size_t f = factorAt(pos);
    const int d = graph_[f].dim();
    const double* r = r_.data() + factor_row_[f];
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s) {
      const Slot& sl = slots_[s];
      if (sl.col0 < 0) continue;
      const SlotInJ& at = slot_in_j_[s];
      if (d == 6 && sl.dof == 6) {
        const StridedMap<6, 6> Jp(Jv + at.start, 6, 6, Eigen::OuterStride<>(at.stride));
        g_.segment<6>(sl.col0).noalias() += Jp.transpose() * Eigen::Map<const Vec6>(r);
      } else {
        const StridedMap<Eigen::Dynamic, Eigen::Dynamic> Jp(Jv + at.start, d, sl.dof,
                                                            Eigen::OuterStride<>(at.stride));
        g_.segment(sl.col0, sl.dof).noalias() += Jp.transpose() * Eigen::Map<const VecX>(r, d);
      }
    }
    for (std::size_t b = hblock_begin_[pos]; b < hblock_begin_[pos + 1]; ++b) {
      const HBlock& hb = hblocks_[b];
      const Slot &sp = slots_[hb.slot_p], &sq = slots_[hb.slot_q];
      const SlotInJ &jp = slot_in_j_[hb.slot_p], &jq = slot_in_j_[hb.slot_q];
      const bool diag = hb.slot_p == hb.slot_q;
      const Index* colptr_q = H_.colptr.data() + sq.col0;
      if (d == 6 && sp.dof == 6 && sq.dof == 6)
        accumulateBlock<false, 6, 6, 6>(Jv + jp.start, jp.stride, Jv + jq.start, jq.stride, d, 6, 6, H, colptr_q,
                                        hb.h_start, diag);
      else
        accumulateBlock<false, Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic>(
            Jv + jp.start, jp.stride, Jv + jq.start, jq.stride, d, sp.dof, sq.dof, H, colptr_q, hb.h_start, diag);
    }
  }
}

VecX LinearSystem::multiplyJacobian(const VecX& x) const {
  if (!options_.store_jacobian)
    throw std::logic_error("multiplyJacobian needs a LinearSystem built with store_jacobian");
  VecX y = VecX::Zero(num_rows_);
  for (Index j = 0; j < num_cols_; ++j) {
    const double xj = x[j];
    for (Index k = J_.colptr[j]; k < J_.colptr[j + 1]; ++k) y[J_.rowind[k]] += J_.values[k] * xj;
  }
  return y;
}

}  // namespace fgcal
