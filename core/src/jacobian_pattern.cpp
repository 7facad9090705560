// The pattern of the whitened Jacobian J kept in compressed columns
// (store_jacobian): its column pointers and row indices, and where each
// slot's block sits in its values.
#include "fgcal/core/internal/column_ordering.hpp"
#include "fgcal/core/internal/system_pattern.hpp"

namespace fgcal {

void SystemPattern::buildJacobianPattern(const FactorGraph& graph, const ColumnOrdering& ordering, CscMatrix& J) {
  // Rows touching each free variable; every column of a variable has the same
  // row pattern, so a block's columns are evenly strided.
  std::vector<Index> rows_of_var(num_values_, 0);
  for (std::size_t f = 0; f < graph.size(); ++f)
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
      if (slots_[s].col0 >= 0) rows_of_var[slots_[s].value_index] += graph[f].dim();

  const Index num_cols = ordering.numColumns();
  J.rows = num_rows_;
  J.cols = num_cols;
  J.colptr.assign(num_cols + 1, 0);
  std::vector<Index> var_base(num_values_, 0);
  for (std::size_t vi : ordering.order()) {
    const Index c0 = ordering.col0(vi);
    var_base[vi] = J.colptr[c0];
    for (int c = 0; c < ordering.dof(vi); ++c) J.colptr[c0 + c + 1] = J.colptr[c0 + c] + rows_of_var[vi];
  }
  const Index nnz = J.colptr[num_cols];
  J.rowind.resize(nnz);
  J.values.assign(nnz, 0.0);

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
        for (int r = 0; r < d; ++r) J.rowind[at.start + c * at.stride + r] = factor_row_[f] + r;
      fill[vi] += d;
    }
  }
}

}  // namespace fgcal
