// The order of H's columns: the free variables in value order, or, for the
// Schur complement, an elimination set first (elimination_set.hpp), so that
// H is [[A B] [B^T C]] with A block diagonal.
#include "fgcal/core/internal/linear_system.hpp"

#include "elimination_set.hpp"

namespace fgcal {

std::vector<std::size_t> LinearSystem::orderColumns(const std::vector<char>& is_free, std::vector<char>& in_set) const {
  const std::size_t nv = is_free.size();
  in_set.assign(nv, 0);
  if (options_.order_for_schur)
    in_set = detail::eliminationSet(
        slot_begin_, [&](std::size_t s) { return static_cast<std::size_t>(slots_[s].value_index); }, is_free,
        var_dof_);
  std::vector<std::size_t> order;
  order.reserve(nv);
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t vi = 0; vi < nv; ++vi)
      if (is_free[vi] && (!options_.order_for_schur ? pass == 0 : (pass == 0) == static_cast<bool>(in_set[vi])))
        order.push_back(vi);
  return order;
}

}  // namespace fgcal
