// Regularized incomplete gamma functions (series below a + 1, Lentz's
// continued fraction above), the chi-square's CDF and survival function
// through them, and its quantile by bisection on the survival function.
#include "quality/chi_square.hpp"

#include <cmath>
#include <limits>

namespace fgcal::apps::quality {

namespace {

constexpr int kMaxTerms = 1000;
constexpr double kEps = 1e-15;

/// P(a, x) by its series; valid for x < a + 1.
double lowerSeries(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < kMaxTerms; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * kEps) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Q(a, x) by its continued fraction; valid for x >= a + 1.
double upperFraction(double a, double x) {
  constexpr double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int n = 1; n < kMaxTerms; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < kEps) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double chiSquareCdf(double x, double dof) {
  if (!(x > 0.0)) return 0.0;
  if (std::isinf(x)) return 1.0;
  const double a = 0.5 * dof, h = 0.5 * x;
  return h < a + 1.0 ? lowerSeries(a, h) : 1.0 - upperFraction(a, h);
}

double chiSquareSf(double x, double dof) {
  if (!(x > 0.0)) return 1.0;
  if (std::isinf(x)) return 0.0;
  const double a = 0.5 * dof, h = 0.5 * x;
  return h < a + 1.0 ? 1.0 - lowerSeries(a, h) : upperFraction(a, h);
}

double chiSquareQuantile(double p, double dof) {
  if (!(p > 0.0)) return 0.0;
  if (!(p < 1.0)) return std::numeric_limits<double>::infinity();
  const double q = 1.0 - p;
  double lo = 0.0, hi = dof + 10.0 * std::sqrt(2.0 * dof) + 50.0;
  while (chiSquareSf(hi, dof) > q) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chiSquareSf(mid, dof) > q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace fgcal::apps::quality
