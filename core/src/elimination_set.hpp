// The Schur complement's elimination set: a greedy independent set of the
// free variables in ascending degree (variables no factor ties together, like
// the board poses of a calibration), each of at most 9 degrees of freedom.
// Shared by ColumnOrdering and the streamed Schur complement.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace fgcal::detail {

/// in_set[vi] for each of is_free.size() variables. Factor f touches the
/// variables valueOf(s) for s in [slot_begin[f], slot_begin[f + 1]); dof[vi]
/// is variable vi's tangent dimension.
template <class ValueOf>
std::vector<char> eliminationSet(const std::vector<std::size_t>& slot_begin, ValueOf&& valueOf,
                                 const std::vector<char>& is_free, const std::vector<int>& dof) {
  const std::size_t nv = is_free.size();
  std::vector<char> in_set(nv, 0);
  // Adjacency of the free variables in compressed rows: count, fill, then
  // count each row's distinct neighbours (degree[vi]) with a marker; rows
  // keep their repeats (marking a neighbour blocked twice is harmless).
  std::vector<std::size_t> adj_begin(nv + 1, 0);
  auto forEachFreePair = [&](auto&& visit) {
    for (std::size_t f = 0; f + 1 < slot_begin.size(); ++f)
      for (std::size_t p = slot_begin[f]; p < slot_begin[f + 1]; ++p)
        for (std::size_t q = slot_begin[f]; q < slot_begin[f + 1]; ++q) {
          const std::size_t a = valueOf(p), b = valueOf(q);
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
    if (blocked[vi] || dof[vi] > 9) continue;
    in_set[vi] = 1;
    for (std::size_t i = adj_begin[vi]; i < adj_begin[vi + 1]; ++i) blocked[adj[i]] = 1;
  }
  return in_set;
}

}  // namespace fgcal::detail
