#include "fgcal/core/internal/linear_system.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <typeinfo>

#include "parallel.hpp"

namespace fgcal {

namespace {

using Index = CscMatrix::Index;
// For the per-factor steps shared by the single and the paired paths: inlined
// into each caller, as when they were one function (a call each costs about
// 5 % of a linearization at 2:10^5).
#if defined(__GNUC__)
#define FGCAL_FORCE_INLINE inline __attribute__((always_inline))
#else
#define FGCAL_FORCE_INLINE inline
#endif
// |r|^2 of a whitened residual, summed in one order wherever a cost is formed
// (linearize() and cost() must agree to the bit on one thread).
inline double squaredNorm(const double* r, int d) {
  double sq = 0.0;
  for (int i = 0; i < d; ++i) sq += r[i] * r[i];
  return sq;
}
template <int R, int C>
using StridedMap = Eigen::Map<const Eigen::Matrix<double, R, C>, 0, Eigen::OuterStride<>>;

// x += y, or x = y for a block's first contribution (H then needs no
// clearing before a linearization).
template <bool Assign, class X, class Y>
inline void put(X&& x, const Y& y) {
  if constexpr (Assign)
    x = y;
  else
    x += y;
}
// f(std::true_type) when `assign`, else f(std::false_type): one runtime
// choice for the compile-time Assign of the block writers below.
template <class F>
inline void withAssign(bool assign, F&& f) {
  if (assign)
    f(std::true_type{});
  else
    f(std::false_type{});
}

// H(p, q) += Jp^T Jq (= when Assign) for a block in the columns of q;
// `upper_only` for a diagonal block, whose lower triangle CHOLMOD does not read.
template <bool Assign, int R, int CP, int CQ>
void accumulateBlock(const double* jp, Index sp, const double* jq, Index sq, int rows, int cp, int cq,
                     double* H, const Index* colptr_q, Index offset, bool upper_only) {
  const StridedMap<R, CP> Jp(jp, rows, cp, Eigen::OuterStride<>(sp));
  const StridedMap<R, CQ> Jq(jq, rows, cq, Eigen::OuterStride<>(sq));
  const Eigen::Matrix<double, CP, CQ> M = Jp.transpose() * Jq;
  for (int c = 0; c < cq; ++c) {
    double* col = H + colptr_q[c] + offset;
    const int rmax = upper_only ? c + 1 : cp;
    for (int r = 0; r < rmax; ++r) put<Assign>(col[r], M(r, c));
  }
}

// H(p, q) += w B (= when Assign) for the factor's dp x dq block B
// (column-major), or w B^T when `transposed` (B then dq x dp); only the upper
// triangle when `diagonal`. The 6x6 case (SE(3) with SE(3)) goes by whole
// columns of two-lane packets: a transposed block is transposed once in
// registers, a diagonal block's column c adds its c + 1 upper entries.
template <bool Assign>
void addScaledBlock(const double* B, int dp, int dq, bool transposed, bool diagonal, double w, double* H,
                    const Index* colptr_q, Index offset) {
  if (dp == 6 && dq == 6) {
    const Eigen::Map<const Mat6> Bm(B);
    if (diagonal) {
      for (int c = 0; c < 6; ++c) {
        double* col = H + colptr_q[c] + offset;
        int r = 0;
        for (; r < c; r += 2) put<Assign>(Eigen::Map<Eigen::Vector2d>(col + r), w * Bm.col(c).segment<2>(r));
        if (r == c) put<Assign>(col[r], w * Bm(r, c));
      }
    } else if (transposed) {
      const Mat6 Bt = w * Bm.transpose();
      for (int c = 0; c < 6; ++c) put<Assign>(Eigen::Map<Vec6>(H + colptr_q[c] + offset), Bt.col(c));
    } else {
      for (int c = 0; c < 6; ++c) put<Assign>(Eigen::Map<Vec6>(H + colptr_q[c] + offset), w * Bm.col(c));
    }
    return;
  }
  for (int c = 0; c < dq; ++c) {
    double* col = H + colptr_q[c] + offset;
    const int rmax = diagonal ? c + 1 : dp;
    for (int r = 0; r < rmax; ++r) {
      const std::ptrdiff_t rr = r, cc = c;
      put<Assign>(col[r], w * B[transposed ? cc + rr * dq : rr + cc * dp]);
    }
  }
}

}  // namespace

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
  const FactorGraph& graph = graph_;
  const bool order_for_schur = options_.order_for_schur;
  // Which variables are free: touched by a factor and not held fixed.
  std::vector<char> touched(values.size(), 0), is_fixed(values.size(), 0);
  for (Key k : fixed)
    if (const std::size_t vi = values.find(k); vi != Values::npos) is_fixed[vi] = 1;

