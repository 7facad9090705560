// SO(3) and SE(3): every operation's Jacobian against central differences
// through the retraction, at identity, near identity, near pi and at random
// points; the manifold invariants; exp/log round trips.
#include <random>

#include "fgcal/core/internal/lie_series.hpp"
#include "fgcal/core/se3.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;
using fgcal::test::se3TestPoints;

namespace {
std::vector<SO3> so3TestPoints() {
  std::vector<SO3> out;
  for (const SE3& T : se3TestPoints(11)) out.push_back(T.so3());
  return out;
}
}  // namespace

TEST_CASE("SO3 exp/log round trip is exact near 0 and near pi") {
  std::mt19937 gen(3);
  std::normal_distribution<double> n;
  for (double angle : {0.0, 1e-12, 1e-8, 1e-4, 0.3, 1.0, 2.5, M_PI - 1e-3, M_PI - 1e-7}) {
    for (int i = 0; i < 10; ++i) {
      const Vec3 w = Vec3(n(gen), n(gen), n(gen)).normalized() * angle;
      const SO3 R = SO3::exp(w);
      CHECK((R.matrix().transpose() * R.matrix() - Mat3::Identity()).norm() < 1e-14);
      CHECK((R.log() - w).norm() < 1e-10 * std::max(1.0, angle));
    }
  }
  // Exactly pi: log returns a vector of norm pi on the right axis (up to sign).
  const Vec3 axis = Vec3(1, 2, -0.5).normalized();
  const Vec3 w = SO3::exp(axis * M_PI).log();
  CHECK(std::abs(w.norm() - M_PI) < 1e-9);
  CHECK(std::abs(std::abs(w.normalized().dot(axis)) - 1.0) < 1e-9);
}

TEST_CASE("SE3 exp/log round trip and manifold invariants") {
  std::mt19937 gen(5);
  std::normal_distribution<double> n;
  for (const SE3& T : se3TestPoints()) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d[i] = 0.1 * n(gen);
    CHECK(T.minus(T.plus(Vec6::Zero())).norm() < 1e-12);  // x ⊕ 0 = x
    CHECK((T.minus(T.plus(d)) - d).norm() < 1e-10);        // (x ⊕ d) ⊖ x = d
    const Vec6 xi = T.log();
    CHECK((SE3::exp(xi).matrix() - T.matrix()).norm() < 1e-9);
  }
}

TEST_CASE("SE3 log's fused Jacobian equals Jr^-1 of its result at every angle") {
  // SE3::log builds Jr^-1 from the quaternion's half-angle terms instead of
  // calling rightJacobianInverse; both must agree, on each side of every
  // series threshold (t^2 = 1e-2, r^2 = 0.0025) and up to pi.
  std::mt19937 gen(17);
  std::normal_distribution<double> n;
  for (double angle : {0.0, 1e-9, 1e-5, 9.9e-4, 1.01e-3, 9.9e-3, 1.01e-2, 0.0999, 0.1, 0.1001, 1.0, 2.0, 3.0, M_PI - 1e-6}) {
    for (int i = 0; i < 20; ++i) {
      const Vec3 w = Vec3(n(gen), n(gen), n(gen)).normalized() * angle;
      const Vec3 v = Vec3(n(gen), n(gen), n(gen)) * (i % 2 ? 0.01 : 3.0);
      Vec6 xi;
      xi << w, v;
      const SE3 T = SE3::exp(xi);
      Mat6 J;
      const Vec6 log_xi = T.log(&J);
      CHECK((T.log() - log_xi).norm() == 0.0);
      CHECK((log_xi - xi).norm() < 1e-9 * std::max(1.0, v.norm()));
      const Mat6 reference = SE3::rightJacobianInverse(log_xi);
      CHECK((J - reference).norm() < 1e-9 * std::max(1.0, reference.norm()));
    }
  }
}

namespace {
// sum_k (-1)^k t^(2k) / (2k + m)!, in long double: the coefficient functions'
// own definitions as series, independent of the coefficients typed into the
// library (20 terms: exact to long double for t <= 1).
long double alternatingSeries(long double t2, int m) {
  long double sum = 0.0L, term = 1.0L;
  for (int i = 1; i <= m; ++i) term /= i;  // 1 / m!
  for (int k = 0; k < 20; ++k) {
    sum += term;
    term *= -t2 / static_cast<long double>((2 * k + m + 1) * (2 * k + m + 2));
  }
  return sum;
}
double relativeError(double x, long double ref) {
  return static_cast<double>(std::fabs(static_cast<long double>(x) - ref) / std::fabs(ref));
}
}  // namespace

