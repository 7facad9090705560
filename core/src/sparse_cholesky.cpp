#include "fgcal/core/internal/sparse_cholesky.hpp"

#include <cstring>
#include <utility>
#include <sstream>
#include <type_traits>

#include <cholmod.h>

#include "weakest_pivot.hpp"

namespace fgcal {

static_assert(sizeof(SuiteSparse_long) == sizeof(CscMatrix::Index), "CHOLMOD long indices must be 64-bit");

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* L = nullptr;
  bool factorized = false;
  int analyses = 0;
  CscMatrix::Index n = 0, nnz = 0;

  Impl() {
    cholmod_l_start(&common);
    common.print = 0;  // we report through SolverStatus, not stdout
    common.error_handler = nullptr;
    common.quick_return_if_not_posdef = 1;
    common.final_ll = 1;  // LL': the default simplicial LDL' would accept indefinite matrices
  }

  // Every pivot of L, in the input's numbering, through `check`.
  void visitPivots(detail::WeakestPivot& check) const {
    const auto* perm = static_cast<const SuiteSparse_long*>(L->Perm);
    const auto* x = static_cast<const double*>(L->x);
    auto visit = [&](CscMatrix::Index j, double ljj) { check.visit(perm ? perm[j] : j, ljj); };
    if (L->is_super) {
      const auto* super = static_cast<const SuiteSparse_long*>(L->super);
      const auto* pi = static_cast<const SuiteSparse_long*>(L->pi);
      const auto* px = static_cast<const SuiteSparse_long*>(L->px);
      for (size_t s = 0; s < L->nsuper; ++s) {
        const SuiteSparse_long k1 = super[s], k2 = super[s + 1], nsrow = pi[s + 1] - pi[s];
        for (SuiteSparse_long j = k1; j < k2; ++j) visit(j, x[px[s] + (j - k1) + (j - k1) * nsrow]);
      }
    } else {
      const auto* p = static_cast<const SuiteSparse_long*>(L->p);
      for (size_t j = 0; j < L->n; ++j) visit(static_cast<CscMatrix::Index>(j), x[p[j]]);
    }
  }
  ~Impl() {
    if (L) cholmod_l_free_factor(&L, &common);
    cholmod_l_finish(&common);
  }

