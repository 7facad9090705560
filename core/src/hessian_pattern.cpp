// SystemPattern's construction, and H's upper triangle in compressed columns:
// its pattern, its block structure for the block solvers, and where each
// factor's contributions land (the first one to each block assigns, the
// others add).
#include <algorithm>
#include <utility>
#include <vector>

#include "fgcal/core/internal/column_ordering.hpp"
#include "fgcal/core/internal/system_pattern.hpp"

namespace fgcal {

// The pairs of free variables that share a factor, (b, a) with col0(a) <
// col0(b), sorted by the blocks' places, and where each sits in b's columns.
struct SystemPattern::NeighbourPairs {
  using VarPair = std::pair<std::uint32_t, std::uint32_t>;  // (variable b, neighbour a)
  std::vector<std::uint32_t> block_of_value;  // each free variable's place in column order
  std::vector<VarPair> pairs;
  std::vector<Index> nbr_rows;                 // per variable b: its neighbours' rows in each of its columns
  std::vector<std::size_t> first_pair, count_pair;  // per variable b: its run of pairs
  std::vector<Index> pair_offset;              // per pair: a's offset within b's columns
};

SystemPattern::SystemPattern(const FactorGraph& graph, FactorSlots slots, const ColumnOrdering& ordering,
                             const std::vector<std::uint32_t>& schedule, CscMatrix* jacobian, CscMatrix& hessian)
    : num_values_(slots.dofs.size()),
      num_rows_(slots.num_rows),
      max_dim_(slots.max_dim),
      max_dof_(slots.max_dof),
      factor_row_(std::move(slots.factor_row)),
      slot_begin_(std::move(slots.begin)),
      slots_(std::move(slots.slots)) {
  for (Slot& s : slots_) s.col0 = ordering.col0(s.value_index);
  for (std::size_t f = 0; f + 1 < slot_begin_.size(); ++f)
    max_keys_ = std::max(max_keys_, slot_begin_[f + 1] - slot_begin_[f]);
  if (jacobian) buildJacobianPattern(graph, ordering, *jacobian);
  const NeighbourPairs np = neighbourPairs(ordering);
  layOutHessian(np, ordering, hessian);
  buildBlockStructure(np, ordering);
  assignHessianBlocks(np, ordering, schedule);
}

SystemPattern::NeighbourPairs SystemPattern::neighbourPairs(const ColumnOrdering& ordering) const {
  using VarPair = NeighbourPairs::VarPair;
  NeighbourPairs np;
  const std::vector<std::size_t>& col_order = ordering.order();
  np.block_of_value.assign(num_values_, 0);
  for (std::size_t b = 0; b < col_order.size(); ++b) np.block_of_value[col_order[b]] = static_cast<std::uint32_t>(b);
  std::vector<VarPair>& pairs = np.pairs;
  pairs.reserve(slots_.size());
  for (std::size_t f = 0; f + 1 < slot_begin_.size(); ++f)
    for (std::size_t p = slot_begin_[f]; p < slot_begin_[f + 1]; ++p)
      for (std::size_t q = slot_begin_[f]; q < slot_begin_[f + 1]; ++q) {
        const Slot &sp = slots_[p], &sq = slots_[q];
        if (sp.col0 >= 0 && sq.col0 >= 0 && sp.col0 < sq.col0) pairs.emplace_back(sq.value_index, sp.value_index);
      }
  // Sorted by (col0(b), col0(a)), that is by the blocks' places: a counting
  // sort by a's block, then a stable one by b's (linear in pairs and blocks).
  {
    std::vector<std::size_t> start(col_order.size() + 1);
    std::vector<VarPair> sorted(pairs.size());
    auto countingSort = [&](std::vector<VarPair>& from, std::vector<VarPair>& to, auto&& blockOf) {
      std::fill(start.begin(), start.end(), 0);
      for (const VarPair& pr : from) ++start[blockOf(pr) + 1];
      for (std::size_t b = 0; b + 1 < start.size(); ++b) start[b + 1] += start[b];
      for (const VarPair& pr : from) to[start[blockOf(pr)]++] = pr;
    };
    countingSort(pairs, sorted, [&](const VarPair& pr) { return np.block_of_value[pr.second]; });
    countingSort(sorted, pairs, [&](const VarPair& pr) { return np.block_of_value[pr.first]; });
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

  // Per variable b: its neighbours' offsets within each of b's columns.
  np.nbr_rows.assign(num_values_, 0);
  for (const auto& pr : pairs) np.nbr_rows[pr.first] += ordering.dof(pr.second);
  // pairs are sorted by col0(b), not by value index: index them by a map.
  np.first_pair.assign(num_values_, pairs.size());
  np.count_pair.assign(num_values_, 0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (np.first_pair[pairs[i].first] == pairs.size()) np.first_pair[pairs[i].first] = i;
    ++np.count_pair[pairs[i].first];
  }
  np.pair_offset.assign(pairs.size(), 0);
  for (std::size_t vi = 0; vi < num_values_; ++vi) {
    Index off = 0;
    for (std::size_t i = np.first_pair[vi]; i < np.first_pair[vi] + np.count_pair[vi]; ++i) {
      np.pair_offset[i] = off;
      off += ordering.dof(pairs[i].second);
    }
  }
  return np;
}

// H's column pointers and zero values; H(j, j) ends column j.
void SystemPattern::layOutHessian(const NeighbourPairs& np, const ColumnOrdering& ordering, CscMatrix& H) const {
  const Index num_cols = ordering.numColumns();
  H.rows = H.cols = num_cols;
  H.colptr.assign(num_cols + 1, 0);
  for (std::size_t vi = 0; vi < num_values_; ++vi) {
    const Index c0 = ordering.col0(vi);
    if (c0 < 0) continue;
    for (int c = 0; c < ordering.dof(vi); ++c) H.colptr[c0 + c + 1] = np.nbr_rows[vi] + c + 1;
  }
  for (Index j = 0; j < num_cols; ++j) H.colptr[j + 1] += H.colptr[j];
  H.values.assign(H.colptr[num_cols], 0.0);
  // The row indices wait for the first hessianUpper() (the Schur complement
  // path reads H by blocks and never needs them).
  H.rowind.clear();
}

// The block structure, for block solvers (Schur complement).
void SystemPattern::buildBlockStructure(const NeighbourPairs& np, const ColumnOrdering& ordering) {
  blocks_.clear();
  block_neighbours_.clear();
  blocks_.reserve(ordering.order().size());
  block_neighbours_.reserve(np.pairs.size());
  for (std::size_t vi : ordering.order()) {
    BlockColumn bc{ordering.col0(vi), ordering.dof(vi), block_neighbours_.size(), 0, np.nbr_rows[vi]};
    for (std::size_t i = np.first_pair[vi]; i < np.first_pair[vi] + np.count_pair[vi]; ++i)
      block_neighbours_.push_back({np.block_of_value[np.pairs[i].second], np.pair_offset[i]});
    bc.neighbour_end = block_neighbours_.size();
    blocks_.push_back(bc);
  }
}

// Each factor's contributions and where they land; the first contribution
// to each block of H (a variable's diagonal block, or a pair's) assigns, the
// others add.
void SystemPattern::assignHessianBlocks(const NeighbourPairs& np, const ColumnOrdering& ordering,
                                        const std::vector<std::uint32_t>& schedule) {
  using VarPair = NeighbourPairs::VarPair;
  const auto& pairs = np.pairs;
  // The pair (b, a) in b's sorted list: the factors mostly visit a
  // variable's neighbours in order (a camera's board poses one after the
  // other), so the entry after the last one found is tried before a search.
  std::vector<std::size_t> last_found(num_values_, pairs.size());
  auto pairIndex = [&](std::size_t b, std::size_t a) {
    std::size_t& at = last_found[b];
    const std::size_t end = np.first_pair[b] + np.count_pair[b];
    if (at < end && pairs[at].second == a) return at;
    if (at + 1 < end && pairs[at + 1].second == a) return ++at;
    const auto first = pairs.begin() + static_cast<std::ptrdiff_t>(np.first_pair[b]);
    const auto last = first + static_cast<std::ptrdiff_t>(np.count_pair[b]);
    const VarPair key{static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(a)};
    const auto it = std::lower_bound(first, last, key, [&](const auto& x, const auto& y) {
      return ordering.col0(x.second) < ordering.col0(y.second);
    });
    return at = static_cast<std::size_t>(it - pairs.begin());
  };
  hblock_begin_.assign(schedule.size() + 1, 0);
  hblocks_.reserve(slots_.size() + pairs.size());
  std::vector<char> diagonal_seen(num_values_, 0), pair_seen(pairs.size(), 0);
  for (std::size_t pos = 0; pos < schedule.size(); ++pos) {
    const std::size_t f = schedule[pos] & kFactorBits;
    hblock_begin_[pos] = hblocks_.size();
    for (std::size_t p = slot_begin_[f]; p < slot_begin_[f + 1]; ++p)
      for (std::size_t q = slot_begin_[f]; q < slot_begin_[f + 1]; ++q) {
        const Slot &sp = slots_[p], &sq = slots_[q];
        if (sp.col0 < 0 || sq.col0 < 0 || sp.col0 > sq.col0) continue;
        HBlock hb{};
        hb.slot_p = static_cast<std::uint32_t>(p);
        hb.slot_q = static_cast<std::uint32_t>(q);
        char* seen;
        if (p == q) {
          hb.h_start = np.nbr_rows[sq.value_index];
          seen = &diagonal_seen[sq.value_index];
        } else {
          const std::size_t i = pairIndex(sq.value_index, sp.value_index);
          hb.h_start = np.pair_offset[i];
          seen = &pair_seen[i];
        }
        hb.assign = !*seen;
        *seen = 1;
        hblocks_.push_back(hb);
      }
  }
  hblock_begin_.back() = hblocks_.size();
}

void SystemPattern::fillHessianRowIndices(CscMatrix& H) const {
  H.rowind.resize(H.values.size());
  for (const BlockColumn& bc : blocks_)
    for (int c = 0; c < bc.dof; ++c) {
      Index pos = H.colptr[bc.col0 + c];
      for (std::size_t k = bc.neighbour_begin; k < bc.neighbour_end; ++k) {
        const BlockColumn& nb = blocks_[block_neighbours_[k].block];
        for (int r = 0; r < nb.dof; ++r) H.rowind[pos++] = nb.col0 + r;
      }
      for (int r = 0; r <= c; ++r) H.rowind[pos++] = bc.col0 + r;
    }
}

}  // namespace fgcal