TEST_CASE("the coefficient series are exact to double precision up to their threshold") {
  // a = sin t / t, b = (1 - cos t) / t^2, c = (t - sin t) / t^3 (exp and the
  // Jacobians); Q's c1 = c, c2 = (t^2/2 + cos t - 1) / t^4 and
  // c3 = -c2 - 3 (t - sin t - t^3/6) / t^5, against their definitions summed in
  // long double. Below |t| = 0.1 the library takes its series; above, its
  // closed forms, which lose digits to cancellation as t shrinks.
  for (double t : {0.0, 1e-6, 1e-3, 0.01, 0.05, 0.0999, 0.1001, 0.2, 0.5, 1.0}) {
    INFO("t = " << t);
    const double t2 = t * t;
    double a, b, c, c1, c2, c3;
    detail::so3Coefficients(t2, a, b, c);
    detail::se3QCoefficients(t2, t, std::sin(t), std::cos(t), c1, c2, c3);
    const long double T2 = static_cast<long double>(t2);
    const long double ref_c2 = alternatingSeries(T2, 4);
    const long double ref_c3 = -ref_c2 + 3.0L * alternatingSeries(T2, 5);
    const double tol = t2 < detail::kSeriesTheta2 ? 1e-15 : 1e-9;
    CHECK(relativeError(a, alternatingSeries(T2, 1)) < tol);
    CHECK(relativeError(b, alternatingSeries(T2, 2)) < tol);
    CHECK(relativeError(c, alternatingSeries(T2, 3)) < tol);
    CHECK(relativeError(c1, alternatingSeries(T2, 3)) < tol);
    CHECK(relativeError(c2, ref_c2) < tol);
    CHECK(relativeError(c3, ref_c3) < tol);
  }
  // d of Jr^-1 = I + W/2 + d W^2 (its series has Bernoulli numbers), against
  // 1/t^2 - cot(t/2) / (2 t) in long double, which keeps 15.5 digits from t =
  // 0.05 up; and Jr^-1 Jr = I on each side of the threshold.
  for (double t : {0.05, 0.07, 0.0999}) {
    const long double T = t;
    const long double ref = 1.0L / (T * T) - std::cos(T / 2.0L) / (std::sin(T / 2.0L) * 2.0L * T);
    CHECK(relativeError(detail::so3InverseCoefficientSeries(t * t), ref) < 1e-15);
  }
  std::mt19937 gen(29);
  std::normal_distribution<double> n;
  for (double t : {1e-4, 0.03, 0.0999, 0.1001, 0.5}) {
    for (int i = 0; i < 10; ++i) {
      const Vec3 w = Vec3(n(gen), n(gen), n(gen)).normalized() * t;
      CHECK((SO3::rightJacobianInverse(w) * SO3::rightJacobian(w) - Mat3::Identity()).norm() < 1e-15);
    }
  }
}

TEST_CASE("SO3 log is exact to double precision on each side of its series threshold") {
  // A unit quaternion at angle t, its rotation matrix, and the log against
  // 2 atan2(|qv|, qw) qv / |qv| in long double. tan(t/2)^2 = 0.0025 (t =
  // 0.09992) switches the log from atan2 to its series.
  std::mt19937 gen(31);
  std::normal_distribution<double> n;
  for (double t : {1e-7, 1e-3, 0.05, 0.0999, 0.09998, 0.1, 0.11, 1.0}) {
    for (int i = 0; i < 20; ++i) {
      const Vec3 axis = Vec3(n(gen), n(gen), n(gen)).normalized();
      const Eigen::Quaterniond q(Eigen::AngleAxisd(t, axis));
      const Mat3 R = q.toRotationMatrix();
      const Eigen::Quaterniond qr(R);  // the log starts from it, or from 4 qw times it below the series threshold
      const long double qw = qr.w(), nv = std::sqrt(static_cast<long double>(qr.vec().squaredNorm()));
      const long double k = 2.0L * std::atan2(nv, qw) / nv;
      const Vec3 w = SO3(R).log();
      for (int j = 0; j < 3; ++j)
        CHECK(std::fabs(static_cast<long double>(w[j]) - k * static_cast<long double>(qr.vec()[j])) <=
              5e-16L * static_cast<long double>(t));
    }
  }
}

