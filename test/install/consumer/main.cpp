// A project embedding fgcal's solver with a factor of its own: locate a 3-D
// point from noisy ranges to known anchors. Uses only the installed fgcal::core.
#include <cmath>
#include <cstdio>
#include <random>

#include <fgcal/core/factor_graph.hpp>
#include <fgcal/core/marginals.hpp>
#include <fgcal/core/optimizer.hpp>

// r = |p - anchor| - range, one residual; its Jacobian d r / d p is the unit
// vector from the anchor to p.
class RangeFactor final : public fgcal::TypedFactor<1, Eigen::Vector3d> {
 public:
  RangeFactor(fgcal::Key k, Eigen::Vector3d anchor, double range, double sigma)
      : TypedFactor({k}, fgcal::NoiseModel::isotropic(1, sigma)), anchor_(anchor), range_(range) {}
  Residual evaluateTyped(const Eigen::Vector3d& p, Jacobian<Eigen::Vector3d>* J_r_p) const override {
    const Eigen::Vector3d d = p - anchor_;
    if (J_r_p) *J_r_p = d.normalized().transpose();
    return Residual(d.norm() - range_);
  }

 private:
  Eigen::Vector3d anchor_;
  double range_;
};

int main() {
  const Eigen::Vector3d truth(1.0, 2.0, 0.5);
  std::mt19937 gen(1);
  std::normal_distribution<double> noise(0.0, 0.01);
  fgcal::FactorGraph graph;
  const fgcal::Key p = fgcal::key('p', 0);
  for (const Eigen::Vector3d a : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(0, 5, 0),
                                  Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(5, 5, 5)})
    graph.emplace<RangeFactor>(p, a, (truth - a).norm() + noise(gen), 0.01);
  fgcal::Values init;
  init.insert(p, Eigen::Vector3d(0.5, 0.5, 0.5));

  fgcal::OptimizerOptions options;  // Levenberg-Marquardt by default
  options.check_jacobians = true;   // RangeFactor's Jacobian against central differences, once
  const fgcal::OptimizerResult res = fgcal::optimize(graph, init, options);
  const Eigen::Vector3d est = res.values.at<Eigen::Vector3d>(p);
  const Eigen::Matrix3d cov = fgcal::Marginals(graph, res.values).covariance(p);
  std::printf("%s after %d iterations: error %.4f m, sigma x %.4f m\n", res.converged ? "converged" : "FAILED",
              res.iterations, (est - truth).norm(), std::sqrt(cov(0, 0)));
  return res.converged && (est - truth).norm() < 0.05 ? 0 : 1;
}