  // Tangent sizes once per variable: the slots read them from here, not
  // through a virtual call per (factor, key).
  var_dof_.resize(values.size());
  for (std::size_t vi = 0; vi < values.size(); ++vi) var_dof_[vi] = values.variableAt(vi).dim();

  if (values.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("LinearSystem: more than 2^32 - 1 variables");
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
  // Each factor's fast path, looked up once per dynamic type met (a few),
  // and the pairs (see buildSchedule): a factor pairs with the next factor of
  // its type when that type's path pairs and that one is at most kPairWindow
  // places later. Decided here, while each factor is in cache, with the last
  // unpaired factor of each type.
  const bool fast = !options_.store_jacobian;
  const bool pair = fast && options_.pair_factors && graph.size() <= options_.pair_max_factors;
  std::vector<std::uint32_t> partner(pair ? graph.size() : 0, kNoPartner);
  fast_path_.assign(fast ? graph.size() : 0, nullptr);
  struct TypeMet {
    const std::type_info* type;
    const internal::NormalEquations* path;
    std::size_t waiting;  // the last unpaired factor of the type; graph.size() when none waits
  };
  std::vector<TypeMet> types_met;
  Index row = 0;
  for (std::size_t f = 0; f < graph.size(); ++f) {
    const Factor& factor = graph[f];
    if (fast) {
      const std::type_info& type = typeid(factor);
      auto t = std::find_if(types_met.begin(), types_met.end(),
                            [&](const TypeMet& x) { return x.type == &type || *x.type == type; });
      if (t == types_met.end())
        t = types_met.insert(types_met.end(), {&type, internal::normalEquationsFor(type), graph.size()});
      const bool small = factor.keys().size() <= kFastKeys;
      if (small) fast_path_[f] = t->path;
      if (pair) {
        const bool pairable = small && t->path && t->path->pairs();
        if (t->waiting < graph.size() && pairable && f - t->waiting <= kPairWindow) {
          partner[t->waiting] = static_cast<std::uint32_t>(f);
          t->waiting = graph.size();
        } else {
          t->waiting = pairable ? f : graph.size();
        }
      }
    }
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

  // Free variables, then the elimination set: a greedy independent set in
  // ascending degree (variables no factor ties together, like the board poses
  // of a calibration). With order_for_schur they get the first columns, so H
  // is [[A B] [B^T C]] with A block diagonal.
  std::vector<char> is_free(values.size(), 0);
  for (std::size_t vi = 0; vi < values.size(); ++vi) is_free[vi] = touched[vi] && !is_fixed[vi];
  std::vector<char> in_set(values.size(), 0);
  if (order_for_schur) {
    // Adjacency of the free variables in compressed rows: count, fill, then
    // count each row's distinct neighbours (degree[vi]) with a marker; rows
    // keep their repeats (marking a neighbour blocked twice is harmless).
    std::vector<std::size_t> adj_begin(values.size() + 1, 0);
    auto forEachFreePair = [&](auto&& visit) {
      for (std::size_t f = 0; f < graph.size(); ++f)
        for (std::size_t p = slot_begin_[f]; p < slot_begin_[f + 1]; ++p)
          for (std::size_t q = slot_begin_[f]; q < slot_begin_[f + 1]; ++q) {
            const std::size_t a = slots_[p].value_index, b = slots_[q].value_index;
            if (a != b && is_free[a] && is_free[b]) visit(a, b);
          }
    };
    forEachFreePair([&](std::size_t a, std::size_t) { ++adj_begin[a + 1]; });
    for (std::size_t vi = 0; vi < values.size(); ++vi) adj_begin[vi + 1] += adj_begin[vi];
    std::vector<std::size_t> adj(adj_begin.back()), adj_fill(adj_begin.begin(), adj_begin.end() - 1);
    forEachFreePair([&](std::size_t a, std::size_t b) { adj[adj_fill[a]++] = b; });
    std::vector<std::size_t> degree(values.size(), 0), mark(values.size(), values.size());
    std::size_t max_degree = 0;
    for (std::size_t vi = 0; vi < values.size(); ++vi) {
      for (std::size_t i = adj_begin[vi]; i < adj_begin[vi + 1]; ++i)
        if (mark[adj[i]] != vi) {
          mark[adj[i]] = vi;
          ++degree[vi];
        }
      max_degree = std::max(max_degree, degree[vi]);
    }
    // The free variables by ascending degree, ties in value order (a counting sort).
    std::vector<std::size_t> degree_start(max_degree + 2, 0), by_degree;
    for (std::size_t vi = 0; vi < values.size(); ++vi)
      if (is_free[vi]) ++degree_start[degree[vi] + 1];
    for (std::size_t k = 0; k <= max_degree; ++k) degree_start[k + 1] += degree_start[k];
    by_degree.resize(degree_start[max_degree + 1]);
    for (std::size_t vi = 0; vi < values.size(); ++vi)
      if (is_free[vi]) by_degree[degree_start[degree[vi]]++] = vi;
    std::vector<char> blocked(values.size(), 0);
    for (std::size_t vi : by_degree) {
      if (blocked[vi] || var_dof_[vi] > 9) continue;
      in_set[vi] = 1;
      for (std::size_t i = adj_begin[vi]; i < adj_begin[vi + 1]; ++i) blocked[adj[i]] = 1;
    }
  }
  std::vector<std::size_t> order;
  order.reserve(values.size());
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t vi = 0; vi < values.size(); ++vi)
      if (is_free[vi] && (!order_for_schur ? pass == 0 : (pass == 0) == static_cast<bool>(in_set[vi])))
        order.push_back(vi);

  var_col0_.assign(values.size(), -1);
  col_key_.reserve(order.size());
  Index col = 0;
  for (std::size_t vi : order) {
    if (order_for_schur && in_set[vi]) {
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

  if (options_.store_jacobian) buildJacobianPattern(graph);
  buildSchedule(partner);
  buildHessianPattern();
  if (options_.store_jacobian) r_.setZero(num_rows_);  // else each factor's r goes to the scratch
  g_.setZero(num_cols_);
  for (std::size_t f = 0; f < graph.size(); ++f) max_keys_ = std::max(max_keys_, slot_begin_[f + 1] - slot_begin_[f]);
  // Room for a factor's Jacobian blocks, or for its gradient parts and pair
  // blocks (linearizeFromFactorBlocks), whichever is larger.
  const std::size_t nk = std::max<std::size_t>(max_keys_, 1), dof = static_cast<std::size_t>(max_dof_);
  residual_at_ = std::max(static_cast<std::size_t>(max_dim_) * dof * nk, nk * dof + nk * (nk + 1) / 2 * dof * dof);
  scratch_half_ = residual_at_ + static_cast<std::size_t>(max_dim_);
  scratch_.resize(2 * scratch_half_);
}

void LinearSystem::buildSchedule(const std::vector<std::uint32_t>& partner) {
  // Fewer factors than slots (a factor has at least one key), and build()
  // refused 2^31 slots: a factor index leaves kPairedWithNext's bit free.
  const std::size_t nf = graph_.size();
  schedule_.clear();
  schedule_.reserve(nf);
  // Pairs shorten the chains of dependent operations of evaluations whose
  // data is in cache; beyond it, evaluation waits on memory, and a pair (one
  // larger unit of work) overlaps fewer of the next factor's loads with its
  // arithmetic (LinearSystemOptions::pair_max_factors). A factor's partner
  // follows it.
  std::vector<char> placed(partner.size(), 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!partner.empty() && placed[f]) continue;
    schedule_.push_back(static_cast<std::uint32_t>(f));
    if (partner.empty() || partner[f] == kNoPartner) continue;
    schedule_.back() |= kPairedWithNext;
    schedule_.push_back(partner[f]);
    placed[partner[f]] = 1;
  }
}

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

void LinearSystem::buildHessianPattern() {
  // Each free variable's block: its place in column order.
  std::vector<std::uint32_t> block_of_value(num_values_, 0);
  for (std::size_t b = 0; b < col_order_.size(); ++b) block_of_value[col_order_[b]] = static_cast<std::uint32_t>(b);
  // Neighbours with a smaller first column, per free variable.
  using VarPair = std::pair<std::uint32_t, std::uint32_t>;  // (variable b, neighbour a), col0(a) < col0(b)
  std::vector<VarPair> pairs;
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
    std::vector<std::size_t> start(col_order_.size() + 1);
    std::vector<VarPair> sorted(pairs.size());
    auto countingSort = [&](std::vector<VarPair>& from, std::vector<VarPair>& to, auto&& blockOf) {
      std::fill(start.begin(), start.end(), 0);
      for (const VarPair& pr : from) ++start[blockOf(pr) + 1];
      for (std::size_t b = 0; b + 1 < start.size(); ++b) start[b + 1] += start[b];
      for (const VarPair& pr : from) to[start[blockOf(pr)]++] = pr;
    };
    countingSort(pairs, sorted, [&](const VarPair& pr) { return block_of_value[pr.second]; });
    countingSort(sorted, pairs, [&](const VarPair& pr) { return block_of_value[pr.first]; });
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

  // Per variable b: its neighbours' offsets within each of b's columns.
  std::vector<Index> nbr_rows(num_values_, 0);
  for (const auto& pr : pairs) nbr_rows[pr.first] += var_dof_[pr.second];
  // pairs are sorted by col0(b), not by value index: index them by a map.
  std::vector<std::size_t> first_pair(num_values_, pairs.size()), count_pair(num_values_, 0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (first_pair[pairs[i].first] == pairs.size()) first_pair[pairs[i].first] = i;
    ++count_pair[pairs[i].first];
  }
  std::vector<Index> pair_offset(pairs.size(), 0);
  for (std::size_t vi = 0; vi < num_values_; ++vi) {
    Index off = 0;
    for (std::size_t i = first_pair[vi]; i < first_pair[vi] + count_pair[vi]; ++i) {
      pair_offset[i] = off;
      off += var_dof_[pairs[i].second];
    }
  }

  H_.rows = H_.cols = num_cols_;
  H_.colptr.assign(num_cols_ + 1, 0);
  for (std::size_t vi = 0; vi < num_values_; ++vi) {
    const Index c0 = var_col0_[vi];
    if (c0 < 0) continue;
    for (int c = 0; c < var_dof_[vi]; ++c) H_.colptr[c0 + c + 1] = nbr_rows[vi] + c + 1;
  }
  for (Index j = 0; j < num_cols_; ++j) H_.colptr[j + 1] += H_.colptr[j];
  H_.values.assign(H_.colptr[num_cols_], 0.0);
  // H(j, j) ends column j; the row indices wait for the first hessianUpper()
  // (the Schur complement path reads H by blocks and never needs them).
  H_.rowind.clear();
  h_rowind_ready_ = false;
  h_values_zero_ = true;

  // The block structure, for block solvers (Schur complement).
  blocks_.clear();
  block_neighbours_.clear();
  blocks_.reserve(col_order_.size());
  block_neighbours_.reserve(pairs.size());
  for (std::size_t vi : col_order_) {
    BlockColumn bc{var_col0_[vi], var_dof_[vi], block_neighbours_.size(), 0, nbr_rows[vi]};
    for (std::size_t i = first_pair[vi]; i < first_pair[vi] + count_pair[vi]; ++i)
      block_neighbours_.push_back({block_of_value[pairs[i].second], pair_offset[i]});
    bc.neighbour_end = block_neighbours_.size();
    blocks_.push_back(bc);
  }

  // Each factor's contributions and where they land.
  // The pair (b, a) in b's sorted list: the factors mostly visit a
  // variable's neighbours in order (a camera's board poses one after the
  // other), so the entry after the last one found is tried before a search.
  std::vector<std::size_t> last_found(num_values_, pairs.size());
  auto pairIndex = [&](std::size_t b, std::size_t a) {
    std::size_t& at = last_found[b];
    const std::size_t end = first_pair[b] + count_pair[b];
    if (at < end && pairs[at].second == a) return at;
    if (at + 1 < end && pairs[at + 1].second == a) return ++at;
    const auto first = pairs.begin() + static_cast<std::ptrdiff_t>(first_pair[b]);
    const auto last = first + static_cast<std::ptrdiff_t>(count_pair[b]);
    const VarPair key{static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(a)};
    const auto it = std::lower_bound(first, last, key, [&](const auto& x, const auto& y) {
      return var_col0_[x.second] < var_col0_[y.second];
    });
    return at = static_cast<std::size_t>(it - pairs.begin());
  };
  hblock_begin_.assign(schedule_.size() + 1, 0);
  hblocks_.reserve(slots_.size() + pairs.size());
  // Which contribution comes first to each block of H (a variable's diagonal
  // block, or a pair's): that one assigns, the others add.
  std::vector<char> diagonal_seen(num_values_, 0), pair_seen(pairs.size(), 0);
  for (std::size_t pos = 0; pos < schedule_.size(); ++pos) {
    const std::size_t f = factorAt(pos);
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
          hb.h_start = nbr_rows[sq.value_index];
          seen = &diagonal_seen[sq.value_index];
        } else {
          const std::size_t i = pairIndex(sq.value_index, sp.value_index);
          hb.h_start = pair_offset[i];
          seen = &pair_seen[i];
        }
        hb.assign = !*seen;
        *seen = 1;
        hblocks_.push_back(hb);
      }
  }
  hblock_begin_.back() = hblocks_.size();
}

