#include "fgcal_test/jacobian_check.hpp"

#include <cmath>
#include <limits>
#include <random>

namespace fgcal::test {

JacobianComparison compareJacobians(const MatX& analytic, const MatX& numeric, double tol,
                                    const std::string& what) {
  JacobianComparison out;
  if (analytic.rows() != numeric.rows() || analytic.cols() != numeric.cols()) {
    std::ostringstream s;
    s << what << ": analytic is " << analytic.rows() << "x" << analytic.cols() << ", numeric is "
      << numeric.rows() << "x" << numeric.cols();
    out.ok = false;
    out.message = s.str();
    return out;
  }
  Eigen::Index wr = 0, wc = 0;
  double worst_ratio = 0.0;
  for (Eigen::Index c = 0; c < analytic.cols(); ++c)
    for (Eigen::Index r = 0; r < analytic.rows(); ++r) {
      const double err = std::abs(analytic(r, c) - numeric(r, c));
      out.max_abs_error = std::max(out.max_abs_error, err);
      double ratio = err / (tol * (1.0 + std::abs(numeric(r, c))));
      if (!std::isfinite(ratio)) ratio = std::numeric_limits<double>::infinity();  // NaN is wrong
      if (ratio > worst_ratio) {
        worst_ratio = ratio;
        wr = r;
        wc = c;
      }
    }
  if (!(worst_ratio <= 1.0)) {
    std::ostringstream s;
    s << what << " is wrong: worst entry (" << wr << "," << wc << ") analytic " << analytic(wr, wc)
      << " vs numeric " << numeric(wr, wc) << "\nanalytic:\n"
      << analytic << "\nnumeric:\n"
      << numeric;
    out.ok = false;
    out.message = s.str();
  }
  return out;
}

std::vector<SE3> se3TestPoints(unsigned seed, int random_count) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  auto rnd = [&]() { return Vec3(n(gen), n(gen), n(gen)); };
  std::vector<SE3> pts;
  pts.push_back(SE3::identity());
  Vec6 tiny;
  tiny << 1e-9, -2e-9, 3e-9, 1e-9, 0.0, -1e-9;
  pts.push_back(SE3::exp(tiny));
  Vec6 small;
  small << 1e-4, 2e-4, -1e-4, 0.01, -0.02, 0.03;
  pts.push_back(SE3::exp(small));
  Vec6 near_pi;
  near_pi.head<3>() = rnd().normalized() * (M_PI - 1e-4);
  near_pi.tail<3>() = rnd();
  pts.push_back(SE3::exp(near_pi));
  for (int i = 0; i < random_count; ++i) {
    Vec6 xi;
    xi.head<3>() = rnd().normalized() * std::uniform_real_distribution<double>(0.0, M_PI)(gen);
    xi.tail<3>() = rnd();
    pts.push_back(SE3::exp(xi));
  }
  return pts;
}

}  // namespace fgcal::test
