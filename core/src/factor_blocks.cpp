// FactorEvaluator, per factor: one factor's (or one pair's) contribution to
// the normal equations: its evaluation, through its type's fast path or
// through evaluate() and J, whitening by the noise model, robust reweighting
// (IRLS), and the blocks added into H and g while they are in cache.
#include <algorithm>
#include <cmath>

#include "fgcal/core/internal/factor_evaluator.hpp"
#include "normal_equation_blocks.hpp"

// For the per-factor steps shared by the single and the paired paths: inlined
// into each caller, as when they were one function (a call each costs about
// 5 % of a linearization at 2:10^5).
#if defined(__GNUC__)
#define FGCAL_FORCE_INLINE inline __attribute__((always_inline))
#else
#define FGCAL_FORCE_INLINE inline
#endif

namespace fgcal {

using detail::accumulateBlock;
using detail::addTransposeTimes;
using detail::withSmallDof;
using detail::addScaledBlock;
using detail::squaredNorm;
using detail::withAssign;

// The generic path's whitening of factor f's residual r and Jacobian blocks
// jp (robust reweighting included), copied into J when it is stored; returns
// the factor's cost.
FGCAL_FORCE_INLINE double FactorEvaluator::whitenFactor(std::size_t f, double* r, double* const* jp) {
  const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
  const std::vector<Slot>& slots = pattern_->slots();
  const std::vector<SlotInJ>& slot_in_j = pattern_->slotsInJ();
  const Factor& factor = graph()[f];
  const int d = factor.dim();
  const std::size_t n = slot_begin[f + 1] - slot_begin[f];
  const NoiseModel& noise = factor.noiseModel();
  noise.whitenResidual(r);
  double sq = 0.0;
  for (int i = 0; i < d; ++i) sq += r[i] * r[i];
  const double cost = factor.costOfWhitened(sq);
  double scale = 1.0;
  if (const RobustKernel* robust = factor.robustKernel()) {
    scale = std::sqrt(robust->weight(sq));
    for (int i = 0; i < d; ++i) r[i] *= scale;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& s = slots[slot_begin[f] + i];
    if (!jp[i]) continue;
    noise.whitenJacobian(jp[i], s.dof, d);
    if (scale != 1.0)
      for (int k = 0; k < d * s.dof; ++k) jp[i][k] *= scale;
    if (!store_jacobian_) continue;
    const SlotInJ& at = slot_in_j[slot_begin[f] + i];
    double* dst = J_.values.data() + at.start;
    for (int c = 0; c < s.dof; ++c)
      std::copy_n(jp[i] + static_cast<std::ptrdiff_t>(c) * d, d, dst + c * at.stride);
  }
  return cost;
}

// The normal equations of the factor at `pos` from its whitened blocks, while
// they are still in cache: g += J_p^T r, H(p, q) += J_p^T J_q into the cached
// positions of the upper triangle.
FGCAL_FORCE_INLINE void FactorEvaluator::addNormalEquations(std::size_t pos, int d, const double* r,
                                                            double* const* jp, double* H_values, double* g) const {
  const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
  const std::vector<Slot>& slots = pattern_->slots();
  const std::vector<std::size_t>& hblock_begin = pattern_->hblockBegin();
  const std::vector<HBlock>& hblocks = pattern_->hblocks();
  const std::size_t f = factorAt(pos);
  const std::size_t s0 = slot_begin[f], n = slot_begin[f + 1] - s0;
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& s = slots[s0 + i];
    if (!jp[i]) continue;
    if (d == 6 && s.dof == 6)
      Eigen::Map<Vec6>(g + s.col0).noalias() += Eigen::Map<const Mat6>(jp[i]).transpose() * Eigen::Map<const Vec6>(r);
    else if (d == 2)  // 2-D residuals (reprojection errors): the sum unrolled
      addTransposeTimes<2>(jp[i], d, s.dof, r, g + s.col0);
    else
      addTransposeTimes<Eigen::Dynamic>(jp[i], d, s.dof, r, g + s.col0);
  }
  for (std::size_t b = hblock_begin[pos]; b < hblock_begin[pos + 1]; ++b) {
    const HBlock& hb = hblocks[b];
    const Slot &sp = slots[hb.slot_p], &sq = slots[hb.slot_q];
    const bool diag = hb.slot_p == hb.slot_q;
    const double* Jp = jp[hb.slot_p - s0];
    const double* Jq = jp[hb.slot_q - s0];
    const Index* colptr_q = H_.colptr.data() + sq.col0;
    withAssign(assign_first_ && hb.assign, [&](auto assign) {
      constexpr bool kAssign = decltype(assign)::value;
      constexpr int X = Eigen::Dynamic;
      if (d == 6 && sp.dof == 6 && sq.dof == 6) {
        accumulateBlock<kAssign, 6, 6, 6>(Jp, d, Jq, d, d, 6, 6, H_values, colptr_q, hb.h_start, diag);
      } else if (d == 2) {
        // 2-D residuals (reprojection errors) on poses (6) and small parameter
        // vectors (e.g. intrinsics, 4 or 8): the product in registers.
        withSmallDof(sp.dof, [&](auto cp) {
          withSmallDof(sq.dof, [&](auto cq) {
            accumulateBlock<kAssign, 2, decltype(cp)::value, decltype(cq)::value>(Jp, d, Jq, d, d, sp.dof, sq.dof,
                                                                                 H_values, colptr_q, hb.h_start, diag);
          });
        });
      } else {
        accumulateBlock<kAssign, X, X, X>(Jp, d, Jq, d, d, sp.dof, sq.dof, H_values, colptr_q, hb.h_start, diag);
      }
    });
  }
}