void LinearSystem::fillHessianRowIndices() const {
  if (h_rowind_ready_) return;
  H_.rowind.resize(H_.values.size());
  for (const BlockColumn& bc : blocks_)
    for (int c = 0; c < bc.dof; ++c) {
      Index pos = H_.colptr[bc.col0 + c];
      for (std::size_t k = bc.neighbour_begin; k < bc.neighbour_end; ++k) {
        const BlockColumn& nb = blocks_[block_neighbours_[k].block];
        for (int r = 0; r < nb.dof; ++r) H_.rowind[pos++] = nb.col0 + r;
      }
      for (int r = 0; r <= c; ++r) H_.rowind[pos++] = bc.col0 + r;
    }
  h_rowind_ready_ = true;
}

double LinearSystem::evaluateFactor(std::size_t pos, const Values& values, double* scratch_J, double* H_values,
                                    double* g) {
  const std::size_t f = factorAt(pos);
  const Factor& factor = graph_[f];
  const int d = factor.dim();
  const std::size_t n = slot_begin_[f + 1] - slot_begin_[f];
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
  const std::size_t s0 = slot_begin_[f];
  if (const internal::NormalEquations* path = fast_path_.empty() ? nullptr : fast_path_[f])
    return linearizeFromFactorBlocks(pos, *path, vp, scratch_J, H_values, g);
  double* J = scratch_J;
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& s = slots_[slot_begin_[f] + i];
    jp[i] = s.col0 >= 0 ? J : nullptr;
    if (jp[i]) J += static_cast<std::ptrdiff_t>(d) * s.dof;
  }
  double* r = residualOut(f, scratch_J);
  factor.evaluate(vp, r, jp);

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
    const Slot& s = slots_[slot_begin_[f] + i];
    if (!jp[i]) continue;
    noise.whitenJacobian(jp[i], s.dof, d);
    if (scale != 1.0)
      for (int k = 0; k < d * s.dof; ++k) jp[i][k] *= scale;
    if (!options_.store_jacobian) continue;
    const SlotInJ& at = slot_in_j_[slot_begin_[f] + i];
    double* dst = J_.values.data() + at.start;
    for (int c = 0; c < s.dof; ++c)
      std::copy_n(jp[i] + static_cast<std::ptrdiff_t>(c) * d, d, dst + c * at.stride);
  }
  // The normal equations, while the blocks are still in cache: g += J_p^T r,
  // H(p, q) += J_p^T J_q into the cached positions of the upper triangle.
  for (std::size_t i = 0; i < n; ++i) {
    const Slot& s = slots_[slot_begin_[f] + i];
    if (!jp[i]) continue;
    if (d == 6 && s.dof == 6)
      Eigen::Map<Vec6>(g + s.col0).noalias() += Eigen::Map<const Mat6>(jp[i]).transpose() * Eigen::Map<const Vec6>(r);
    else
      Eigen::Map<VecX>(g + s.col0, s.dof).noalias() +=
          Eigen::Map<const MatX>(jp[i], d, s.dof).transpose() * Eigen::Map<const VecX>(r, d);
  }
  for (std::size_t b = hblock_begin_[pos]; b < hblock_begin_[pos + 1]; ++b) {
    const HBlock& hb = hblocks_[b];
    const Slot &sp = slots_[hb.slot_p], &sq = slots_[hb.slot_q];
    const bool diag = hb.slot_p == hb.slot_q;
    const double* Jp = jp[hb.slot_p - s0];
    const double* Jq = jp[hb.slot_q - s0];
    const Index* colptr_q = H_.colptr.data() + sq.col0;
    withAssign(assign_first_ && hb.assign, [&](auto assign) {
      constexpr bool kAssign = decltype(assign)::value;
      constexpr int X = Eigen::Dynamic;
      if (d == 6 && sp.dof == 6 && sq.dof == 6)
        accumulateBlock<kAssign, 6, 6, 6>(Jp, d, Jq, d, d, 6, 6, H_values, colptr_q, hb.h_start, diag);
      else
        accumulateBlock<kAssign, X, X, X>(Jp, d, Jq, d, d, sp.dof, sq.dof, H_values, colptr_q, hb.h_start, diag);
    });
  }
  return cost;
}

