// With a stored J (store_jacobian): the normal equations formed again from J
// and r as they stand, and J x.
#include <algorithm>
#include <stdexcept>

#include "fgcal/core/internal/factor_evaluator.hpp"
#include "normal_equation_blocks.hpp"

namespace fgcal {

using detail::accumulateBlock;
using detail::StridedMap;

void FactorEvaluator::formNormalEquations() {
  if (!store_jacobian_)
    throw std::logic_error("formNormalEquations needs a LinearSystem built with store_jacobian");
  const SystemPattern& pattern = *pattern_;
  const std::vector<std::size_t>& slot_begin = pattern.slotBegin();
  const std::vector<Slot>& slots = pattern.slots();
  const std::vector<SlotInJ>& slot_in_j = pattern.slotsInJ();
  std::fill(H_.values.begin(), H_.values.end(), 0.0);
  h_values_zero_ = false;
  g_.setZero(H_.cols);
  double* H = H_.values.data();
  const double* Jv = J_.values.data();
  for (std::size_t pos = 0; pos < schedule_.size(); ++pos) {
    const std::size_t f = factorAt(pos);
    const int d = graph()[f].dim();
    const double* r = r_.data() + pattern.factorRows()[f];
    for (std::size_t s = slot_begin[f]; s < slot_begin[f + 1]; ++s) {
      const Slot& sl = slots[s];
      if (sl.col0 < 0) continue;
      const SlotInJ& at = slot_in_j[s];
      if (d == 6 && sl.dof == 6) {
        const StridedMap<6, 6> Jp(Jv + at.start, 6, 6, Eigen::OuterStride<>(at.stride));
        g_.segment<6>(sl.col0).noalias() += Jp.transpose() * Eigen::Map<const Vec6>(r);
      } else {
        const StridedMap<Eigen::Dynamic, Eigen::Dynamic> Jp(Jv + at.start, d, sl.dof,
                                                            Eigen::OuterStride<>(at.stride));
        g_.segment(sl.col0, sl.dof).noalias() += Jp.transpose() * Eigen::Map<const VecX>(r, d);
      }
    }
    for (std::size_t b = pattern.hblockBegin()[pos]; b < pattern.hblockBegin()[pos + 1]; ++b) {
      const HBlock& hb = pattern.hblocks()[b];
      const Slot &sp = slots[hb.slot_p], &sq = slots[hb.slot_q];
      const SlotInJ &jp = slot_in_j[hb.slot_p], &jq = slot_in_j[hb.slot_q];
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

VecX FactorEvaluator::multiplyJacobian(const VecX& x) const {
  if (!store_jacobian_)
    throw std::logic_error("multiplyJacobian needs a LinearSystem built with store_jacobian");
  VecX y = VecX::Zero(J_.rows);
  for (Index j = 0; j < J_.cols; ++j) {
    const double xj = x[j];
    for (Index k = J_.colptr[j]; k < J_.colptr[j + 1]; ++k) y[J_.rowind[k]] += J_.values[k] * xj;
  }
  return y;
}

}  // namespace fgcal
