// Like factors evaluated two at a time (the pairing schedule): the H, g and
// cost of one by one, which factors pair, and the limits that switch it off.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

namespace {
// A prior that counts the pairs it evaluates, through PriorFactorSE3's own
// fast path.
class CountingPrior final : public Factor {
 public:
  CountingPrior(const PriorFactorSE3& inner, int* pairs, RobustKernel::Ptr robust = nullptr)
      : Factor(inner.keys(), inner.noiseModelPtr(), std::move(robust)), inner_(inner), pairs_(pairs) {
    static const FastPath path;
    internal::registerNormalEquations(typeid(CountingPrior), path);
  }
  void evaluate(const Variable* const* vars, double* r, double* const* J) const override { inner_.evaluate(vars, r, J); }

 private:
  struct FastPath final : internal::NormalEquations {
    static const internal::NormalEquations& prior() { return *internal::normalEquationsFor(typeid(PriorFactorSE3)); }
    void whitened(const Factor& f, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      prior().whitened(static_cast<const CountingPrior&>(f).inner_, vars, r, g, H);
    }
    bool pairs() const override { return true; }
    void whitenedPair(const Factor& a, const Factor& b, const Variable* const* vars_a, const Variable* const* vars_b,
                      double* r_a, double* const* g_a, double* const* H_a, double* r_b, double* const* g_b,
                      double* const* H_b) const override {
      const auto& ca = static_cast<const CountingPrior&>(a);
      prior().whitenedPair(ca.inner_, static_cast<const CountingPrior&>(b).inner_, vars_a, vars_b, r_a, g_a, H_a, r_b,
                           g_b, H_b);
      ++*ca.pairs_;
    }
  };
  PriorFactorSE3 inner_;
  int* pairs_;
};
}  // namespace

TEST_CASE("like factors evaluated in pairs give the H, g and cost of one by one") {
  // A calibration-shaped graph (each board's prior, then its views) near its
  // optimum, where the pairs' series apply; a Huber kernel on some views.
  ArrowProblem p = makeArrowProblem(3, 700, 11);
  const Values at = optimize(p.graph, p.values).values;
  // Each board's prior after its views: pairing the priors moves the next
  // board's prior ahead of that board's views, so the first write of its
  // block of H (which assigns) is the prior's in the order of evaluation.
  int pairs = 0;
  FactorGraph g;
  Factor::Ptr pending;
  for (std::size_t f = 0; f < p.graph.size(); ++f) {
    const Factor::Ptr& factor = p.graph.at(f);
    if (const auto* prior = dynamic_cast<const PriorFactorSE3*>(factor.get())) {
      if (pending) g.add(pending);
      // Every seventh prior with a Huber kernel (weights differ inside a pair).
      pending = std::make_shared<CountingPrior>(*prior, &pairs, f % 7 == 0 ? huber(0.01) : nullptr);
    } else {
      g.add(factor);
      if (f % 5 == 0) p.graph.at(f)->setRobustKernel(huber(0.02));
    }
  }
  g.add(pending);
  // Weak extra priors up to 4096 factors: the most that are paired here
  // (pair_max_factors below), and the fewest that two threads share.
  int priors = 700;
  for (int b = 0; g.size() < 4096; ++b, ++priors)
    g.emplace<CountingPrior>(
        PriorFactorSE3(key('b', b % 700), at.at<SE3>(key('b', b % 700)), NoiseModel::isotropic(6, 1.0)), &pairs);
  REQUIRE(g.size() == 4096);
  LinearSystemOptions paired, single, with_j;
  paired.order_for_schur = single.order_for_schur = with_j.order_for_schur = true;
  paired.store_jacobian = single.store_jacobian = false;
  paired.pair_max_factors = 4096;
  single.pair_factors = false;
  LinearSystem sp(g, at, {}, paired), ss(g, at, {}, single), sj(g, at, {}, with_j);
  // Relinearized after a linearization elsewhere: every block of H rewritten
  // in the pairs' order of evaluation.
  sp.linearize(p.values);
  pairs = 0;
  const double cp = sp.linearize(at);
  CHECK(pairs == priors / 2);  // in pairs although each board's views come between its prior and the next
  pairs = 0;
  const double cs = ss.linearize(at), cj = sj.linearize(at);
  CHECK(pairs == 0);  // pair_factors off, and never with a stored J
  CHECK(cp == Approx(cs).epsilon(1e-13));
  CHECK(cj == Approx(cs).epsilon(1e-13));
  CHECK(relativeMaxDifference(sp.hessianUpper().values, ss.hessianUpper().values) <= 1e-12);
  CHECK((sp.gradient() - ss.gradient()).norm() <= 1e-12 * ss.gradient().norm());
  // The cost alone takes the same pairs, to the same bits (the optimizer compares the two).
  pairs = 0;
  CHECK(sp.cost(at) == cp);
  CHECK(pairs == priors / 2);
  // Two threads split the schedule (a pair across the split goes singly).
  LinearSystemOptions two = paired;
  two.threads = 2;
  LinearSystem s2(g, at, {}, two);
  const double c2 = s2.linearize(at);
  REQUIRE(s2.lastLinearizeThreads() == 2);
  CHECK(relativeMaxDifference(s2.hessianUpper().values, ss.hessianUpper().values) <= 1e-12);
  CHECK((s2.gradient() - ss.gradient()).norm() <= 1e-12 * ss.gradient().norm());
  CHECK(c2 == Approx(cs).epsilon(1e-13));
  // A fixed camera (its slots have no columns), paired and not.
  {
    LinearSystem fp(g, at, {key('c', 1)}, paired), fs(g, at, {key('c', 1)}, single);
    pairs = 0;
    CHECK(fp.linearize(at) == Approx(fs.linearize(at)).epsilon(1e-13));
    CHECK(pairs == priors / 2);
    CHECK(relativeMaxDifference(fp.hessianUpper().values, fs.hessianUpper().values) <= 1e-12);
    CHECK((fp.gradient() - fs.gradient()).norm() <= 1e-12 * fs.gradient().norm());
  }
  // One factor more than pair_max_factors: no pairs; the default limit pairs it.
  {
    FactorGraph big = g;
    big.emplace<CountingPrior>(PriorFactorSE3(key('b', 0), at.at<SE3>(key('b', 0)), NoiseModel::isotropic(6, 1.0)),
                               &pairs);
    LinearSystem sb(big, at, {}, paired);
    pairs = 0;
    sb.linearize(at);
    sb.cost(at);
    CHECK(pairs == 0);
    LinearSystemOptions by_default;
    by_default.store_jacobian = false;
    REQUIRE(big.size() <= by_default.pair_max_factors);
    LinearSystem sd(big, at, {}, by_default);
    pairs = 0;
    sd.linearize(at);
    CHECK(pairs == (priors + 1) / 2);
  }
  // The optimizer (which pairs) reaches the optimum of the factors evaluated one by one.
  ss.linearize(p.values);
  const double g0 = ss.gradient().norm();
  const OptimizerResult r = optimize(g, p.values);
  REQUIRE(r.converged);
  ss.linearize(r.values);
  CHECK(ss.gradient().norm() <= 1e-6 * g0);
}
