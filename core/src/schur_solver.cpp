#include "fgcal/core/schur_solver.hpp"

#include <algorithm>

#include <Eigen/Cholesky>

namespace fgcal {

namespace {
using Index = CscMatrix::Index;
}

SchurSolver::SchurSolver(const LinearSystem& system)
    : sys_(system), ne_(system.numEliminatedBlocks()), offset_(system.numEliminatedColumns()) {
  const auto& blocks = sys_.blocks();
  const auto& nbrs = sys_.blockNeighbours();
  const std::size_t nr = blocks.size() - ne_;

  // Reduced-block pairs (i <= j): direct neighbours among the reduced
  // variables, and every pair that shares an eliminated neighbour.
  std::vector<std::vector<std::size_t>> upper(nr);  // per j: the i <= j
  for (std::size_t j = 0; j < nr; ++j) {
    upper[j].push_back(j);
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
      if (nbrs[k].block >= ne_) upper[j].push_back(nbrs[k].block - ne_);
  }
  // Eliminated block e's reduced neighbours are the reduced blocks listing e.
  std::vector<std::vector<std::size_t>> reduced_of(ne_);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
      if (nbrs[k].block < ne_) reduced_of[nbrs[k].block].push_back(j);
  }
  for (const auto& rs : reduced_of)
    for (std::size_t a = 0; a < rs.size(); ++a)
      for (std::size_t b = 0; b < rs.size(); ++b)
        if (rs[a] <= rs[b]) upper[rs[b]].push_back(rs[a]);
  for (auto& u : upper) {
    std::sort(u.begin(), u.end());
    u.erase(std::unique(u.begin(), u.end()), u.end());
  }

  S_.rows = S_.cols = sys_.numColumns() - offset_;
  S_.colptr.assign(S_.cols + 1, 0);
  s_cols_.resize(nr);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    Index off = 0;
    for (std::size_t i : upper[j]) {
      s_cols_[j].emplace_back(i, off);
      if (i != j) off += blocks[ne_ + i].dof;
    }
    for (int c = 0; c < bj.dof; ++c) S_.colptr[bj.col0 - offset_ + c + 1] = off + c + 1;
  }
  for (Index c = 0; c < S_.cols; ++c) S_.colptr[c + 1] += S_.colptr[c];
  S_.rowind.resize(S_.colptr[S_.cols]);
  S_.values.assign(S_.colptr[S_.cols], 0.0);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (int c = 0; c < bj.dof; ++c) {
      Index pos = S_.colptr[bj.col0 - offset_ + c];
      for (const auto& [i, off] : s_cols_[j]) {
        const auto& bi = blocks[ne_ + i];
        const int rows = i == j ? c + 1 : bi.dof;
        for (int r = 0; r < rows; ++r) S_.rowind[pos++] = bi.col0 - offset_ + r;
      }
    }
  }
}

Index SchurSolver::pairOffset(std::size_t i, std::size_t j) const {
  const auto& col = s_cols_[j];
  const auto it = std::lower_bound(col.begin(), col.end(), std::make_pair(i, Index(-1)));
  return it->second;
}