TEST_CASE("the block form of -Jlog Ad(D^-1) equals the 6x6 product") {
  std::mt19937 gen(23);
  std::normal_distribution<double> n;
  for (double angle : {0.0, 1e-6, 0.3, 2.0, M_PI - 1e-6}) {
    for (int i = 0; i < 10; ++i) {
      Vec6 xi, d;
      xi << Vec3(n(gen), n(gen), n(gen)).normalized() * angle, Vec3(n(gen), n(gen), n(gen));
      d << Vec3(n(gen), n(gen), n(gen)), Vec3(n(gen), n(gen), n(gen)) * 2.0;
      const SE3 E = SE3::exp(xi), D = SE3::exp(d);
      Mat6 J;
      E.log(&J);
      const Mat6 reference = -J * D.inverse().adjoint();
      CHECK((SE3::minusLogJacobianTimesInverseAdjoint(J, D) - reference).norm() < 1e-12 * (1.0 + reference.norm()));
    }
  }
}

TEST_CASE("SO3 Jacobians of exp, log, compose, inverse, between, act") {
  std::mt19937 gen(9);
  std::normal_distribution<double> n;
  const auto pts = so3TestPoints();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const SO3& A = pts[i];
    const SO3& B = pts[(i + 3) % pts.size()];
    const Vec3 p(n(gen), n(gen), n(gen));
    Mat3 J1, J2;
    A.compose(B, &J1, &J2);
    CHECK_JACOBIAN(J1, [&](const SO3& x) { return x.compose(B); }, A);
    CHECK_JACOBIAN(J2, [&](const SO3& x) { return A.compose(x); }, B);
    A.between(B, &J1, &J2);
    CHECK_JACOBIAN(J1, [&](const SO3& x) { return x.between(B); }, A);
    CHECK_JACOBIAN(J2, [&](const SO3& x) { return A.between(x); }, B);
    A.inverse(&J1);
    CHECK_JACOBIAN(J1, [&](const SO3& x) { return x.inverse(); }, A);
    A.act(p, &J1, &J2);
    CHECK_JACOBIAN(J1, [&](const SO3& x) { return x.act(p); }, A);
    CHECK_JACOBIAN(J2, [&](const Vec3& x) { return A.act(x); }, p);
    const Vec3 w = A.log(&J1);
    if (w.norm() < M_PI - 1e-3) {  // Log is not differentiable at pi itself
      CHECK_JACOBIAN(J1, [&](const SO3& x) { return x.log(); }, A);
    }
    SO3::exp(w, &J1);
    CHECK_JACOBIAN(J1, [&](const Vec3& x) { return SO3::exp(x); }, w);
    CHECK((SO3::rightJacobianInverse(w) * SO3::rightJacobian(w) - Mat3::Identity()).norm() < 1e-9);
    CHECK((SO3::leftJacobianInverse(w) * SO3::leftJacobian(w) - Mat3::Identity()).norm() < 1e-9);
  }
}

TEST_CASE("SE3 Jacobians of exp, log, compose, inverse, between, act") {
  std::mt19937 gen(13);
  std::normal_distribution<double> n;
  const auto pts = se3TestPoints();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const SE3& A = pts[i];
    const SE3& B = pts[(i + 5) % pts.size()];
    const Vec3 p(n(gen), n(gen), n(gen));
    Mat6 J1, J2;
    A.compose(B, &J1, &J2);
    CHECK_JACOBIAN(J1, [&](const SE3& x) { return x.compose(B); }, A);
    CHECK_JACOBIAN(J2, [&](const SE3& x) { return A.compose(x); }, B);
    A.between(B, &J1, &J2);
    CHECK_JACOBIAN(J1, [&](const SE3& x) { return x.between(B); }, A);
    CHECK_JACOBIAN(J2, [&](const SE3& x) { return A.between(x); }, B);
    A.inverse(&J1);
    CHECK_JACOBIAN(J1, [&](const SE3& x) { return x.inverse(); }, A);
    Mat36 Jt;
    Mat3 Jp;
    A.act(p, &Jt, &Jp);
    CHECK_JACOBIAN(Jt, [&](const SE3& x) { return x.act(p); }, A);
    CHECK_JACOBIAN(Jp, [&](const Vec3& x) { return A.act(x); }, p);
    const Vec6 xi = A.log(&J1);
    if (xi.head<3>().norm() < M_PI - 1e-3) {
      CHECK_JACOBIAN(J1, [&](const SE3& x) { return x.log(); }, A);
    }
    SE3::exp(xi, &J1);
    CHECK_JACOBIAN(J1, [&](const Vec6& x) { return SE3::exp(x); }, xi);
    CHECK((SE3::rightJacobianInverse(xi) * SE3::rightJacobian(xi) - Mat6::Identity()).norm() < 1e-8);
    CHECK((SE3::leftJacobianInverse(xi) * SE3::leftJacobian(xi) - Mat6::Identity()).norm() < 1e-8);
    // Adjoint: T Exp(d) T^-1 = Exp(Ad d).
    Vec6 d;
    for (int k = 0; k < 6; ++k) d[k] = 0.3 * n(gen);
    CHECK((A.compose(SE3::exp(d)).compose(A.inverse()).matrix() - SE3::exp(A.adjoint() * d).matrix()).norm() <
          1e-9);
  }
}