FGCAL_FORCE_INLINE void LinearSystem::gatherVariables(std::size_t f, const Values& values,
                                                       const Variable** out) const {
  for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
    out[s - slot_begin_[f]] = &values.variableAt(slots_[s].value_index);
}

FGCAL_FORCE_INLINE void LinearSystem::factorBlockPointers(std::size_t f, double* scratch, double** gp,
                                                           double** hp) const {
  // Scratch: the gradient parts, then the blocks of the pairs i <= j.
  const std::size_t s0 = slot_begin_[f], n = slot_begin_[f + 1] - s0;
  double* at = scratch;
  for (std::size_t i = 0; i < n; ++i) {
    gp[i] = at;
    at += slots_[s0 + i].dof;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i; j < n; ++j, ++k) {
      hp[k] = at;
      at += static_cast<std::ptrdiff_t>(slots_[s0 + i].dof) * slots_[s0 + j].dof;
    }
}

FGCAL_FORCE_INLINE double LinearSystem::accumulateFactorBlocks(std::size_t pos, double* r, const double* const* gp,
                                            const double* const* hp, double* H_values, double* g) const {
  const std::size_t f = factorAt(pos);
  const Factor& factor = graph_[f];
  const std::size_t s0 = slot_begin_[f], n = slot_begin_[f + 1] - s0;
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
    const Slot& sl = slots_[s0 + i];
    if (sl.col0 < 0) continue;
    double* gi = g + sl.col0;
    if (sl.dof == 6)
      Eigen::Map<Vec6>(gi) += w * Eigen::Map<const Vec6>(gp[i]);
    else
      for (int c = 0; c < sl.dof; ++c) gi[c] += w * gp[i][c];
  }
  const auto pair = [n](std::size_t i, std::size_t j) { return i * (2 * n - i - 1) / 2 + j; };  // i <= j
  for (std::size_t b = hblock_begin_[pos]; b < hblock_begin_[pos + 1]; ++b) {
    const HBlock& hb = hblocks_[b];
    const std::size_t p = hb.slot_p - s0, q = hb.slot_q - s0;
    const int dp = slots_[hb.slot_p].dof, dq = slots_[hb.slot_q].dof;
    const Index* colptr_q = H_.colptr.data() + slots_[hb.slot_q].col0;
    // H's block (p, q) is the factor's (p, q), or the transpose of its (q, p).
    const double* blk = p <= q ? hp[pair(p, q)] : hp[pair(q, p)];
    withAssign(assign_first_ && hb.assign, [&](auto assign) {
      addScaledBlock<decltype(assign)::value>(blk, dp, dq, p > q, p == q, w, H_values, colptr_q, hb.h_start);
    });
  }
  return cost;
}

