#include "commands/pose_graph_demo/pose_graph_demo.hpp"

#include <cstdio>
#include <random>
#include <vector>

#include "fgcal/core/marginals.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::apps {

int runPoseGraphDemo(const PoseGraphDemoOptions& o) {
  std::mt19937 gen(o.seed);
  std::normal_distribution<double> n;
  const double rot_sigma = 0.01, trans_sigma = 0.05;
  auto noisy = [&](const SE3& T) {
    Vec6 d;
    d << rot_sigma * n(gen), rot_sigma * n(gen), rot_sigma * n(gen), trans_sigma * n(gen), trans_sigma * n(gen),
        trans_sigma * n(gen);
    return T.plus(d);
  };

  // A helix of poses; odometry between neighbours, loop closures a turn apart.
  std::vector<SE3> truth;
  for (int i = 0; i < o.poses; ++i) {
    const double a = 2.0 * M_PI * i / o.poses_per_turn;
    truth.emplace_back(SO3::exp(Vec3(0.0, 0.0, a + M_PI / 2)), Vec3(5.0 * std::cos(a), 5.0 * std::sin(a), 0.02 * i));
  }
  Vec6 sig;
  sig << rot_sigma, rot_sigma, rot_sigma, trans_sigma, trans_sigma, trans_sigma;
  const auto noise = NoiseModel::diagonal(sig);
  FactorGraph graph;
  Values initial;
  graph.emplace<PriorFactorSE3>(key('x', 0), truth[0], NoiseModel::isotropic(6, 1e-4));
  SE3 chained = truth[0];
  initial.insert(key('x', 0), chained);
  for (int i = 0; i + 1 < o.poses; ++i) {
    const SE3 z = noisy(truth[i].between(truth[i + 1]));
    graph.emplace<RelativePoseFactor>(key('x', i), key('x', i + 1), z, noise);
    chained = chained * z;
    initial.insert(key('x', i + 1), chained);
  }
  int loops = 0;
  for (int i = 0; i + o.poses_per_turn < o.poses; i += 2, ++loops)
    graph.emplace<RelativePoseFactor>(key('x', i), key('x', i + o.poses_per_turn),
                                      noisy(truth[i].between(truth[i + o.poses_per_turn])), noise);

  auto rms_error = [&](const Values& v) {
    double s = 0.0;
    for (int i = 0; i < o.poses; ++i) s += (v.at<SE3>(key('x', i)).translation() - truth[i].translation()).squaredNorm();
    return std::sqrt(s / o.poses);
  };

  std::printf("fgcal core demo: SE(3) pose graph, %d poses, %d loop closures, %zu factors\n", o.poses, loops,
              graph.size());
  std::printf("noise: %.3f rad, %.3f m per relative pose; initial guess = chained odometry\n\n", rot_sigma,
              trans_sigma);
  std::printf("%5s %14s %12s %10s %10s %9s\n", "iter", "cost", "step", "lambda", "time ms", "accepted");
  OptimizerOptions opt;
  opt.callback = [](const IterationReport& r) {
    std::printf("%5d %14.6g %12.3e %10.2e %10.2f %9s\n", r.iteration, r.cost, r.step_norm, r.lambda,
                1e3 * r.total_seconds, r.accepted ? "yes" : "no");
  };
  const OptimizerResult res = optimize(graph, initial, opt);
  const Marginals marginals(graph, res.values);
  const MatX cov = marginals.covariance(key('x', o.poses - 1));

  std::printf("\n%s: %s after %d iterations, %.1f ms (linearize %.1f ms, factorize+solve %.1f ms)\n",
              res.converged ? "converged" : "NOT converged", res.message.c_str(), res.iterations,
              1e3 * res.total_seconds, 1e3 * res.linearize_seconds, 1e3 * res.solve_seconds);
  std::printf("position RMS error against the truth: initial %.3f m -> final %.3f m\n", rms_error(initial),
              rms_error(res.values));
  std::printf("last pose 1-sigma from the marginal covariance: %.3f m, %.3f deg\n",
              std::sqrt(cov.diagonal().tail<3>().maxCoeff()),
              std::sqrt(cov.diagonal().head<3>().maxCoeff()) * 180.0 / M_PI);
  return res.converged ? 0 : 1;
}

}  // namespace fgcal::apps
