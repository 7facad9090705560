// FactorEvaluator::FastPathFinder: which factors the evaluator takes by their
// type's fast path, and the pairs of like factors it evaluates in one call, in
// the order of evaluation (the schedule).
#include <algorithm>
#include <typeinfo>

#include "fgcal/core/internal/factor_evaluator.hpp"

namespace fgcal {

FactorEvaluator::FastPathFinder::FastPathFinder(std::size_t num_factors, const LinearSystemOptions& options)
    : num_factors_(num_factors),
      fast_(!options.store_jacobian),
      pair_(fast_ && options.pair_factors && num_factors_ <= options.pair_max_factors),
      partner_(pair_ ? num_factors_ : 0, kNoPartner) {
  fast_path_.assign(fast_ ? num_factors_ : 0, nullptr);
}

void FactorEvaluator::FastPathFinder::see(std::size_t f, const Factor& factor) {
  // A fast path is looked up once per dynamic type met (a few). A factor
  // pairs with the next factor of its type when that type's path pairs and
  // that one is at most kPairWindow places later: the last unpaired factor of
  // each type waits for it.
  if (!fast_) return;
  const std::type_info& type = typeid(factor);
  // The same type_info object first (the usual case, a pointer compare),
  // then equal ones (a type whose type_info is duplicated across libraries).
  auto t = std::find_if(types_met_.begin(), types_met_.end(), [&](const TypeMet& x) { return x.type == &type; });
  if (t == types_met_.end())
    t = std::find_if(types_met_.begin(), types_met_.end(), [&](const TypeMet& x) { return *x.type == type; });
  if (t == types_met_.end())
    t = types_met_.insert(types_met_.end(), {&type, internal::normalEquationsFor(type), num_factors_});
  const bool small = factor.keys().size() <= kFastKeys;
  if (small) fast_path_[f] = t->path;
  if (!pair_) return;
  const bool pairable = small && t->path && t->path->pairs();
  if (t->waiting < num_factors_ && pairable && f - t->waiting <= kPairWindow) {
    partner_[t->waiting] = static_cast<std::uint32_t>(f);
    t->waiting = num_factors_;
  } else {
    t->waiting = pairable ? f : num_factors_;
  }
}

std::vector<std::uint32_t> FactorEvaluator::FastPathFinder::schedule() const {
  // Fewer factors than slots (a factor has at least one key), and FactorSlots
  // refused 2^31 slots: a factor index leaves kPairedWithNext's bit free.
  const std::size_t nf = num_factors_;
  const std::vector<std::uint32_t>& partner = partner_;
  std::vector<std::uint32_t> schedule;
  schedule.reserve(nf);
  // Pairs shorten the chains of dependent operations of evaluations whose
  // data is in cache; beyond it, evaluation waits on memory, and a pair (one
  // larger unit of work) overlaps fewer of the next factor's loads with its
  // arithmetic (LinearSystemOptions::pair_max_factors). A factor's partner
  // follows it.
  std::vector<char> placed(partner.size(), 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!partner.empty() && placed[f]) continue;
    schedule.push_back(static_cast<std::uint32_t>(f));
    if (partner.empty() || partner[f] == kNoPartner) continue;
    schedule.back() |= kPairedWithNext;
    schedule.push_back(partner[f]);
    placed[partner[f]] = 1;
  }
  return schedule;
}

}  // namespace fgcal
