#ifdef FGCAL_HAVE_CERES

#include "ceres_problem.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::bench {

namespace {

using RowJ7 = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;

// r = W Log(Z^-1 X), as PriorFactorSE3 then the noise model compute it.
class PriorCost final : public ceres::SizedCostFunction<6, 7> {
 public:
  PriorCost(const SE3& measured, const Mat6& W) : measured_inverse_(measured.inverse()), W_(W) {}
  bool Evaluate(double const* const* x, double* residual, double** jacobians) const override {
    const SE3 X = paramsToPose(x[0]);
    const SE3 E = measured_inverse_.compose(X);
    const bool need = jacobians && jacobians[0];
    Mat6 J;
    const Vec6 r = E.log(need ? &J : nullptr);
    Vec6::Map(residual) = W_ * r;
    if (need) {
      Eigen::Map<RowJ7> out(jacobians[0]);
      out.leftCols<6>() = W_ * J;
      out.col(6).setZero();
    }
    return true;
  }

 private:
  SE3 measured_inverse_;
  Mat6 W_;
};

// r = W Log(Z^-1 A^-1 B), as RelativePoseFactor then the noise model compute it.
class RelativePoseCost final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  RelativePoseCost(const SE3& measured, const Mat6& W) : measured_inverse_(measured.inverse()), W_(W) {}
  bool Evaluate(double const* const* x, double* residual, double** jacobians) const override {
    const SE3 A = paramsToPose(x[0]), B = paramsToPose(x[1]);
    const SE3 D = A.between(B);
    const SE3 E = measured_inverse_.compose(D);
    const bool need_a = jacobians && jacobians[0], need_b = jacobians && jacobians[1];
    Mat6 Jlog;
    const Vec6 r = E.log(need_a || need_b ? &Jlog : nullptr);
    Vec6::Map(residual) = W_ * r;
    if (need_a) {
      Eigen::Map<RowJ7> out(jacobians[0]);
      out.leftCols<6>() = -W_ * Jlog * D.inverse().adjoint();
      out.col(6).setZero();
    }
    if (need_b) {
      Eigen::Map<RowJ7> out(jacobians[1]);
      out.leftCols<6>() = W_ * Jlog;
      out.col(6).setZero();
    }
    return true;
  }

 private:
  SE3 measured_inverse_;
  Mat6 W_;
};

}  // namespace

void poseToParams(const SE3& T, double* x) {
  Eigen::Quaterniond q(T.rotation());
  q.normalize();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  x[4] = T.translation().x();
  x[5] = T.translation().y();
  x[6] = T.translation().z();
}

SE3 paramsToPose(const double* x) {
  const Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
  return SE3(SO3(q), Vec3(x[4], x[5], x[6]));
}

bool SE3Manifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  poseToParams(paramsToPose(x).plus(Eigen::Map<const Vec6>(delta)), x_plus_delta);
  return true;
}

bool SE3Manifold::PlusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<6>().setIdentity();
  return true;
}

bool SE3Manifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Vec6::Map(y_minus_x) = paramsToPose(x).minus(paramsToPose(y));
  return true;
}

bool SE3Manifold::MinusJacobian(const double*, double* jacobian) const {
  Eigen::Map<RowJ7> J(jacobian);
  J.setZero();
  J.leftCols<6>().setIdentity();
  return true;
}

void buildCeresProblem(const CalibrationProblem& p, CeresCalibrationProblem& out) {
  out.params.assign(7 * static_cast<std::size_t>(p.cameras + p.frames), 0.0);
  for (int i = 0; i < p.cameras; ++i) poseToParams(p.initial_cameras[static_cast<std::size_t>(i)], out.camera(i));
  for (int j = 0; j < p.frames; ++j)
    poseToParams(p.initial_boards[static_cast<std::size_t>(j)], out.board(j, p.cameras));

  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  out.problem = std::make_unique<ceres::Problem>(po);
  ceres::Problem& problem = *out.problem;
  for (int i = 0; i < p.cameras; ++i) problem.AddParameterBlock(out.camera(i), 7, &out.manifold);
  for (int j = 0; j < p.frames; ++j) problem.AddParameterBlock(out.board(j, p.cameras), 7, &out.manifold);
  std::size_t o = 0;
  for (int j = 0; j < p.frames; ++j) {
    const PoseMeasurement& prior = p.board_priors[static_cast<std::size_t>(j)];
    double* board = out.board(j, p.cameras);
    problem.AddResidualBlock(new PriorCost(prior.measured, prior.sqrt_information), nullptr, board);
    for (; o < p.observations.size() && p.observations[o].frame == j; ++o) {
      const Observation& ob = p.observations[o];
      problem.AddResidualBlock(new RelativePoseCost(ob.z.measured, ob.z.sqrt_information), nullptr,
                               out.camera(ob.camera), board);
    }
  }
}

EvaluationMismatch compareWithFgcal(const CalibrationProblem& p, std::size_t max_factors) {
  FactorGraph graph;
  Values values;
  buildFgcalProblem(p, graph, values);
  CeresCalibrationProblem cp;
  buildCeresProblem(p, cp);
  std::vector<ceres::ResidualBlockId> blocks;
  cp.problem->GetResidualBlocks(&blocks);
  EvaluationMismatch worst;
  const std::size_t n = std::min<std::size_t>({max_factors, graph.size(), blocks.size()});
  for (std::size_t f = 0; f < n; ++f) {
    const Factor& factor = graph[f];
    std::vector<MatX> J;
    VecX r = factor.noiseModel().whiten(factor.error(values, &J));
    for (MatX& Jk : J) Jk = factor.noiseModel().sqrtInformation() * Jk;

    const ceres::CostFunction* cost = cp.problem->GetCostFunctionForResidualBlock(blocks[f]);
    std::vector<double*> params;
    cp.problem->GetParameterBlocksForResidualBlock(blocks[f], &params);
    Vec6 rc;
    std::vector<RowJ7> Jc(params.size());
    std::vector<double*> jac;
    for (auto& Jk : Jc) jac.push_back(Jk.data());
    cost->Evaluate(params.data(), rc.data(), jac.data());
    worst.residual = std::max(worst.residual, (rc - r).cwiseAbs().maxCoeff() / std::max(1.0, r.cwiseAbs().maxCoeff()));
    for (std::size_t k = 0; k < params.size(); ++k) {
      const MatX Jt = Jc[k].leftCols<6>();
      worst.jacobian =
          std::max(worst.jacobian, (Jt - J[k]).cwiseAbs().maxCoeff() / std::max(1.0, J[k].cwiseAbs().maxCoeff()));
    }
  }
  return worst;
}

}  // namespace fgcal::bench

#endif  // FGCAL_HAVE_CERES