  // A header over our arrays: CHOLMOD reads them in place.
  cholmod_sparse view(const CscMatrix& A) const {
    cholmod_sparse s{};
    s.nrow = static_cast<size_t>(A.rows);
    s.ncol = static_cast<size_t>(A.cols);
    s.nzmax = A.values.size();
    s.p = const_cast<CscMatrix::Index*>(A.colptr.data());
    s.i = const_cast<CscMatrix::Index*>(A.rowind.data());
    s.x = const_cast<double*>(A.values.data());
    s.stype = 1;
    s.itype = CHOLMOD_LONG;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;

SolverStatus SparseCholesky::analyze(const CscMatrix& upper) {
  SolverStatus st;
  if (upper.rows != upper.cols || upper.colptr.size() != static_cast<std::size_t>(upper.cols) + 1) {
    st.code = SolverStatus::Code::Failed;
    st.message = "matrix to factorize is not square or its column pointers are malformed";
    return st;
  }
  if (impl_->L) cholmod_l_free_factor(&impl_->L, &impl_->common);
  impl_->factorized = false;
  cholmod_sparse A = impl_->view(upper);
  impl_->L = cholmod_l_analyze(&A, &impl_->common);
  ++impl_->analyses;
  impl_->n = upper.cols;
  impl_->nnz = static_cast<CscMatrix::Index>(upper.values.size());
  if (!impl_->L || impl_->common.status < CHOLMOD_OK) {
    st.code = SolverStatus::Code::Failed;
    st.message = "CHOLMOD symbolic analysis failed (status " + std::to_string(impl_->common.status) + ")";
  }
  return st;
}

SolverStatus SparseCholesky::factorize(const CscMatrix& upper) {
  SolverStatus st;
  if (!impl_->L || upper.cols != impl_->n || static_cast<CscMatrix::Index>(upper.values.size()) != impl_->nnz) {
    st.code = SolverStatus::Code::Failed;
    st.message = "factorize called without an analysis of this sparsity pattern";
    return st;
  }
  cholmod_sparse A = impl_->view(upper);
  cholmod_l_factorize(&A, impl_->L, &impl_->common);
  impl_->factorized = false;
  if (impl_->common.status == CHOLMOD_NOT_POSDEF) {
    st.code = SolverStatus::Code::NotPositiveDefinite;
    const auto minor = static_cast<CscMatrix::Index>(impl_->L->minor);
    const auto* perm = static_cast<const SuiteSparse_long*>(impl_->L->Perm);
    st.failed_column = (minor < impl_->n && perm) ? perm[minor] : -1;
    st.message = "matrix is not positive definite";
    return st;
  }
  if (impl_->common.status < CHOLMOD_OK) {
    st.code = SolverStatus::Code::Failed;
    st.message = "CHOLMOD numeric factorization failed (status " + std::to_string(impl_->common.status) + ")";
    return st;
  }
  if (!impl_->L->is_ll) {
    st.code = SolverStatus::Code::Failed;
    st.message = "CHOLMOD returned an LDL' factor where LL' was asked for";
    return st;
  }
  detail::WeakestPivot check(upper);
  impl_->visitPivots(check);
  st = check.status();
  if (!st.ok()) return st;
  impl_->factorized = true;
  return st;
}

SolverStatus SparseCholesky::solveRaw(const double* B, long rows, long cols, double* X) const {
  SolverStatus st;
  if (!impl_->factorized || rows != impl_->n) {
    st.code = SolverStatus::Code::Failed;
    st.message = !impl_->factorized ? "solve called before a successful factorization"
                                    : "right-hand side has the wrong number of rows";
    return st;
  }
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(rows);
  b.ncol = static_cast<size_t>(cols);
  b.nzmax = static_cast<size_t>(rows * cols);
  b.d = static_cast<size_t>(rows);
  b.x = const_cast<double*>(B);
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  auto& common = const_cast<cholmod_common&>(impl_->common);
  cholmod_dense* x = cholmod_l_solve(CHOLMOD_A, impl_->L, &b, &common);
  if (!x) {
    st.code = SolverStatus::Code::Failed;
    st.message = "CHOLMOD solve failed (status " + std::to_string(common.status) + ")";
    return st;
  }
  std::memcpy(X, x->x, sizeof(double) * static_cast<std::size_t>(rows * cols));
  cholmod_l_free_dense(&x, &common);
  return st;
}

SolverStatus SparseCholesky::solve(const MatX& B, MatX& X) const {
  X.resize(B.rows(), B.cols());
  return solveRaw(B.data(), B.rows(), B.cols(), X.data());
}

SolverStatus SparseCholesky::solve(const VecX& b, VecX& x) const {
  x.resize(b.size());
  return solveRaw(b.data(), b.size(), 1, x.data());
}

bool SparseCholesky::analyzed() const { return impl_->L != nullptr; }
bool SparseCholesky::factorized() const { return impl_->factorized; }
int SparseCholesky::analysisCount() const { return impl_->analyses; }

double SparseCholesky::factorNonZeros() const { return impl_->common.lnz; }

std::string SparseCholesky::ordering() const {
  if (!impl_->L) return "none";
  switch (impl_->L->ordering) {
    case CHOLMOD_NATURAL: return "natural";
    case CHOLMOD_GIVEN: return "given";
    case CHOLMOD_AMD: return "AMD";
    case CHOLMOD_METIS: return "METIS";
    case CHOLMOD_NESDIS: return "NESDIS";
    case CHOLMOD_COLAMD: return "COLAMD";
    case CHOLMOD_POSTORDERED: return "postordered";
    default: return "unknown";
  }
}

}  // namespace fgcal
