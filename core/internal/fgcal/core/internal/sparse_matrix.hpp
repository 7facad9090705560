// A compressed-column sparse matrix that we own (64-bit indices), the form
// CHOLMOD reads without a copy; viewable as an Eigen sparse matrix.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/SparseCore>

namespace fgcal {

struct CscMatrix {
  using Index = std::int64_t;
  Index rows = 0;
  Index cols = 0;
  std::vector<Index> colptr;  // cols + 1 entries
  std::vector<Index> rowind;  // sorted within each column
  std::vector<double> values;

  std::size_t nonZeros() const { return values.size(); }
  Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, Index>> eigen() const {
    return {rows, cols, static_cast<Index>(values.size()), colptr.data(), rowind.data(), values.data()};
  }
};

}  // namespace fgcal