SolverStatus SchurSolver::solve(const VecX& b, VecX& x) {
  const CscMatrix& H = sys_.hessianUpper();
  const auto& blocks = sys_.blocks();
  const auto& nbrs = sys_.blockNeighbours();
  const std::size_t nr = blocks.size() - ne_;
  const Index* hp = H.colptr.data();
  const double* hv = H.values.data();

  // S <- C (the reduced-reduced part of H), rhs <- b_r.
  std::fill(S_.values.begin(), S_.values.end(), 0.0);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (int c = 0; c < bj.dof; ++c) {
      const Index hcol = bj.col0 + c, scol = hcol - offset_;
      for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k) {
        if (nbrs[k].block < ne_) continue;
        const std::size_t i = nbrs[k].block - ne_;
        const Index so = pairOffset(i, j);
        for (int r = 0; r < blocks[nbrs[k].block].dof; ++r)
          S_.values[S_.colptr[scol] + so + r] = hv[hp[hcol] + nbrs[k].offset + r];
      }
      const Index so = pairOffset(j, j);
      for (int r = 0; r <= c; ++r) S_.values[S_.colptr[scol] + so + r] = hv[hp[hcol] + bj.neighbour_rows + r];
    }
  }
  VecX rhs = b.tail(S_.cols);

  // Eliminated blocks: gather B_e (their rows in the reduced columns).
  struct Link {
    std::size_t j;  // reduced block
    Index offset;   // of e's rows in j's columns of H
  };
  std::vector<std::vector<Link>> links(ne_);
  for (std::size_t j = 0; j < nr; ++j) {
    const auto& bj = blocks[ne_ + j];
    for (std::size_t k = bj.neighbour_begin; k < bj.neighbour_end; ++k)
      if (nbrs[k].block < ne_) links[nbrs[k].block].push_back({j, nbrs[k].offset});
  }
  auto blockB = [&](std::size_t e, const Link& l) {
    const auto& be = blocks[e];
    const auto& bj = blocks[ne_ + l.j];
    MatX B(be.dof, bj.dof);
    for (int c = 0; c < bj.dof; ++c)
      for (int r = 0; r < be.dof; ++r) B(r, c) = hv[hp[bj.col0 + c] + l.offset + r];
    return B;
  };
  auto blockA = [&](std::size_t e) {
    const auto& be = blocks[e];
    MatX A(be.dof, be.dof);
    for (int c = 0; c < be.dof; ++c)
      for (int r = 0; r <= c; ++r) A(r, c) = A(c, r) = hv[hp[be.col0 + c] + be.neighbour_rows + r];
    return A;
  };

  std::vector<Eigen::LLT<MatX>> Ainv(ne_);
  std::vector<std::vector<MatX>> Bs(ne_);
  for (std::size_t e = 0; e < ne_; ++e) {
    Ainv[e].compute(blockA(e));
    if (Ainv[e].info() != Eigen::Success) {
      SolverStatus st;
      st.code = SolverStatus::Code::NotPositiveDefinite;
      st.failed_column = blocks[e].col0;
      st.message = "an eliminated block is not positive definite";
      return st;
    }
    const auto& be = blocks[e];
    const VecX Ainv_be = Ainv[e].solve(b.segment(be.col0, be.dof));
    std::vector<MatX> W;  // A^-1 B_i
    for (const Link& l : links[e]) {
      Bs[e].push_back(blockB(e, l));
      W.push_back(Ainv[e].solve(Bs[e].back()));
    }
    for (std::size_t p = 0; p < links[e].size(); ++p) {
      const std::size_t i = links[e][p].j;
      const auto& bi = blocks[ne_ + i];
      rhs.segment(bi.col0 - offset_, bi.dof).noalias() -= Bs[e][p].transpose() * Ainv_be;
      for (std::size_t q = 0; q < links[e].size(); ++q) {
        const std::size_t j = links[e][q].j;
        if (i > j) continue;
        const auto& bj = blocks[ne_ + j];
        const MatX M = Bs[e][p].transpose() * W[q];
        const Index so = pairOffset(i, j);
        for (int c = 0; c < bj.dof; ++c) {
          double* col = S_.values.data() + S_.colptr[bj.col0 - offset_ + c] + so;
          const int rows = i == j ? c + 1 : bi.dof;
          for (int r = 0; r < rows; ++r) col[r] -= M(r, c);
        }
      }
    }
  }

  SolverStatus st;
  VecX xr(0);
  if (S_.cols > 0) {
  if (!analyzed_) {
    st = cholesky_.analyze(S_);
    if (!st.ok()) return st;
    analyzed_ = true;
  }
  st = cholesky_.factorize(S_);
  if (!st.ok()) {
    if (st.failed_column >= 0) st.failed_column += offset_;
    return st;
  }
  st = cholesky_.solve(rhs, xr);
  if (!st.ok()) return st;
  }

  x.resize(sys_.numColumns());
  x.tail(S_.cols) = xr;
  for (std::size_t e = 0; e < ne_; ++e) {
    const auto& be = blocks[e];
    VecX t = b.segment(be.col0, be.dof);
    for (std::size_t p = 0; p < links[e].size(); ++p) {
      const auto& bj = blocks[ne_ + links[e][p].j];
      t.noalias() -= Bs[e][p] * xr.segment(bj.col0 - offset_, bj.dof);
    }
    x.segment(be.col0, be.dof) = Ainv[e].solve(t);
  }
  return st;
}

}  // namespace fgcal
