// ColumnOrdering: the free variables (named by a factor, not held fixed) and
// their columns, in value order or, for the Schur complement, an elimination
// set first (elimination_set.hpp), so that H is [[A B] [B^T C]] with A block
// diagonal; the lookups from keys to columns and back; the retraction.
#include "fgcal/core/internal/column_ordering.hpp"

#include <algorithm>

#include "elimination_set.hpp"
#include "fgcal/core/internal/system_pattern.hpp"
#include "parallel.hpp"

namespace fgcal {

ColumnOrdering::ColumnOrdering(const Values& values, const FactorSlots& slots, const std::vector<Key>& fixed,
                               bool order_for_schur)
    : dof_(slots.dofs) {
  // Free variables: touched by a factor and not held fixed.
  std::vector<char> is_free(slots.touched);
  for (Key k : fixed)
    if (const std::size_t vi = values.find(k); vi != Values::npos) is_free[vi] = 0;
  std::vector<char> in_set;
  std::vector<std::size_t> order = orderColumns(slots, is_free, in_set, order_for_schur);
  col0_.assign(values.size(), -1);
  col_key_.reserve(order.size());
  Index col = 0;
  for (std::size_t vi : order) {
    if (order_for_schur && in_set[vi]) {
      ++num_eliminated_blocks_;
      num_eliminated_cols_ += dof_[vi];
    }
    col0_[vi] = col;
    col_key_.push_back(values.keys()[vi]);
    col += dof_[vi];
  }
  order_ = std::move(order);
  num_cols_ = col;
}

std::vector<std::size_t> ColumnOrdering::orderColumns(const FactorSlots& slots, const std::vector<char>& is_free,
                                                      std::vector<char>& in_set, bool order_for_schur) const {
  const std::size_t nv = is_free.size();
  in_set.assign(nv, 0);
  if (order_for_schur)
    in_set = detail::eliminationSet(
        slots.begin, [&](std::size_t s) { return static_cast<std::size_t>(slots.slots[s].value_index); }, is_free,
        dof_);
  std::vector<std::size_t> order;
  order.reserve(nv);
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t vi = 0; vi < nv; ++vi)
      if (is_free[vi] && (!order_for_schur ? pass == 0 : (pass == 0) == static_cast<bool>(in_set[vi])))
        order.push_back(vi);
  return order;
}

Key ColumnOrdering::keyOfColumn(Index col) const {
  const auto it = std::upper_bound(order_.begin(), order_.end(), col,
                                   [this](Index c, std::size_t vi) { return c < col0_[vi]; });
  return col_key_[static_cast<std::size_t>(it - order_.begin()) - 1];
}

std::ptrdiff_t ColumnOrdering::blockOf(Key k) const {
  // Only error paths and marginals ask: the index is not built with the
  // system (a million-entry map for a solve that never reads it).
  std::call_once(*key_block_once_, [this] {
    key_block_.resize(col_key_.size());
    for (std::size_t b = 0; b < col_key_.size(); ++b) key_block_[b] = {col_key_[b], b};
    std::sort(key_block_.begin(), key_block_.end());
  });
  const auto it = std::lower_bound(key_block_.begin(), key_block_.end(), std::make_pair(k, std::size_t{0}));
  return it != key_block_.end() && it->first == k ? static_cast<std::ptrdiff_t>(it->second) : -1;
}

ColumnOrdering::Index ColumnOrdering::columnOf(Key k) const {
  const std::ptrdiff_t b = blockOf(k);
  return b < 0 ? -1 : col0_[order_[static_cast<std::size_t>(b)]];
}

int ColumnOrdering::dofOf(Key k) const {
  const std::ptrdiff_t b = blockOf(k);
  return b < 0 ? 0 : dof_[order_[static_cast<std::size_t>(b)]];
}

void ColumnOrdering::retract(Values& values, const VecX& delta, int threads) const {
  const std::size_t num_values = col0_.size();
  const int T = detail::threadsFor(threads, num_values, 16384);
  detail::parallelRun(T, [&](int t) {
    const auto [v0, v1] = detail::chunkRange(num_values, T, t);
    for (std::size_t vi = v0; vi < v1; ++vi)
      if (col0_[vi] >= 0) values.variableAt(vi).retract(delta.data() + col0_[vi]);
  });
}

}  // namespace fgcal
