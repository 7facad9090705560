// Gauss-Newton and Levenberg-Marquardt on SE(3) pose graphs: agreement with an
// independent dense solve, convergence on hundreds of poses with loop
// closures, marginals against the dense inverse and against Monte Carlo,
// robust kernels under 20 % outliers, and the failure statuses.
#include <map>
#include <random>

#include <Eigen/Cholesky>

#include "fgcal/core/marginals.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "sloppy_prior.hpp"

using namespace fgcal;

namespace {

struct PoseGraph {
  FactorGraph graph;
  Values initial;
  std::vector<SE3> truth;
};

Vec6 noise6(std::mt19937& gen, double rot_sigma, double trans_sigma) {
  std::normal_distribution<double> n;
  Vec6 d;
  d << rot_sigma * n(gen), rot_sigma * n(gen), rot_sigma * n(gen), trans_sigma * n(gen), trans_sigma * n(gen),
      trans_sigma * n(gen);
  return d;
}

// Poses on a helix; odometry between consecutive poses; loop closures between
// poses a turn apart; a prior on the first. The initial guess chains the noisy
// odometry, so it drifts.
PoseGraph makePoseGraph(int n, int per_turn, unsigned seed, double rot_sigma = 0.01, double trans_sigma = 0.05) {
  std::mt19937 gen(seed);
  PoseGraph pg;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / per_turn;
    const SO3 R = SO3::exp(Vec3(0.0, 0.0, a + M_PI / 2)) * SO3::exp(Vec3(0.1 * std::sin(a), 0.0, 0.0));
    pg.truth.emplace_back(R, Vec3(5.0 * std::cos(a), 5.0 * std::sin(a), 0.05 * i));
  }
  Vec6 sig;
  sig << rot_sigma, rot_sigma, rot_sigma, trans_sigma, trans_sigma, trans_sigma;
  const auto noise = NoiseModel::diagonal(sig);
  pg.graph.emplace<PriorFactorSE3>(key('x', 0), pg.truth[0], NoiseModel::isotropic(6, 1e-3));
  auto measure = [&](int i, int j) {
    return pg.truth[i].between(pg.truth[j]).plus(noise6(gen, rot_sigma, trans_sigma));
  };
  SE3 chained = pg.truth[0];
  pg.initial.insert(key('x', 0), chained);
  for (int i = 0; i + 1 < n; ++i) {
    const SE3 z = measure(i, i + 1);
    pg.graph.emplace<RelativePoseFactor>(key('x', i), key('x', i + 1), z, noise);
    chained = chained * z;
    pg.initial.insert(key('x', i + 1), chained);
  }
  for (int i = 0; i + per_turn < n; i += 3)
    pg.graph.emplace<RelativePoseFactor>(key('x', i), key('x', i + per_turn), measure(i, i + per_turn), noise);
  return pg;
}

// An independent reference: dense Gauss-Newton straight from Factor::error,
// Eigen's dense LLT, no LinearSystem, no CHOLMOD.
Values denseGaussNewton(const FactorGraph& g, Values v, MatX* information = nullptr) {
  const auto& keys = v.keys();
  std::map<Key, int> col;
  int n = 0;
  for (Key k : keys) {
    col[k] = n;
    n += v.variable(k).dim();
  }
  for (int it = 0; it < 50; ++it) {
    MatX H = MatX::Zero(n, n);
    VecX b = VecX::Zero(n);
    for (const auto& f : g) {
      std::vector<MatX> Js;
      const MatX& W = f->noiseModel().sqrtInformation();
      const VecX r = W * f->error(v, &Js);
      MatX J = MatX::Zero(r.size(), n);
      for (std::size_t k = 0; k < f->keys().size(); ++k)
        J.middleCols(col[f->keys()[k]], Js[k].cols()) = W * Js[k];
      H += J.transpose() * J;
      b -= J.transpose() * r;
    }
    if (information) *information = H;
    const VecX dx = H.llt().solve(b);
    for (Key k : keys) v.variable(k).retract(dx.data() + col[k]);
    if (dx.norm() < 1e-12) break;
  }
  return v;
}