double LinearSystem::linearizeFromFactorBlocks(std::size_t pos, const internal::NormalEquations& path,
                                               const Variable* const* vars, double* scratch, double* H_values,
                                               double* g) {
  const std::size_t f = factorAt(pos);
  double* gp[kFastKeys];
  double* hp[kFastPairs];
  factorBlockPointers(f, scratch, gp, hp);
  double* r = residualOut(f, scratch);
  path.whitened(graph_[f], vars, r, gp, hp);
  return accumulateFactorBlocks(pos, r, gp, hp, H_values, g);
}

void LinearSystem::evaluatePair(std::size_t pos, const Values& values, double* scratch, double* H_values, double* g,
                                double& cost) {
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
  fast_path_[fa]->whitenedPair(graph_[fa], graph_[fb], va, vb, ra, gpa, hpa, rb, gpb, hpb);
  cost += accumulateFactorBlocks(pos, ra, gpa, hpa, H_values, g);
  cost += accumulateFactorBlocks(pos + 1, rb, gpb, hpb, H_values, g);
}

double LinearSystem::linearize(const Values& values) {
  if (values.size() != num_values_)
    throw std::invalid_argument("linearize: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values_));
  const std::size_t nf = graph_.size();
  // Enough factors per thread to pay for starting it and for summing its copy
  // of H (a factor costs about a microsecond, an entry of H about a nanosecond).
  const int T = detail::threadsFor(options_.threads, nf, std::max<std::size_t>(2048, H_.values.size() / 512));
  last_threads_ = T;
  if (thread_buffers_.size() < static_cast<std::size_t>(T - 1)) thread_buffers_.resize(static_cast<std::size_t>(T - 1));
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  // On one thread every block of H is first written by the factor that
  // contributes to it first, which assigns: H is not cleared beforehand (a
  // pass over all of H per linearization). Threads add into cleared copies.
  assign_first_ = T == 1;
  detail::parallelRun(T, [&](int t) {
    double* H = H_.values.data();
    double* g = nullptr;
    double* scratch = scratch_.data();
    if (t == 0) {
      if (!h_values_zero_ && !assign_first_) std::fill(H_.values.begin(), H_.values.end(), 0.0);
      g_.setZero(num_cols_);
      g = g_.data();
    } else {
      ThreadBuffers& b = thread_buffers_[static_cast<std::size_t>(t - 1)];
      b.H.assign(H_.values.size(), 0.0);
      b.g.setZero(num_cols_);
      b.scratch.resize(scratch_.size());
      H = b.H.data();
      g = b.g.data();
      scratch = b.scratch.data();
    }
    // The schedule's places in this thread's range; a pair split by the range's end goes singly.
    const auto [p0, p1] = detail::chunkRange(nf, T, t);
    double cost = 0.0;
    walkSchedule(
        p0, p1, [&](std::size_t pos) { cost += evaluateFactor(pos, values, scratch, H, g); },
        [&](std::size_t pos) { evaluatePair(pos, values, scratch, H, g, cost); });
    costs[static_cast<std::size_t>(t)] = cost;
  });
  // Sum the threads' normal equations, each thread a range of entries.
  detail::parallelRun(T, [&](int t) {
    const auto [i0, i1] = detail::chunkRange(H_.values.size(), T, t);
    for (int u = 1; u < T; ++u) {
      const double* src = thread_buffers_[static_cast<std::size_t>(u - 1)].H.data();
      for (std::size_t i = i0; i < i1; ++i) H_.values[i] += src[i];
    }
    const auto [c0, c1] = detail::chunkRange(static_cast<std::size_t>(num_cols_), T, t);
    for (int u = 1; u < T; ++u) {
      const double* src = thread_buffers_[static_cast<std::size_t>(u - 1)].g.data();
      for (std::size_t c = c0; c < c1; ++c) g_[static_cast<Eigen::Index>(c)] += src[c];
    }
  });
  h_values_zero_ = false;
  double cost = 0.0;
  for (double c : costs) cost += c;
  return cost;
}

double LinearSystem::cost(const Values& values) const {
  if (values.size() != num_values_)
    throw std::invalid_argument("cost: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values_));
  const std::size_t nf = graph_.size();
  // Residuals only: a factor costs less than in linearize, and there is no H to sum.
  const int T = detail::threadsFor(options_.threads, nf, 4096);
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  detail::parallelRun(T, [&](int t) {
    std::vector<const Variable*> vars(max_keys_), vars_b(max_keys_);
    VecX r(std::max(max_dim_, 1)), r_b(std::max(max_dim_, 1));
    // In linearize()'s order, with its pairs and its squared norm (one thread: the same bits).
    const auto add = [&](const Factor& factor, const VecX& res, double& sum) {
      sum += factor.costOfWhitened(squaredNorm(res.data(), factor.dim()));
    };
    const auto alone = [&](std::size_t f, double& sum) {
      const Factor& factor = graph_[f];
      gatherVariables(f, values, vars.data());
      if (const internal::NormalEquations* path = fast_path_.empty() ? nullptr : fast_path_[f]) {
        path->whitened(factor, vars.data(), r.data(), nullptr, nullptr);
      } else {
        factor.evaluate(vars.data(), r.data(), nullptr);
        factor.noiseModel().whitenResidual(r.data());
      }
      add(factor, r, sum);
    };
    const auto [p0, p1] = detail::chunkRange(nf, T, t);
    double total = 0.0;
    walkSchedule(
        p0, p1, [&](std::size_t pos) { alone(factorAt(pos), total); },
        [&](std::size_t pos) {
          const std::size_t f = factorAt(pos), fb = factorAt(pos + 1);
          gatherVariables(f, values, vars.data());
          gatherVariables(fb, values, vars_b.data());
          fast_path_[f]->whitenedPair(graph_[f], graph_[fb], vars.data(), vars_b.data(), r.data(), nullptr, nullptr,
                                      r_b.data(), nullptr, nullptr);
          add(graph_[f], r, total);
          add(graph_[fb], r_b, total);
        });
    costs[static_cast<std::size_t>(t)] = total;
  });
  double total = 0.0;
  for (double c : costs) total += c;
  return total;
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

void LinearSystem::retract(Values& values, const VecX& delta) const {
  const int T = detail::threadsFor(options_.threads, num_values_, 16384);
  detail::parallelRun(T, [&](int t) {
    const auto [v0, v1] = detail::chunkRange(num_values_, T, t);
    for (std::size_t vi = v0; vi < v1; ++vi)
      if (var_col0_[vi] >= 0) values.variableAt(vi).retract(delta.data() + var_col0_[vi]);
  });
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

#undef FGCAL_FORCE_INLINE
