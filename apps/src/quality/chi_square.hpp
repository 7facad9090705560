// The chi-square distribution, for the quality checks' thresholds: each check
// compares a statistic with its distribution under a correct model and flags
// it beyond a fixed false-alarm rate, never beyond a tuned constant.
#pragma once

namespace fgcal::apps::quality {

/// P(X <= x) for X ~ chi-square(dof), dof > 0 (not necessarily an integer).
double chiSquareCdf(double x, double dof);
/// P(X > x), accurate far into the tail (no 1 - cdf cancellation).
double chiSquareSf(double x, double dof);
/// The x with P(X <= x) = p, 0 < p < 1.
double chiSquareQuantile(double p, double dof);

}  // namespace fgcal::apps::quality
