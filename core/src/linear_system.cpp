// LinearSystem's construction: the slots and each factor's fast path in one
// pass over the factors, then the column order, the pattern of J and H in the
// order of evaluation, and the evaluator over that pattern.
#include "fgcal/core/internal/linear_system.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace fgcal {

LinearSystem::LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
                           bool order_for_schur)
    : LinearSystem(graph, values, fixed, LinearSystemOptions{order_for_schur, true, 1}) {}

LinearSystem::LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
                           const LinearSystemOptions& options)
    : options_(options) {
  if (options_.threads < 1)
    throw std::invalid_argument("LinearSystemOptions::threads must be >= 1, got " + std::to_string(options_.threads));
  // Each factor's fast path and its partner in a pair (pairing_schedule.cpp),
  // found while the slots are made, each factor in cache.
  FactorEvaluator::FastPathFinder finder(graph.size(), options_);
  FactorSlots slots(graph, values, options_.store_jacobian, finder);
  ordering_ = ColumnOrdering(values, slots, fixed, options_.order_for_schur);
  std::vector<std::uint32_t> schedule = finder.schedule();
  CscMatrix J, H;
  pattern_ = SystemPattern(graph, std::move(slots), ordering_, schedule, options_.store_jacobian ? &J : nullptr, H);
  evaluator_ = FactorEvaluator(graph, options_, pattern_, std::move(finder), std::move(schedule), std::move(J),
                               std::move(H));
}

}  // namespace fgcal