double maxPoseDifference(const Values& a, const Values& b) {
  double worst = 0.0;
  for (Key k : a.keys()) worst = std::max(worst, a.at<SE3>(k).minus(b.at<SE3>(k)).norm());
  return worst;
}

}  // namespace

TEST_CASE("Gauss-Newton and LM reach the optimum of an independent dense solve") {
  const PoseGraph pg = makePoseGraph(12, 6, 1);
  const Values reference = denseGaussNewton(pg.graph, pg.initial);
  for (auto alg : {OptimizerOptions::Algorithm::GaussNewton, OptimizerOptions::Algorithm::LevenbergMarquardt}) {
    OptimizerOptions opt;
    opt.algorithm = alg;
    // Tight, yet above the cost's rounding floor: translations of 5 m
    // whitened by 1 / 0.05 carry about 1e-14 of rounding per residual, so
    // near the optimum a 1e-14 relative change is noise, which a rejected
    // step can neither beat nor confirm.
    opt.relative_cost_tolerance = 1e-12;
    const OptimizerResult res = optimize(pg.graph, pg.initial, opt);
    INFO(res.message);
    CHECK(res.converged);
    CHECK(res.final_cost < res.initial_cost);
    CHECK(maxPoseDifference(res.values, reference) < 1e-7);
    CHECK(res.final_cost == Approx(pg.graph.cost(reference)).epsilon(1e-9));
  }
}

TEST_CASE("GN and LM converge on a 400-pose graph with loop closures") {
  const PoseGraph pg = makePoseGraph(400, 40, 7);
  for (auto alg : {OptimizerOptions::Algorithm::GaussNewton, OptimizerOptions::Algorithm::LevenbergMarquardt}) {
    OptimizerOptions opt;
    opt.algorithm = alg;
    std::vector<IterationReport> seen;
    opt.callback = [&](const IterationReport& r) { seen.push_back(r); };
    const OptimizerResult res = optimize(pg.graph, pg.initial, opt);
    INFO(res.message);
    REQUIRE(res.converged);
    CHECK(res.iterations < 30);
    CHECK(seen.size() == res.reports.size());
    for (std::size_t i = 1; i < res.reports.size(); ++i) CHECK(res.reports[i].cost <= res.reports[i - 1].cost);
    // The estimate sits at the noise level: 2 cost / (residuals - unknowns) ~ 1 (chi-square).
    const double dof = 6.0 * static_cast<double>(pg.graph.size()) - 6.0 * 400.0;
    CHECK(2.0 * res.final_cost / dof == Approx(1.0).margin(0.25));
    // The drifted initial guess was far off; the solution is close to the truth.
    double init_err = 0.0, final_err = 0.0;
    for (int i = 0; i < 400; ++i) {
      init_err = std::max(init_err, pg.truth[i].minus(pg.initial.at<SE3>(key('x', i))).tail<3>().norm());
      final_err = std::max(final_err, pg.truth[i].minus(res.values.at<SE3>(key('x', i))).tail<3>().norm());
    }
    CHECK(init_err > 1.0);
    CHECK(final_err < 0.5);
  }
}

TEST_CASE("marginals equal the inverse of the dense information matrix") {
  const PoseGraph pg = makePoseGraph(10, 5, 3);
  MatX information;
  const Values solution = denseGaussNewton(pg.graph, pg.initial, &information);
  const MatX dense_cov = information.inverse();
  const Marginals marg(pg.graph, solution);
  for (int i : {0, 4, 9}) CHECK((marg.covariance(key('x', i)) - dense_cov.block(6 * i, 6 * i, 6, 6)).norm() <
                                1e-8 * dense_cov.norm());
  const MatX joint = marg.jointCovariance({key('x', 7), key('x', 2)});
  CHECK((joint.block(0, 6, 6, 6) - dense_cov.block(42, 12, 6, 6)).norm() < 1e-8 * dense_cov.norm());
  CHECK_THROWS_AS(marg.covariance(key('x', 99)), std::invalid_argument);
}

