// The order of H's columns: the free variables in value order, or, for the
// Schur complement, an elimination set first: a greedy independent set in
// ascending degree (variables no factor ties together, like the board poses
// of a calibration), so that H is [[A B] [B^T C]] with A block diagonal.
#include "fgcal/core/internal/linear_system.hpp"

#include <algorithm>

namespace fgcal {

std::vector<std::size_t> LinearSystem::orderColumns(const std::vector<char>& is_free, std::vector<char>& in_set) const {
  const std::size_t nv = is_free.size();
  const FactorGraph& graph = graph_;
  in_set.assign(nv, 0);
  if (options_.order_for_schur) {
    // Adjacency of the free variables in compressed rows: count, fill, then
    // count each row's distinct neighbours (degree[vi]) with a marker; rows
    // keep their repeats (marking a neighbour blocked twice is harmless).
    std::vector<std::size_t> adj_begin(nv + 1, 0);
    auto forEachFreePair = [&](auto&& visit) {
      for (std::size_t f = 0; f < graph.size(); ++f)
        for (std::size_t p = slot_begin_[f]; p < slot_begin_[f + 1]; ++p)
          for (std::size_t q = slot_begin_[f]; q < slot_begin_[f + 1]; ++q) {
            const std::size_t a = slots_[p].value_index, b = slots_[q].value_index;
            if (a != b && is_free[a] && is_free[b]) visit(a, b);
          }
    };
    forEachFreePair([&](std::size_t a, std::size_t) { ++adj_begin[a + 1]; });
    for (std::size_t vi = 0; vi < nv; ++vi) adj_begin[vi + 1] += adj_begin[vi];
    std::vector<std::size_t> adj(adj_begin.back()), adj_fill(adj_begin.begin(), adj_begin.end() - 1);
    forEachFreePair([&](std::size_t a, std::size_t b) { adj[adj_fill[a]++] = b; });
    std::vector<std::size_t> degree(nv, 0), mark(nv, nv);
    std::size_t max_degree = 0;
    for (std::size_t vi = 0; vi < nv; ++vi) {
      for (std::size_t i = adj_begin[vi]; i < adj_begin[vi + 1]; ++i)
        if (mark[adj[i]] != vi) {
          mark[adj[i]] = vi;
          ++degree[vi];
        }
      max_degree = std::max(max_degree, degree[vi]);
    }
    // The free variables by ascending degree, ties in value order (a counting sort).
    std::vector<std::size_t> degree_start(max_degree + 2, 0), by_degree;
    for (std::size_t vi = 0; vi < nv; ++vi)
      if (is_free[vi]) ++degree_start[degree[vi] + 1];
    for (std::size_t k = 0; k <= max_degree; ++k) degree_start[k + 1] += degree_start[k];
    by_degree.resize(degree_start[max_degree + 1]);
    for (std::size_t vi = 0; vi < nv; ++vi)
      if (is_free[vi]) by_degree[degree_start[degree[vi]]++] = vi;
    std::vector<char> blocked(nv, 0);
    for (std::size_t vi : by_degree) {
      if (blocked[vi] || var_dof_[vi] > 9) continue;
      in_set[vi] = 1;
      for (std::size_t i = adj_begin[vi]; i < adj_begin[vi + 1]; ++i) blocked[adj[i]] = 1;
    }
  }
  std::vector<std::size_t> order;
  order.reserve(nv);
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t vi = 0; vi < nv; ++vi)
      if (is_free[vi] && (!options_.order_for_schur ? pass == 0 : (pass == 0) == static_cast<bool>(in_set[vi])))
        order.push_back(vi);
  return order;
}

}  // namespace fgcal
