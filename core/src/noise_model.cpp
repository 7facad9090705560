#include "fgcal/core/noise_model.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace fgcal {

namespace {

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
  return Ptr(new NoiseModel(llt.matrixU(), false));
}

NoiseModel::Ptr NoiseModel::fromCovariance(const MatX& covariance) {
  checkSymmetricPositiveDefinite(covariance, "covariance");
  if (covariance.isDiagonal(0.0)) return diagonal(covariance.diagonal().cwiseSqrt());
  const MatX information = covariance.inverse();
  Eigen::LLT<MatX> llt(0.5 * (information + information.transpose()));
  return Ptr(new NoiseModel(llt.matrixU(), false));
}

NoiseModel::Ptr NoiseModel::diagonal(const VecX& sigmas) {
  if (sigmas.size() == 0) throw InvalidNoiseModel("noise model needs at least one sigma");
  for (Eigen::Index i = 0; i < sigmas.size(); ++i)
    if (!std::isfinite(sigmas[i]) || !(sigmas[i] > 0.0)) {
      std::ostringstream err;
      err << "sigma " << i << " of a diagonal noise model must be finite and > 0, got " << sigmas[i];
      throw InvalidNoiseModel(err.str());
    }
  return Ptr(new NoiseModel(sigmas.cwiseInverse().asDiagonal().toDenseMatrix(), true));
}

NoiseModel::Ptr NoiseModel::isotropic(int dim, double sigma) {
  if (dim <= 0) throw InvalidNoiseModel("isotropic noise model needs a dimension > 0");
  return diagonal(VecX::Constant(dim, sigma));
}

MatX NoiseModel::covariance() const {
  const MatX Winv = sqrt_information_.triangularView<Eigen::Upper>().solve(MatX::Identity(dim(), dim()));
  return Winv * Winv.transpose();
}

void NoiseModel::whitenResidual(double* r) const { whitenJacobian(r, 1, dim()); }

void NoiseModel::whitenJacobian(double* J, int cols, int stride) const {
  const int n = dim();
  if (diagonal_) {
    const double* w = diag_.data();
    for (int c = 0; c < cols; ++c) {
      double* col = J + static_cast<std::ptrdiff_t>(c) * stride;
      for (int i = 0; i < n; ++i) col[i] *= w[i];
    }
    return;
  }
  if (n == 6) {
    // The SE(3) factors: plain fixed-size products, which Eigen unrolls (a
    // triangular view takes its general blocked path even at 6x6).
    int c = 0;
    for (; c + 6 <= cols; c += 6) {
      Eigen::Map<Mat6, 0, Eigen::OuterStride<>> Jm(J + static_cast<std::ptrdiff_t>(c) * stride, 6, 6,
                                                   Eigen::OuterStride<>(stride));
      const Mat6 t = W6_ * Jm;
      Jm = t;
    }
    for (; c < cols; ++c) {
      Eigen::Map<Vec6> v(J + static_cast<std::ptrdiff_t>(c) * stride);
      const Vec6 t = W6_ * v;
      v = t;
    }
    return;
  }
  Eigen::Map<MatX, 0, Eigen::OuterStride<>> Jm(J, n, cols, Eigen::OuterStride<>(stride));
  Jm = sqrt_information_.triangularView<Eigen::Upper>() * Jm;
}

}  // namespace fgcal