TEST_CASE("marginals match the Monte-Carlo spread of the estimate") {
  // The same truth, 300 noise draws; the spread of the error of one pose
  // against the marginal covariance predicted from one solve.
  const int n = 20, trials = 300;
  const int probe = 15;
  std::vector<Vec6> errors;
  MatX predicted;
  for (int t = 0; t < trials; ++t) {
    const PoseGraph pg = makePoseGraph(n, 10, 100 + t, 0.02, 0.05);
    const OptimizerResult res = optimize(pg.graph, pg.initial);
    REQUIRE(res.converged);
    errors.push_back(pg.truth[probe].minus(res.values.at<SE3>(key('x', probe))));
    if (t == 0) predicted = Marginals(pg.graph, res.values).covariance(key('x', probe));
  }
  Mat6 sample = Mat6::Zero();
  for (const Vec6& e : errors) sample += e * e.transpose();
  sample /= trials;
  for (int i = 0; i < 6; ++i) {
    INFO("axis " << i << " sample " << sample(i, i) << " predicted " << predicted(i, i));
    CHECK(sample(i, i) == Approx(predicted(i, i)).epsilon(0.25));
  }
}

TEST_CASE("robust kernels keep the estimate near the truth with 20 % outliers") {
  std::mt19937 gen(42);
  const SE3 truth = SE3::exp((Vec6() << 0.3, -0.2, 0.5, 1.0, 2.0, -0.5).finished());
  const auto noise = NoiseModel::diagonal((Vec6() << 0.01, 0.01, 0.01, 0.01, 0.01, 0.01).finished());
  auto build = [&](RobustKernel::Ptr kernel) {
    std::mt19937 g2(42);
    FactorGraph g;
    for (int i = 0; i < 100; ++i) {
      const bool outlier = i % 5 == 0;
      const Vec6 d = outlier ? noise6(g2, 0.5, 1.0) : noise6(g2, 0.01, 0.01);
      g.emplace<PriorFactorSE3>(key('x', 0), truth.plus(d), noise, kernel);
    }
    return g;
  };
  Values init;
  init.insert(key('x', 0), SE3());
  const FactorGraph plain = build(nullptr);
  const OptimizerResult ls = optimize(plain, init);
  REQUIRE(ls.converged);
  const double ls_err = truth.minus(ls.values.at<SE3>(key('x', 0))).norm();
  CHECK(ls_err > 0.05);
  for (const auto& kernel : {huber(1.345), cauchy(2.0), tukey(4.685)}) {
    INFO(kernel->name());
    const FactorGraph robust = build(kernel);
    const OptimizerResult res = optimize(robust, ls.values);  // IRLS from the least-squares estimate
    REQUIRE(res.converged);
    const double err = truth.minus(res.values.at<SE3>(key('x', 0))).norm();
    CHECK(err < 0.01);
    CHECK(err < ls_err / 10.0);
  }
  (void)gen;
}

TEST_CASE("an unconstrained system stops with a status naming the variable") {
  PoseGraph pg = makePoseGraph(6, 3, 5);
  FactorGraph no_prior;
  for (std::size_t i = 1; i < pg.graph.size(); ++i) no_prior.add(pg.graph.at(i));  // drop the prior: gauge freedom
  OptimizerOptions opt;
  opt.algorithm = OptimizerOptions::Algorithm::GaussNewton;
  const OptimizerResult res = optimize(no_prior, pg.initial, opt);
  CHECK(res.termination == Termination::NotPositiveDefinite);
  CHECK_FALSE(res.converged);
  REQUIRE_FALSE(res.degenerate_keys.empty());
  CHECK(res.message.find("x") != std::string::npos);
  CHECK_THROWS_AS(Marginals(no_prior, pg.initial), DegenerateSystem);
}