TEST_CASE("the Jacobian checker catches a wrong Jacobian") {
  const SE3 A = se3TestPoints()[5];
  const SE3 B = se3TestPoints()[7];
  Mat6 J1;
  A.compose(B, &J1, nullptr);
  Mat6 wrong = J1;
  wrong(3, 1) += 1e-3;  // a small error in one entry
  const auto cmp = fgcal::test::checkJacobian(wrong, [&](const SE3& x) { return x.compose(B); }, A);
  CHECK_FALSE(cmp.ok);
  CHECK(cmp.message.find("(3,1)") != std::string::npos);
  // Identity instead of Ad(B^-1): the classic mistake.
  CHECK_FALSE(fgcal::test::checkJacobian(MatX(Mat6::Identity()), [&](const SE3& x) { return x.compose(B); }, A).ok);
}

TEST_CASE("checked construction rejects non-rotations") {
  Mat4 T = Mat4::Identity();
  T(0, 1) = 0.2;
  CHECK_THROWS_AS(SE3::fromMatrix(T), std::invalid_argument);
  Mat4 U = Mat4::Identity();
  U(3, 0) = 1.0;
  CHECK_THROWS_AS(SE3::fromMatrix(U), std::invalid_argument);
  Mat4 N = Mat4::Identity();
  N(1, 1) = std::nan("");
  CHECK_THROWS_AS(SE3::fromMatrix(N), std::invalid_argument);
  Mat4 M = Mat4::Identity();
  M(2, 2) = -1.0;  // a reflection
  CHECK_THROWS_AS(SE3::fromMatrix(M), std::invalid_argument);
  CHECK_NOTHROW(SE3::fromMatrix(SE3::exp((Vec6() << 0.1, 0.2, 0.3, 1, 2, 3).finished()).matrix()));
}

TEST_CASE("roll-pitch-yaw follows the URDF convention") {
  const SO3 R = SO3::fromRpy(0.1, -0.4, 2.0);
  const Mat3 expected = (Eigen::AngleAxisd(2.0, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.4, Vec3::UnitY()) *
                         Eigen::AngleAxisd(0.1, Vec3::UnitX()))
                            .toRotationMatrix();
  CHECK((R.matrix() - expected).norm() < 1e-14);
  CHECK((R.rpy() - Vec3(0.1, -0.4, 2.0)).norm() < 1e-12);
}

TEST_CASE("roll-pitch-yaw gives the rotation back at and near gimbal lock") {
  // A URDF origin is written from rpy(): near pitch = +-90 deg roll and yaw
  // each lose digits, and the rotation they compose must not.
  double worst = 0.0;
  for (const double pitch : {M_PI / 2, -M_PI / 2, M_PI / 2 - 1e-13, M_PI / 2 - 1e-9, -M_PI / 2 + 1e-7,
                             M_PI / 2 - 1e-4, 0.3})
    for (const double roll : {0.0, 0.4, -3.0})
      for (const double yaw : {0.0, 0.7, -2.9}) {
        const SO3 R = SO3::fromRpy(roll, pitch, yaw);
        const Vec3 rpy = R.rpy();
        worst = std::max(worst, R.between(SO3::fromRpy(rpy[0], rpy[1], rpy[2])).log().norm());
        CHECK(std::abs(rpy[1] - pitch) < 1e-9);
      }
  INFO("worst rotation gap " << worst << " rad");
  CHECK(worst < 1e-12);
  // At the lock itself, everything goes into yaw.
  CHECK(SO3::fromRpy(0.4, M_PI / 2, 0.7).rpy()[0] == 0.0);
}
