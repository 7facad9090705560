#include "fgcal/apps/joint_trajectory.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "fgcal/apps/errors.hpp"

namespace fgcal::apps {

namespace {

// Uniform cubic B-spline basis on one knot interval, u in [0, 1], and its
// derivative in u.
void basis(double u, double b[4]) {
  const double v = 1.0 - u, u2 = u * u, u3 = u2 * u;
  b[0] = v * v * v / 6.0;
  b[1] = (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0;
  b[2] = (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0;
  b[3] = u3 / 6.0;
}
void basisDerivative(double u, double d[4]) {
  const double v = 1.0 - u;
  d[0] = -0.5 * v * v;
  d[1] = 0.5 * (3.0 * u * u - 4.0 * u);
  d[2] = 0.5 * (-3.0 * u * u + 2.0 * u + 1.0);
  d[3] = 0.5 * u * u;
}

double medianPeriod(const std::vector<std::int64_t>& st) {
  std::vector<double> d;
  d.reserve(st.size() - 1);
  for (std::size_t i = 1; i < st.size(); ++i) d.push_back(static_cast<double>(st[i] - st[i - 1]) * 1e-9);
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

std::string ms(double seconds) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << seconds * 1e3 << " ms";
  return s.str();
}

}  // namespace

namespace {

/// The least-squares cubic B-spline of `columns` of `log` on `intervals`
/// uniform knot intervals of `h` seconds (t = 0 at the log's first sample),
/// and the fit's residual sum of squares over every joint's finite samples.
struct SplineFit {
  Eigen::MatrixXd coefficients;  // (intervals + 3) x columns
  double rss = 0.0;
};

SplineFit fitSpline(const JointLog& log, const std::vector<int>& columns, const std::string& source,
                    const std::vector<double>& t, int intervals, double h) {
  const int n_coef = intervals + 3;
  SplineFit fit;
  fit.coefficients.setZero(n_coef, static_cast<Eigen::Index>(columns.size()));

  // Where each sample falls: its interval and basis values (shared by the joints).
  const std::size_t n = t.size();
  std::vector<int> interval(n);
  std::vector<std::array<double, 4>> b(n);
  for (std::size_t s = 0; s < n; ++s) {
    const int k = std::clamp(static_cast<int>(std::floor(t[s] / h)), 0, intervals - 1);
    interval[s] = k;
    basis(std::clamp(t[s] / h - k, 0.0, 1.0), b[s].data());
  }

  for (std::size_t j = 0; j < columns.size(); ++j) {
    const int col = columns[j];
    if (col < 0 || col >= log.positions.cols())
      throw InputError(source, "", "joint column index " + std::to_string(col) + " out of range");
    // Normal equations of the least-squares fit: banded, 7 diagonals.
    Eigen::MatrixXd band = Eigen::MatrixXd::Zero(n_coef, 4);  // band(i, d) = A(i, i + d)
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n_coef);
    int finite = 0;
    for (std::size_t s = 0; s < n; ++s) {
      const double y = log.positions(static_cast<Eigen::Index>(s), col);
      if (!std::isfinite(y)) continue;
      ++finite;
      const int k = interval[s];
      for (int a = 0; a < 4; ++a) {
        rhs[k + a] += b[s][a] * y;
        for (int c = a; c < 4; ++c) band(k + a, c - a) += b[s][a] * b[s][c];
      }
    }
    if (finite == 0)
      throw InputError(source, log.names[static_cast<std::size_t>(col)],
                       "the joint has no finite value: its trajectory (for the time offsets) cannot be fitted");
    // The penalty lambda |second differences of c|^2 is zero on any line and
    // vanishes in the interior for cubics too (its gradient is a fourth
    // difference): it only decides where the data say nothing (gaps, NaN
    // samples). Scaled to the data's weight per coefficient, 1e-4 of it.
    const double lambda = 1e-4 * std::max(1.0, static_cast<double>(finite) / n_coef);
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(static_cast<std::size_t>(n_coef) * 4);
    Eigen::MatrixXd pen = Eigen::MatrixXd::Zero(n_coef, 3);
    for (int i = 0; i + 2 < n_coef; ++i) {
      const double w[3] = {1.0, -2.0, 1.0};
      for (int a = 0; a < 3; ++a)
        for (int c = a; c < 3; ++c) pen(i + a, c - a) += lambda * w[a] * w[c];
    }
    for (int i = 0; i < n_coef; ++i)
      for (int d = 0; d < 4 && i + d < n_coef; ++d) {
        double v = band(i, d) + (d < 3 ? pen(i, d) : 0.0);
        if (d == 0) v += 1e-12 * lambda;  // positive definite even with one finite sample
        if (v != 0.0) trip.emplace_back(i + d, i, v);  // lower triangle
      }
    Eigen::SparseMatrix<double> A(n_coef, n_coef);
    A.setFromTriplets(trip.begin(), trip.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(A);
    if (ldlt.info() != Eigen::Success)
      throw InputError(source, log.names[static_cast<std::size_t>(col)], "the joint's trajectory cannot be fitted");
    auto c = fit.coefficients.col(static_cast<Eigen::Index>(j));
    c = ldlt.solve(rhs);
    for (std::size_t s = 0; s < n; ++s) {
      const double y = log.positions(static_cast<Eigen::Index>(s), col);
      if (!std::isfinite(y)) continue;
      const int k = interval[s];
      const double r = y - (b[s][0] * c[k] + b[s][1] * c[k + 1] + b[s][2] * c[k + 2] + b[s][3] * c[k + 3]);
      fit.rss += r * r;
    }
  }
  return fit;
}

/// Finite samples over every column.
double finiteSamples(const JointLog& log, const std::vector<int>& columns) {
  double n = 0.0;
  for (int col : columns)
    if (col >= 0 && col < log.positions.cols()) n += log.positions.col(col).array().isFinite().count();
  return n;
}

}  // namespace

JointLogTrajectory::JointLogTrajectory(const JointLog& log, const std::vector<int>& columns, const std::string& source,
                                       double knot_spacing_s) {
  const auto& st = log.stamps_ns;
  if (st.size() < 2)
    throw InputError(source, "", "a joint trajectory needs at least 2 samples, the log has " +
                                     std::to_string(st.size()));
  first_ns_ = st.front();
  last_ns_ = st.back();
  duration_ = seconds(last_ns_);
  std::vector<double> t(st.size());
  for (std::size_t s = 0; s < st.size(); ++s) t[s] = seconds(st[s]);
  auto intervalsFor = [&](double h) { return std::max(1, static_cast<int>(std::lround(duration_ / h))); };

  if (knot_spacing_s > 0.0) {
    intervals_ = intervalsFor(knot_spacing_s);
    h_ = duration_ / intervals_;
    coefficients_ = fitSpline(log, columns, source, t, intervals_, h_).coefficients;
    return;
  }
  // The knot spacing by generalized cross-validation, RSS / (n (1 - p/n)^2)
  // with p coefficients for n samples, over kJointTrajectoryKnotFactors x the
  // base spacing: the widest knots that still follow the motion average the
  // most samples.
  const double base = std::max(kJointTrajectoryKnotSpacingS, 4.0 * medianPeriod(st));
  const double n = finiteSamples(log, columns);
  double best_score = std::numeric_limits<double>::infinity();
  for (double factor : kJointTrajectoryKnotFactors) {
    const int intervals = intervalsFor(base * factor);
    if (factor != kJointTrajectoryKnotFactors[0] && intervals == intervals_) continue;
    const double p = static_cast<double>(intervals + 3) * static_cast<double>(columns.size());
    if (factor != kJointTrajectoryKnotFactors[0] && !(p < 0.5 * n)) continue;  // too few samples to judge
    const double h = duration_ / intervals;
    SplineFit fit = fitSpline(log, columns, source, t, intervals, h);
    const double dof = 1.0 - p / n;
    const double score = dof > 0.0 ? fit.rss / (n * dof * dof) : std::numeric_limits<double>::infinity();
    if (factor == kJointTrajectoryKnotFactors[0] || score < best_score) {
      best_score = score;
      intervals_ = intervals;
      h_ = h;
      coefficients_ = std::move(fit.coefficients);
    }
  }
}

double JointLogTrajectory::seconds(std::int64_t stamp_ns) const {
  // Unsigned difference: defined for any stamps; exact below 2^53 ns.
  const std::uint64_t d = static_cast<std::uint64_t>(stamp_ns) - static_cast<std::uint64_t>(first_ns_);
  return stamp_ns >= first_ns_ ? static_cast<double>(d) * 1e-9 : -static_cast<double>(-d) * 1e-9;
}

void JointLogTrajectory::evaluateInside(double t, double* q, double* q_dot) const {
  const int k = std::clamp(static_cast<int>(std::floor(t / h_)), 0, intervals_ - 1);
  const double u = std::clamp(t / h_ - k, 0.0, 1.0);
  double b[4], d[4];
  basis(u, b);
  if (q_dot) basisDerivative(u, d);
  for (Eigen::Index j = 0; j < coefficients_.cols(); ++j) {
    const auto c = coefficients_.col(j).segment<4>(k);
    q[j] = b[0] * c[0] + b[1] * c[1] + b[2] * c[2] + b[3] * c[3];
    if (q_dot) q_dot[j] = (d[0] * c[0] + d[1] * c[1] + d[2] * c[2] + d[3] * c[3]) / h_;
  }
}

void JointLogTrajectory::evaluate(double t, VecX* q, VecX* q_dot) const {
  const Eigen::Index n = coefficients_.cols();
  q->resize(n);
  const double end = t < 0.0 ? 0.0 : (t > duration_ ? duration_ : t);
  if (end == t) {
    if (q_dot) q_dot->resize(n);
    evaluateInside(t, q->data(), q_dot ? q_dot->data() : nullptr);
    return;
  }
  // Past the span: the end value continued at the end velocity.
  VecX v_own;
  VecX& v = q_dot ? *q_dot : v_own;
  v.resize(n);
  evaluateInside(end, q->data(), v.data());
  *q += (t - end) * v;
}

void checkTimeOffsetMargin(const TimeOffsetMargin& images, double offset, const JointLogTrajectory& traj,
                           const std::string& log_name, double readout_s) {
  const double first = traj.seconds(images.first_image_ns), last = traj.seconds(images.last_image_ns);
  // The last image's last row is exposed a readout after its first.
  const double late = offset + readout_s;
  const bool before = first + offset < 0.0, after = last + late > traj.duration();
  if (!before && !after) return;
  std::ostringstream m;
  m << "camera " << images.camera << "'s estimated time offset " << (offset >= 0 ? "+" : "") << ms(offset);
  if (readout_s > 0.0) m << " and rolling-shutter readout " << ms(readout_s);
  m << " put" << (readout_s > 0.0 ? "" : "s") << " its " << (before ? "first" : "last") << " image (stamp "
    << (before ? images.first_image_ns : images.last_image_ns) << ") "
    << (before ? ms(-(first + offset)) + " before the joint log's first sample (stamp " +
                     std::to_string(traj.firstStampNs()) + ")"
               : ms(last + late - traj.duration()) + " after the joint log's last sample (stamp " +
                     std::to_string(traj.lastStampNs()) + ")")
    << ": the log's margin at that end is " << ms(before ? first : traj.duration() - last)
    << ", less than " << (readout_s > 0.0 ? "that" : "the offset")
    << ", so the joints at that exposure are unknown and the estimate cannot be trusted. "
       "Record the joints longer than the images at both ends (by more than the expected offset and readout), or "
       "leave time-offset and rolling-shutter out of --estimate";
  throw InputError(log_name, "time offset of camera " + images.camera, m.str());
}

}  // namespace fgcal::apps