namespace {
class BrokenFactor final : public TypedFactor<6, SE3> {
 public:
  explicit BrokenFactor(Key k) : TypedFactor({k}, NoiseModel::isotropic(6, 1.0)) {}
  Residual evaluateTyped(const SE3& X, Jacobian<SE3>* J) const override {
    if (J) J->setIdentity();  // wrong: ignores Jr^-1 and the rotation of the translation part
    return SE3::exp((Vec6() << 0.5, 0.1, 0, 1, 0, 0).finished()).inverse().compose(X).log();
  }
};
}  // namespace

TEST_CASE("check_jacobians stops before solving when a factor's Jacobian is wrong") {
  PoseGraph pg = makePoseGraph(6, 3, 5);
  OptimizerOptions opt;
  opt.check_jacobians = true;
  CHECK(optimize(pg.graph, pg.initial, opt).converged);  // the real factors pass
  pg.graph.emplace<BrokenFactor>(key('x', 3));
  const OptimizerResult res = optimize(pg.graph, pg.initial, opt);
  CHECK(res.termination == Termination::JacobianCheckFailed);
  CHECK(res.message.find("x3") != std::string::npos);
}

TEST_CASE("check_jacobians checks the path the solver takes, a factor's fast path included") {
  PoseGraph pg = makePoseGraph(6, 3, 5);
  OptimizerOptions opt;
  opt.check_jacobians = true;
  pg.graph.emplace<test::SloppyPrior>(key('x', 2), pg.initial.at<SE3>(key('x', 2)).plus(Vec6::Constant(0.2)),
                                      NoiseModel::isotropic(6, 0.1));
  const OptimizerResult res = optimize(pg.graph, pg.initial, opt);
  CHECK(res.termination == Termination::JacobianCheckFailed);
  CHECK(res.message.find("fast path") != std::string::npos);
  CHECK(res.message.find("x2") != std::string::npos);
}

TEST_CASE("fixed variables stay where they are") {
  const PoseGraph pg = makePoseGraph(8, 4, 9);
  OptimizerOptions opt;
  opt.fixed_keys = {key('x', 5)};
  const OptimizerResult res = optimize(pg.graph, pg.initial, opt);
  REQUIRE(res.converged);
  CHECK(res.values.at<SE3>(key('x', 5)).matrix() == pg.initial.at<SE3>(key('x', 5)).matrix());
  CHECK(res.values.at<SE3>(key('x', 4)).minus(pg.initial.at<SE3>(key('x', 4))).norm() > 1e-6);
}

TEST_CASE("options the damping cannot use are refused with the field named") {
  FactorGraph g;
  Values v;
  v.insert(key('x', 0), SE3());
  g.emplace<PriorFactorSE3>(key('x', 0), SE3::exp(Vec6::Constant(0.1)), NoiseModel::isotropic(6, 0.1));
  for (auto solver : {OptimizerOptions::LinearSolver::Auto, OptimizerOptions::LinearSolver::SparseCholesky}) {
    OptimizerOptions o;
    o.linear_solver = solver;
    o.min_diagonal = 2.0;
    o.max_diagonal = 1.0;
    CHECK_THROWS_WITH(optimize(g, v, o), Catch::Contains("min_diagonal"));
    o.min_diagonal = -1.0;
    o.max_diagonal = 1.0;
    CHECK_THROWS_WITH(optimize(g, v, o), Catch::Contains("min_diagonal"));
    o = OptimizerOptions{};
    o.linear_solver = solver;
    for (double bad : {-1.0, 0.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
      o.initial_lambda = bad;
      CHECK_THROWS_WITH(optimize(g, v, o), Catch::Contains("initial_lambda"));
    }
    o.algorithm = OptimizerOptions::Algorithm::GaussNewton;  // no damping: lambda unused
    CHECK(optimize(g, v, o).converged);
    o.algorithm = OptimizerOptions::Algorithm::LevenbergMarquardt;
    o.initial_lambda = 1e-3;
    CHECK(optimize(g, v, o).converged);
  }
}
