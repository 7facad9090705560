// LinearSystem's structure: one slot per (factor, key), the columns of the
// free variables, then the patterns and the schedule of the other units
// (column_ordering, jacobian_pattern, hessian_pattern, pairing_schedule), and
// the lookups from keys to columns.
#include "fgcal/core/internal/linear_system.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fgcal {

LinearSystem::LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
                           bool order_for_schur)
    : LinearSystem(graph, values, fixed, LinearSystemOptions{order_for_schur, true, 1}) {}

LinearSystem::LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
                           const LinearSystemOptions& options)
    : graph_(graph), options_(options), num_values_(values.size()) {
  if (options_.threads < 1)
    throw std::invalid_argument("LinearSystemOptions::threads must be >= 1, got " + std::to_string(options_.threads));
  build(values, fixed);
}

void LinearSystem::build(const Values& values, const std::vector<Key>& fixed) {
  if (values.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("LinearSystem: more than 2^32 - 1 variables");
  // Variables some factor touches, and those held fixed.
  std::vector<char> touched(values.size(), 0), is_fixed(values.size(), 0);
  for (Key k : fixed)
    if (const std::size_t vi = values.find(k); vi != Values::npos) is_fixed[vi] = 1;
  // Tangent sizes once per variable: the slots read them from here, not
  // through a virtual call per (factor, key).
  var_dof_.resize(values.size());
  for (std::size_t vi = 0; vi < values.size(); ++vi) var_dof_[vi] = values.variableAt(vi).dim();

  // Each factor's fast path and its partner in a pair (pairing_schedule.cpp),
  // found while the slots are made, each factor in cache.
  FastPathFinder finder(*this);
  buildSlots(values, finder, touched);
  // Free variables: touched by a factor and not held fixed.
  std::vector<char> is_free(values.size(), 0);
  for (std::size_t vi = 0; vi < values.size(); ++vi) is_free[vi] = touched[vi] && !is_fixed[vi];
  assignColumns(values, is_free);

  if (options_.store_jacobian) buildJacobianPattern(graph_);
  buildSchedule(finder.partners());
  buildHessianPattern();
  if (options_.store_jacobian) r_.setZero(num_rows_);  // else each factor's r goes to the scratch
  g_.setZero(num_cols_);
  for (std::size_t f = 0; f < graph_.size(); ++f)
    max_keys_ = std::max(max_keys_, slot_begin_[f + 1] - slot_begin_[f]);
  // Room for a factor's Jacobian blocks, or for its gradient parts and pair
  // blocks (linearizeFromFactorBlocks), whichever is larger.
  const std::size_t nk = std::max<std::size_t>(max_keys_, 1), dof = static_cast<std::size_t>(max_dof_);
  residual_at_ = std::max(static_cast<std::size_t>(max_dim_) * dof * nk, nk * dof + nk * (nk + 1) / 2 * dof * dof);
  scratch_half_ = residual_at_ + static_cast<std::size_t>(max_dim_);
  scratch_.resize(2 * scratch_half_);
}

// One slot per (factor, key), each factor's rows; marks the values some factor touches.
void LinearSystem::buildSlots(const Values& values, FastPathFinder& finder, std::vector<char>& touched) {
  const FactorGraph& graph = graph_;
  if (options_.store_jacobian) factor_row_.resize(graph.size() + 1);  // r's and J's rows only
  slot_begin_.resize(graph.size() + 1);
  slots_.reserve(graph.size() * 2);
  // A factor mostly names, at each place, the variable that the previous
  // factor with as many keys named there, or the one inserted after it (a
  // camera seen again, the next board pose): those two are compared before
  // the hash lookup, whose scattered nodes cost cache misses on a large graph.
  const std::vector<Key>& value_keys = values.keys();
  constexpr std::size_t kHinted = 4;
  std::size_t hint[kHinted][kHinted] = {};  // [number of keys - 1][place]
  auto valueIndex = [&](Key k, std::size_t n, std::size_t place) {
    if (n > kHinted) return values.find(k);
    std::size_t& h = hint[n - 1][place];
    if (h < value_keys.size() && value_keys[h] == k) return h;
    if (h + 1 < value_keys.size() && value_keys[h + 1] == k) return ++h;
    const std::size_t vi = values.find(k);
    if (vi != Values::npos) h = vi;
    return vi;
  };
  Index row = 0;
  for (std::size_t f = 0; f < graph.size(); ++f) {
    const Factor& factor = graph[f];
    finder.see(f, factor);
    if (options_.store_jacobian) factor_row_[f] = row;
    slot_begin_[f] = slots_.size();
    const std::vector<Key>& keys = factor.keys();
    for (std::size_t place = 0; place < keys.size(); ++place) {
      const Key k = keys[place];
      const std::size_t vi = valueIndex(k, keys.size(), place);
      if (vi == Values::npos) {
        std::ostringstream err;
        err << "factor " << f << " (" << factor.describe() << ") names variable " << keyToString(k)
            << ", which has no initial value";
        throw std::invalid_argument(err.str());
      }
      for (std::size_t s = slot_begin_[f]; s < slots_.size(); ++s)
        if (slots_[s].value_index == vi)
          throw std::invalid_argument("factor " + std::to_string(f) + " names variable " + keyToString(k) +
                                      " twice");
      touched[vi] = 1;
      slots_.push_back({static_cast<std::uint32_t>(vi), var_dof_[vi], -1});
      max_dof_ = std::max(max_dof_, var_dof_[vi]);
    }
    const int d = factor.dim();
    max_dim_ = std::max(max_dim_, d);
    row += d;
  }
  if (slots_.size() >= (std::size_t{1} << 31))  // HBlock holds a slot in 31 bits
    throw std::invalid_argument("LinearSystem: more than 2^31 - 1 (factor, variable) pairs");
  if (options_.store_jacobian) factor_row_[graph.size()] = row;
  slot_begin_[graph.size()] = slots_.size();
  num_rows_ = row;
}

// The free variables' columns in the order orderColumns gives (the
// elimination set first when ordering for the Schur complement).
void LinearSystem::assignColumns(const Values& values, const std::vector<char>& is_free) {
  std::vector<char> in_set;
  std::vector<std::size_t> order = orderColumns(is_free, in_set);
  var_col0_.assign(values.size(), -1);
  col_key_.reserve(order.size());
  Index col = 0;
  for (std::size_t vi : order) {
    if (options_.order_for_schur && in_set[vi]) {
      ++num_eliminated_blocks_;
      num_eliminated_cols_ += var_dof_[vi];
    }
    var_col0_[vi] = col;
    col_key_.push_back(values.keys()[vi]);
    col += var_dof_[vi];
  }
  col_order_ = std::move(order);
  num_cols_ = col;
  for (Slot& s : slots_) s.col0 = var_col0_[s.value_index];
}

Key LinearSystem::keyOfColumn(Index col) const {
  const auto it = std::upper_bound(blocks_.begin(), blocks_.end(), col,
                                   [](Index c, const BlockColumn& b) { return c < b.col0; });
  return col_key_[static_cast<std::size_t>(it - blocks_.begin()) - 1];
}

std::ptrdiff_t LinearSystem::blockOf(Key k) const {
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

LinearSystem::Index LinearSystem::columnOf(Key k) const {
  const std::ptrdiff_t b = blockOf(k);
  return b < 0 ? -1 : blocks_[static_cast<std::size_t>(b)].col0;
}

int LinearSystem::dofOf(Key k) const {
  const std::ptrdiff_t b = blockOf(k);
  return b < 0 ? 0 : blocks_[static_cast<std::size_t>(b)].dof;
}

}  // namespace fgcal
