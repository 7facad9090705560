#include "fgcal/core/noise_model.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "fgcal/core/internal/noise_model_access.hpp"

namespace fgcal {

struct NoiseModel::Shared : NoiseModel {
  Shared(const MatX& W, bool diagonal) : NoiseModel(W, diagonal) {}
};

namespace {

/// W(i, k)'s place in the packed upper triangle.
constexpr int at(int i, int k) { return internal::NoiseModelAccess::upperIndex(i, k); }

void checkSymmetricPositiveDefinite(const MatX& A, const char* what) {
  std::ostringstream err;
  if (A.rows() == 0 || A.rows() != A.cols()) {
    err << what << " must be a non-empty square matrix, got " << A.rows() << "x" << A.cols();
    throw InvalidNoiseModel(err.str());
  }
  if (!A.allFinite()) {
    err << what << " holds NaN or inf";
    throw InvalidNoiseModel(err.str());
  }
  const double scale = A.cwiseAbs().maxCoeff();
  const double asym = (A - A.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-9 * scale) {
    err << what << " is not symmetric (max |A - A^T| = " << asym << ")";
    throw InvalidNoiseModel(err.str());
  }
  // Fast path: a Cholesky factor bounds the eigenvalues, min >= 1 / trace(A^-1)
  // = 1 / |L^-1|_F^2 and max <= trace(A); when even these bounds pass the
  // test below, so do the eigenvalues, without computing them.
  {
    Eigen::LLT<MatX> llt(A);
    if (llt.info() == Eigen::Success) {
      const MatX Linv = llt.matrixL().solve(MatX::Identity(A.rows(), A.cols()));
      const double min_bound = 1.0 / Linv.squaredNorm(), max_bound = A.trace();
      if (min_bound > 0.0 && min_bound >= 1e-14 * max_bound) return;
    }
  }
  Eigen::SelfAdjointEigenSolver<MatX> eig(A);
  const double min_ev = eig.eigenvalues().minCoeff();
  if (!(min_ev > 0.0) || min_ev < 1e-14 * eig.eigenvalues().maxCoeff()) {
    err << what << " is not positive definite (smallest eigenvalue " << min_ev << ")";
    throw InvalidNoiseModel(err.str());
  }
}

}  // namespace

NoiseModel::Ptr NoiseModel::fromInformation(const MatX& information) {
  checkSymmetricPositiveDefinite(information, "information matrix");
  if (information.isDiagonal(0.0)) return diagonal(information.diagonal().cwiseSqrt().cwiseInverse());
  // Lambda = U^T U with U upper triangular: U is the whitening matrix.
  Eigen::LLT<MatX> llt(information);
  return std::make_shared<const Shared>(llt.matrixU(), false);
}

NoiseModel::Ptr NoiseModel::fromCovariance(const MatX& covariance) {
  checkSymmetricPositiveDefinite(covariance, "covariance");
  if (covariance.isDiagonal(0.0)) return diagonal(covariance.diagonal().cwiseSqrt());
  const MatX information = covariance.inverse();
  Eigen::LLT<MatX> llt(0.5 * (information + information.transpose()));
  return std::make_shared<const Shared>(llt.matrixU(), false);
}

NoiseModel::Ptr NoiseModel::diagonal(const VecX& sigmas) {
  if (sigmas.size() == 0) throw InvalidNoiseModel("noise model needs at least one sigma");
  for (Eigen::Index i = 0; i < sigmas.size(); ++i)
    if (!std::isfinite(sigmas[i]) || !(sigmas[i] > 0.0)) {
      std::ostringstream err;
      err << "sigma " << i << " of a diagonal noise model must be finite and > 0, got " << sigmas[i];
      throw InvalidNoiseModel(err.str());
    }
  return std::make_shared<const Shared>(sigmas.cwiseInverse().asDiagonal().toDenseMatrix(), true);
}

NoiseModel::Ptr NoiseModel::isotropic(int dim, double sigma) {
  if (dim <= 0) throw InvalidNoiseModel("isotropic noise model needs a dimension > 0");
  return diagonal(VecX::Constant(dim, sigma));
}

NoiseModel::NoiseModel(const MatX& W, bool diagonal)
    : upper_(new double[static_cast<std::size_t>(W.rows() * (W.rows() + 1) / 2)]),
      dim_(static_cast<int>(W.rows())),
      diagonal_(diagonal) {
  for (int k = 0; k < dim_; ++k)
    for (int i = 0; i <= k; ++i) upper_[static_cast<std::size_t>(at(i, k))] = W(i, k);
}

MatX NoiseModel::sqrtInformation() const {
  MatX W = MatX::Zero(dim_, dim_);
  for (int k = 0; k < dim_; ++k)
    for (int i = 0; i <= k; ++i) W(i, k) = upper_[static_cast<std::size_t>(at(i, k))];
  return W;
}

MatX NoiseModel::information() const {
  const MatX W = sqrtInformation();
  return W.transpose() * W;
}

MatX NoiseModel::covariance() const {
  const MatX Winv = sqrtInformation().triangularView<Eigen::Upper>().solve(MatX::Identity(dim(), dim()));
  return Winv * Winv.transpose();
}

namespace {
// r <- W r, W packed as at() indexes it (N > 0 fixes n): row i reads
// r's entries k >= i only, so going down the rows overwrites each after its
// last use.
template <int N>
void upperTimes(const double* W, int n_dyn, double* r) {
  const int n = N > 0 ? N : n_dyn;
  for (int i = 0; i < n; ++i) {
    double ri = 0.0;
    for (int k = i; k < n; ++k) ri += W[at(i, k)] * r[k];
    r[i] = ri;
  }
}
}  // namespace

void NoiseModel::whitenResidual(double* r) const {
  const int n = dim();
  const double* W = upper_.get();
  if (diagonal_) {
    for (int i = 0; i < n; ++i) r[i] *= W[at(i, i)];
  } else if (n == 6) {
    upperTimes<6>(W, 6, r);  // SE(3) residuals, the loops unrolled
  } else {
    upperTimes<0>(W, n, r);
  }
}

void NoiseModel::whitenJacobian(double* J, int cols, int stride) const {
  const int n = dim();
  const double* W = upper_.get();
  if (diagonal_) {
    if (n == 2) {  // 2-D residuals (reprojection errors): some 10^5 factors per linearization
      const double w0 = W[at(0, 0)], w1 = W[at(1, 1)];
      for (int c = 0; c < cols; ++c) {
        double* col = J + static_cast<std::ptrdiff_t>(c) * stride;
        col[0] *= w0;
        col[1] *= w1;
      }
      return;
    }
    for (int c = 0; c < cols; ++c) {
      double* col = J + static_cast<std::ptrdiff_t>(c) * stride;
      for (int i = 0; i < n; ++i) col[i] *= W[at(i, i)];
    }
    return;
  }
  if (n == 6) {
    // SE(3) residuals (the Jacobian path): W is upper triangular, so row pair (2p, 2p+1) of W x
    // takes W's columns k >= 2p only: 12 two-lane products per column of J
    // instead of a general 6x6 product's 18, on W's row pairs loaded once.
    using A2 = Eigen::Array2d;
    auto pair = [W](int r, int k) { return A2(W[at(r, k)], r + 1 <= k ? W[at(r + 1, k)] : 0.0); };
    const A2 a0 = pair(0, 0), a1 = pair(0, 1), a2 = pair(0, 2), a3 = pair(0, 3), a4 = pair(0, 4), a5 = pair(0, 5);
    const A2 b2 = pair(2, 2), b3 = pair(2, 3), b4 = pair(2, 4), b5 = pair(2, 5);
    const A2 c4 = pair(4, 4), c5 = pair(4, 5);
    for (int c = 0; c < cols; ++c) {
      double* x = J + static_cast<std::ptrdiff_t>(c) * stride;
      const A2 x0(x[0]), x1(x[1]), x2(x[2]), x3(x[3]), x4(x[4]), x5(x[5]);
      const A2 y01 = a0 * x0 + a1 * x1 + a2 * x2 + a3 * x3 + a4 * x4 + a5 * x5;
      const A2 y23 = b2 * x2 + b3 * x3 + b4 * x4 + b5 * x5;
      const A2 y45 = c4 * x4 + c5 * x5;
      x[0] = y01[0], x[1] = y01[1], x[2] = y23[0], x[3] = y23[1], x[4] = y45[0], x[5] = y45[1];
    }
    return;
  }
  // General size: row i of W J from rows k >= i of J, going down the rows.
  for (int c = 0; c < cols; ++c) upperTimes<0>(W, n, J + static_cast<std::ptrdiff_t>(c) * stride);
}

}  // namespace fgcal