double FactorEvaluator::evaluateFactor(std::size_t pos, const Values& values, double* scratch_J, double* H_values,
                                       double* g) {
  const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
  const std::vector<Slot>& slots = pattern_->slots();
  const std::size_t f = factorAt(pos);
  const Factor& factor = graph()[f];
  const int d = factor.dim();
  const std::size_t n = slot_begin[f + 1] - slot_begin[f];
  const Variable* vars[kFastKeys];
  double* jac[kFastKeys];
  std::vector<const Variable*> vars_big;
  std::vector<double*> jac_big;
  const Variable** vp = vars;
  double** jp = jac;
  if (n > kFastKeys) {
    vars_big.resize(n);
    jac_big.resize(n);
    vp = vars_big.data();
    jp = jac_big.data();
  }
  gatherVariables(f, values, vp);
  if (const internal::NormalEquations* path = fast_path_.empty() ? nullptr : fast_path_[f])
    return linearizeFromFactorBlocks(pos, *path, vp, scratch_J, H_values, g);
  double* J = scratch_J;
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& s = slots[slot_begin[f] + i];
    jp[i] = s.col0 >= 0 ? J : nullptr;
    if (jp[i]) J += static_cast<std::ptrdiff_t>(d) * s.dof;
  }
  double* r = residualOut(f, scratch_J);
  factor.evaluate(vp, r, jp);
  const double cost = whitenFactor(f, r, jp);
  addNormalEquations(pos, d, r, jp, H_values, g);
  return cost;
}

FGCAL_FORCE_INLINE void FactorEvaluator::factorBlockPointers(std::size_t f, double* scratch, double** gp,
                                                              double** hp) const {
  const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
  const std::vector<Slot>& slots = pattern_->slots();
  // Scratch: the gradient parts, then the blocks of the pairs i <= j.
  const std::size_t s0 = slot_begin[f], n = slot_begin[f + 1] - s0;
  double* at = scratch;
  for (std::size_t i = 0; i < n; ++i) {
    gp[i] = at;
    at += slots[s0 + i].dof;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i; j < n; ++j, ++k) {
      hp[k] = at;
      at += static_cast<std::ptrdiff_t>(slots[s0 + i].dof) * slots[s0 + j].dof;
    }
}

FGCAL_FORCE_INLINE double FactorEvaluator::accumulateFactorBlocks(std::size_t pos, double* r,
                                                                  const double* const* gp, const double* const* hp,
                                                                  double* H_values, double* g) const {
  const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
  const std::vector<Slot>& slots = pattern_->slots();
  const std::vector<std::size_t>& hblock_begin = pattern_->hblockBegin();
  const std::vector<HBlock>& hblocks = pattern_->hblocks();
  const std::size_t f = factorAt(pos);
  const Factor& factor = graph()[f];
  const std::size_t s0 = slot_begin[f], n = slot_begin[f + 1] - s0;
  const int d = factor.dim();
  const double sq = squaredNorm(r, d);
  const double cost = factor.costOfWhitened(sq);
  double w = 1.0;  // IRLS: J and r both scaled by sqrt(w), so H and g by w
  if (const RobustKernel* robust = factor.robustKernel()) {
    w = robust->weight(sq);
    const double s = std::sqrt(w);
    for (int i = 0; i < d; ++i) r[i] *= s;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& sl = slots[s0 + i];
    if (sl.col0 < 0) continue;
    double* gi = g + sl.col0;
    if (sl.dof == 6)
      Eigen::Map<Vec6>(gi) += w * Eigen::Map<const Vec6>(gp[i]);
    else
      for (int c = 0; c < sl.dof; ++c) gi[c] += w * gp[i][c];
  }
  const auto pair = [n](std::size_t i, std::size_t j) { return i * (2 * n - i - 1) / 2 + j; };  // i <= j
  for (std::size_t b = hblock_begin[pos]; b < hblock_begin[pos + 1]; ++b) {
    const HBlock& hb = hblocks[b];
    const std::size_t p = hb.slot_p - s0, q = hb.slot_q - s0;
    const int dp = slots[hb.slot_p].dof, dq = slots[hb.slot_q].dof;
    const Index* colptr_q = H_.colptr.data() + slots[hb.slot_q].col0;
    // H's block (p, q) is the factor's (p, q), or the transpose of its (q, p).
    const double* blk = p <= q ? hp[pair(p, q)] : hp[pair(q, p)];
    withAssign(assign_first_ && hb.assign, [&](auto assign) {
      addScaledBlock<decltype(assign)::value>(blk, dp, dq, p > q, p == q, w, H_values, colptr_q, hb.h_start);
    });
  }
  return cost;
}

double FactorEvaluator::linearizeFromFactorBlocks(std::size_t pos, const internal::NormalEquations& path,
                                                  const Variable* const* vars, double* scratch, double* H_values,
                                                  double* g) {
  const std::size_t f = factorAt(pos);
  double* gp[kFastKeys];
  double* hp[kFastPairs];
  factorBlockPointers(f, scratch, gp, hp);
  double* r = residualOut(f, scratch);
  path.whitened(graph()[f], vars, r, gp, hp);
  return accumulateFactorBlocks(pos, r, gp, hp, H_values, g);
}

void FactorEvaluator::evaluatePair(std::size_t pos, const Values& values, double* scratch, double* H_values,
                                   double* g, double& cost) {
  const std::size_t fa = factorAt(pos), fb = factorAt(pos + 1);
  const Variable* va[kFastKeys];
  const Variable* vb[kFastKeys];
  gatherVariables(fa, values, va);
  gatherVariables(fb, values, vb);
  double* scratch_b = scratch + scratch_half_;
  double *gpa[kFastKeys], *hpa[kFastPairs], *gpb[kFastKeys], *hpb[kFastPairs];
  factorBlockPointers(fa, scratch, gpa, hpa);
  factorBlockPointers(fb, scratch_b, gpb, hpb);
  double* ra = scratch + residual_at_;
  double* rb = scratch_b + residual_at_;
  // Paired factors share one type, hence one fast path (buildSchedule).
  fast_path_[fa]->whitenedPair(graph()[fa], graph()[fb], va, vb, ra, gpa, hpa, rb, gpb, hpb);
  cost += accumulateFactorBlocks(pos, ra, gpa, hpa, H_values, g);
  cost += accumulateFactorBlocks(pos + 1, rb, gpb, hpb, H_values, g);
}

}  // namespace fgcal

#undef FGCAL_FORCE_INLINE
