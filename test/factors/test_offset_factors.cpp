// The factors that re-evaluate the kinematics: joint zero offsets (FK at
// q + o) and camera time offsets (the board at the image's exposure). Their
// Jacobians against central differences, including d/d delta and d/d o, at
// non-zero residuals; their residuals against the truth they model; and a
// small graph that recovers a known time offset and joint offset exactly.
#include <cmath>
#include <memory>
#include <random>

#include "fgcal/core/marginals.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/factors/joint_offset_factor.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"
#include "fgcal/factors/time_offset_factor.hpp"
#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;

namespace {

std::shared_ptr<const kinematics::KinematicChain> leg() {
  static const auto chain = std::make_shared<const kinematics::KinematicChain>(
      kinematics::loadDefaultRobot().chain("base_link", "lf_foot"));
  return chain;
}

/// q_i(t) = a_i + b_i sin(w_i t + p_i): smooth, with a closed-form derivative.
class SineTrajectory final : public JointTrajectory {
 public:
  explicit SineTrajectory(int n) : a_(n), b_(n), w_(n), p_(n) {
    for (int i = 0; i < n; ++i) {
      a_[i] = 0.3 - 0.4 * i;
      b_[i] = 0.4 + 0.1 * i;
      w_[i] = 2.0 + 1.3 * i;
      p_[i] = 0.7 * i;
    }
  }
  int numJoints() const override { return static_cast<int>(a_.size()); }
  void evaluate(double t, VecX* q, VecX* q_dot) const override {
    *q = a_.array() + b_.array() * (w_.array() * t + p_.array()).sin();
    if (q_dot) *q_dot = b_.array() * w_.array() * (w_.array() * t + p_.array()).cos();
  }

 private:
  VecX a_, b_, w_, p_;
};

constexpr Key kCam = key('c', 0), kBoard = key('b', 0), kMount = key('m', 0), kDelta = key('d', 0),
              kOffsets = key('o', 0);

VecX scalar(double v) { return VecX::Constant(1, v); }

}  // namespace

TEST_CASE("joint-offset kinematic factor: Jacobians, including d/do, match central differences") {
  const auto chain = leg();
  const auto pts = fgcal::test::se3TestPoints(51);
  std::mt19937 gen(3);
  std::normal_distribution<double> n(0.0, 0.3);
  int checked = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    VecX q(3), o(3);
    for (int k = 0; k < 3; ++k) q[k] = n(gen), o[k] = 0.05 * n(gen);
    Values v;
    v.insert(kBoard, pts[i]);
    v.insert(kMount, pts[(i + 3) % pts.size()]);
    v.insert(kOffsets, o);
    JointOffsetKinematicFactor f(kBoard, kMount, kOffsets, chain, q, NoiseModel::isotropic(6, 0.01));
    if (f.error(v).head<3>().norm() > M_PI - 1e-3) continue;  // Log is not differentiable there
    const auto bad = checkFactorJacobians(f, v);
    INFO((bad.empty() ? "" : bad[0].message));
    CHECK(bad.empty());
    ++checked;
  }
  CHECK(checked >= 10);
}

TEST_CASE("joint-offset kinematic factor is the kinematic factor at q + o") {
  const auto chain = leg();
  const VecX q = (VecX(3) << 0.2, 0.7, -1.4).finished();
  const VecX o = (VecX(3) << 0.01, -0.02, 0.005).finished();
  const SE3 mount(SO3::exp(Vec3(0.1, 0.2, -0.3)), Vec3(0.01, 0.0, 0.03));
  const SE3 board = chain->forward(q + o) * mount;
  Values v;
  v.insert(kBoard, board);
  v.insert(kMount, mount);
  v.insert(kOffsets, o);
  JointOffsetKinematicFactor f(kBoard, kMount, kOffsets, chain, q, NoiseModel::isotropic(6, 0.01));
  CHECK(f.error(v).norm() < 1e-12);
  // Away from the truth: the same residual as KinematicFactor at FK(q + o).
  const SE3 moved = board.plus((Vec6() << 0.01, -0.02, 0.03, 0.004, 0.001, -0.002).finished());
  v.insertOrAssign(kBoard, moved);
  const KinematicFactor k(kBoard, kMount, chain->forward(q + o), NoiseModel::isotropic(6, 0.01));
  CHECK((f.error(v) - k.error(v)).norm() < 1e-12);
  CHECK(f.error(v).norm() > 0.01);
  CHECK_THROWS_AS(JointOffsetKinematicFactor(kBoard, kMount, kOffsets, chain, VecX::Zero(2),
                                             NoiseModel::isotropic(6, 0.01)),
                  std::invalid_argument);
}

TEST_CASE("time-offset factor: Jacobians, including d/d delta and d/do, match central differences") {
  const auto chain = leg();
  const auto traj = std::make_shared<const SineTrajectory>(3);
  const auto pts = fgcal::test::se3TestPoints(61);
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  int checked = 0;
  for (bool with_offsets : {false, true})
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const SE3 X = pts[i], L = pts[(i + 4) % pts.size()], M = pts[(i + 7) % pts.size()];
      const SE3 Z = pts[(i + 9) % pts.size()];
      Values v;
      v.insert(kCam, X);
      v.insert(kBoard, L);
      v.insert(kMount, M);
      v.insert(kDelta, scalar(u(gen)));
      if (with_offsets) v.insert(kOffsets, (VecX(3) << u(gen), u(gen), u(gen)).finished());
      const auto pnp = std::make_shared<RelativePoseFactor>(kCam, kBoard, Z, NoiseModel::isotropic(6, 0.01));
      const TimeOffsetFactor f(pnp, 1, kMount, kDelta, with_offsets ? std::optional<Key>(kOffsets) : std::nullopt,
                               chain, traj, {0.3 + 0.1 * i, 0.3 + 0.1 * i + 2e-4}, huber(2.0));
      if (f.error(v).head<3>().norm() > M_PI - 1e-3) continue;
      const auto bad = checkFactorJacobians(f, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
      ++checked;
    }
  CHECK(checked >= 20);
}

TEST_CASE("time-offset factor hands the wrapped factor the board at the exposure") {
  const auto chain = leg();
  const auto traj = std::make_shared<const SineTrajectory>(3);
  const SE3 M(SO3::exp(Vec3(0.3, -0.1, 0.2)), Vec3(0.02, -0.01, 0.04));
  const VecX o = (VecX(3) << 0.004, -0.01, 0.007).finished();
  const double t_j = 1.25, t_i = 1.2502, delta = 0.015;
  auto fk = [&](double t) {
    VecX q;
    traj->evaluate(t, &q, nullptr);
    return chain->forward(q + o) * M;
  };
  const SE3 L = fk(t_j);  // the board at the instant's stamp
  const auto pnp = std::make_shared<RelativePoseFactor>(kCam, kBoard, SE3(), NoiseModel::isotropic(6, 0.01));
  const TimeOffsetFactor f(pnp, 1, kMount, kDelta, kOffsets, chain, traj, {t_j, t_i});
  // Exact, not first order: the board at t_i + delta from the kinematics.
  const SE3 truth = fk(t_i + delta);
  CHECK(f.boardAtExposure(L, M, delta, o).minus(truth).norm() < 1e-12);
  // It moved: a first-order model from the instant would be wrong by more.
  CHECK(L.minus(truth).norm() > 1e-3);
  // Seen from a camera at truth * Z^-1, the residual vanishes.
  const SE3 Z(SO3::exp(Vec3(0.2, 2.5, 0.1)), Vec3(0.05, -0.1, 0.6));
  Values v;
  v.insert(kCam, truth * Z.inverse());
  v.insert(kBoard, L);
  v.insert(kMount, M);
  v.insert(kDelta, scalar(delta));
  v.insert(kOffsets, o);
  const TimeOffsetFactor g(std::make_shared<RelativePoseFactor>(kCam, kBoard, Z, NoiseModel::isotropic(6, 0.01)), 1,
                           kMount, kDelta, kOffsets, chain, traj, {t_j, t_i});
  CHECK(g.error(v).norm() < 1e-9);
  // At the instant's own stamp with no offset, P = L: the wrapped factor's residual.
  const TimeOffsetFactor h(std::make_shared<RelativePoseFactor>(kCam, kBoard, Z, NoiseModel::isotropic(6, 0.01)), 1,
                           kMount, kDelta, kOffsets, chain, traj, {t_j, t_j});
  v.insertOrAssign(kDelta, scalar(0.0));
  const RelativePoseFactor plain(kCam, kBoard, Z, NoiseModel::isotropic(6, 0.01));
  CHECK((h.error(v) - plain.error(v)).norm() < 1e-12);
}

TEST_CASE("rolling-shutter time-offset factor: Jacobians in the readout and the time offset match central differences") {
  // Every combination of variables and constants: a readout alone (a global
  // time offset known), both, and both with joint offsets, at rows across the
  // image.
  const auto chain = leg();
  const auto traj = std::make_shared<const SineTrajectory>(3);
  const auto pts = fgcal::test::se3TestPoints(41);
  constexpr Key kReadout = key('r', 0);
  std::mt19937 gen(12);
  std::uniform_real_distribution<double> u(-0.05, 0.05), row(0.0, 1.0);
  int checked = 0;
  for (int mode = 0; mode < 3; ++mode)
    for (std::size_t i = 0; i < pts.size(); ++i) {
      Values v;
      v.insert(kCam, pts[i]);
      v.insert(kBoard, pts[(i + 4) % pts.size()]);
      v.insert(kMount, pts[(i + 7) % pts.size()]);
      v.insert(kReadout, scalar(0.03 + u(gen)));
      TimeOffsetFactor::Variables vars{kMount, std::nullopt, kReadout, std::nullopt};
      if (mode >= 1) vars.time_offset = kDelta, v.insert(kDelta, scalar(u(gen)));
      if (mode == 2) vars.joint_offsets = kOffsets, v.insert(kOffsets, (VecX(3) << u(gen), u(gen), u(gen)).finished());
      TimeOffsetFactor::Timing timing{0.3 + 0.1 * i, 0.3 + 0.1 * i + 2e-4, row(gen), 0.004, 0.0};
      const auto pnp = std::make_shared<RelativePoseFactor>(kCam, kBoard, pts[(i + 9) % pts.size()],
                                                            NoiseModel::isotropic(6, 0.01));
      const TimeOffsetFactor f(pnp, 1, vars, chain, traj, timing, huber(2.0));
      CHECK(f.keys().size() == 3u + (mode >= 1 ? 1u : 0u) + (mode == 2 ? 1u : 0u) + 1u);
      if (f.error(v).head<3>().norm() > M_PI - 1e-3) continue;
      const auto bad = checkFactorJacobians(f, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
      ++checked;
    }
  CHECK(checked >= 20);
}

TEST_CASE("rolling-shutter time-offset factor sees its row at stamp + offset + row x readout") {
  const auto chain = leg();
  const auto traj = std::make_shared<const SineTrajectory>(3);
  const SE3 M(SO3::exp(Vec3(0.3, -0.1, 0.2)), Vec3(0.02, -0.01, 0.04));
  const double t_j = 1.25, t_i = 1.2502, delta = 0.006, readout = 0.03, r = 0.75;
  auto fk = [&](double t) {
    VecX q;
    traj->evaluate(t, &q, nullptr);
    return chain->forward(q) * M;
  };
  const SE3 L = fk(t_j);
  const SE3 Z(SO3::exp(Vec3(0.2, 2.5, 0.1)), Vec3(0.05, -0.1, 0.6));
  const SE3 truth = fk(t_i + delta + r * readout);
  constexpr Key kReadout = key('r', 0);
  Values v;
  v.insert(kCam, truth * Z.inverse());
  v.insert(kBoard, L);
  v.insert(kMount, M);
  v.insert(kDelta, scalar(delta));
  v.insert(kReadout, scalar(readout));
  auto pnp = [&] { return std::make_shared<RelativePoseFactor>(kCam, kBoard, Z, NoiseModel::isotropic(6, 0.01)); };
  // Both estimated, the readout a constant, the time offset a constant: one board.
  const TimeOffsetFactor both(pnp(), 1, {kMount, kDelta, kReadout, std::nullopt}, chain, traj, {t_j, t_i, r});
  const TimeOffsetFactor known_readout(pnp(), 1, {kMount, kDelta, std::nullopt, std::nullopt}, chain, traj,
                                       {t_j, t_i, r, 0.0, readout});
  const TimeOffsetFactor known_offset(pnp(), 1, {kMount, std::nullopt, kReadout, std::nullopt}, chain, traj,
                                      {t_j, t_i, r, delta, 0.0});
  CHECK(both.error(v).norm() < 1e-9);
  CHECK(known_readout.error(v).norm() < 1e-9);
  CHECK(known_offset.error(v).norm() < 1e-9);
  CHECK(both.boardAtExposure(L, M, delta, readout, VecX()).minus(truth).norm() < 1e-12);
  // The first row is at the offset alone; the readout moved this one.
  const TimeOffsetFactor first_row(pnp(), 1, {kMount, kDelta, kReadout, std::nullopt}, chain, traj, {t_j, t_i, 0.0});
  CHECK(first_row.error(v).norm() > 1e-2);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp(), 1, {kMount, kDelta, kReadout, std::nullopt}, chain, traj, {t_j, t_i, 1.5}),
                  std::invalid_argument);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp(), 1, {kMount, kDelta, kDelta, std::nullopt}, chain, traj, {t_j, t_i, 0.5}),
                  std::invalid_argument);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp(), 1, {kMount, kDelta, std::nullopt, std::nullopt}, chain, traj,
                                   {t_j, t_i, 0.5, 0.0, std::nan("")}),
                  std::invalid_argument);
}

TEST_CASE("time-offset factor refuses what it cannot evaluate") {
  const auto chain = leg();
  const auto pnp = std::make_shared<RelativePoseFactor>(kCam, kBoard, SE3(), NoiseModel::isotropic(6, 0.01));
  const auto traj3 = std::make_shared<const SineTrajectory>(3);
  const auto traj2 = std::make_shared<const SineTrajectory>(2);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp, 1, kMount, kDelta, std::nullopt, chain, traj2, {0, 0}), std::invalid_argument);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp, 2, kMount, kDelta, std::nullopt, chain, traj3, {0, 0}), std::invalid_argument);
  CHECK_THROWS_AS(TimeOffsetFactor(pnp, 1, kCam, kDelta, std::nullopt, chain, traj3, {0, 0}), std::invalid_argument);
  CHECK_THROWS_AS(TimeOffsetFactor(nullptr, 0, kMount, kDelta, std::nullopt, chain, traj3, {0, 0}),
                  std::invalid_argument);
}

TEST_CASE("a graph of time-offset and joint-offset factors recovers a known delay and joint offset") {
  // A camera sees the board at t + 15 ms while the joint log is stamped at t;
  // the middle joint's encoder reads 0.01 rad less than the joint stands. The
  // cameras, the board poses, the mount, delta and o are all estimated.
  const auto chain = leg();
  const auto traj = std::make_shared<const SineTrajectory>(3);
  const double delta_true = 0.015;
  const VecX o_true = (VecX(3) << 0.0, 0.01, 0.0).finished();
  const SE3 M_true(SO3::exp(Vec3(0.1, 1.4, 0.0)), Vec3(0.0, 0.0, -0.02));
  const SE3 X_true[2] = {SE3(SO3::exp(Vec3(-1.6, 0.0, -1.6)), Vec3(1.1, 0.25, 0.0)),
                         SE3(SO3::exp(Vec3(-1.5, 0.1, -1.7)), Vec3(1.0, 0.05, 0.1))};
  auto q_at = [&](double t) {
    VecX q;
    traj->evaluate(t, &q, nullptr);
    return q;
  };
  FactorGraph graph;
  Values init;
  for (int c = 0; c < 2; ++c) init.insert(key('c', c), X_true[c].plus(Vec6::Constant(0.01)));
  init.insert(kMount, M_true.plus(Vec6::Constant(0.005)));
  init.insert(kDelta, scalar(0.0));
  init.insert(kOffsets, VecX::Zero(3));
  graph.emplace<PriorFactorSE3>(kMount, M_true, NoiseModel::isotropic(6, 0.05));
  // Wide priors (their pull on exact data is what is not tested here); they
  // hold the base- and board-side offsets, which these data cannot tell from
  // the cameras and the mount, at zero.
  graph.emplace<PriorFactorVector>(kDelta, scalar(0.0), NoiseModel::isotropic(1, 10.0));
  graph.emplace<PriorFactorVector>(kOffsets, VecX::Zero(3), NoiseModel::isotropic(3, 10.0));
  const auto noise = NoiseModel::isotropic(6, 1e-3);
  for (int j = 0; j < 150; ++j) {
    const double t = 0.05 * j;
    const VecX q_read = q_at(t) - o_true;  // what the encoders log
    const Key b = key('b', j);
    init.insert(b, chain->forward(q_read) * M_true);
    graph.emplace<JointOffsetKinematicFactor>(b, kMount, kOffsets, chain, q_read, noise);
    for (int c = 0; c < 2; ++c) {
      // Camera 0 is on time; camera 1 exposes 15 ms after its stamp.
      const double delay = c == 0 ? 0.0 : delta_true;
      const SE3 seen = chain->forward(q_at(t + delay)) * M_true;
      const auto pnp = std::make_shared<RelativePoseFactor>(key('c', c), b, X_true[c].inverse() * seen, noise);
      if (c == 0) {
        graph.add(pnp);
      } else {
        // The factor reads the joint log (q - o_true, as logged), like the kinematic factors.
        struct Logged final : JointTrajectory {
          std::shared_ptr<const SineTrajectory> truth;
          VecX o;
          int numJoints() const override { return 3; }
          void evaluate(double t, VecX* q, VecX* q_dot) const override {
            truth->evaluate(t, q, q_dot);
            *q -= o;
          }
        };
        auto logged = std::make_shared<Logged>();
        logged->truth = traj;
        logged->o = o_true;
        graph.emplace<TimeOffsetFactor>(pnp, 1, kMount, kDelta, kOffsets, chain, logged,
                                        TimeOffsetFactor::Timing{t, t});
      }
    }
  }
  const OptimizerResult r = optimize(graph, init);
  REQUIRE(r.converged);
  CHECK(r.values.at<VecX>(kDelta)[0] == Approx(delta_true).margin(1e-7));
  CHECK(r.values.at<VecX>(kOffsets)[1] == Approx(0.01).margin(1e-6));
  for (int c = 0; c < 2; ++c) CHECK(r.values.at<SE3>(key('c', c)).minus(X_true[c]).norm() < 1e-6);
}

TEST_CASE("origin-corrected kinematics: zero corrections are the URDF's chain, a correction is the URDF moved") {
  const auto model = kinematics::loadDefaultRobot();
  const auto chain = leg();
  const VecX q = (VecX(3) << 0.2, 0.7, -1.3).finished();
  const SE3 M = SE3::fromXyzRpy(Vec3(0.01, -0.02, 0.03), Vec3(0.1, -0.2, 0.3));
  CHECK(chain->forwardCorrected(q, VecX::Zero(18), M).between(chain->forward(q) * M).log().norm() < 1e-12);
  // The second joint's origin moved by u_1 is the URDF whose <origin> of that
  // joint (no fixed joint stands between it and the first joint here) is C Exp(u_1).
  Vec6 u1;
  u1 << 0.01, -0.02, 0.015, 0.002, -0.001, 0.003;
  VecX u = VecX::Zero(18);
  u.segment<6>(6) = u1;
  std::vector<kinematics::PathStep> path;
  for (const std::string& name : chain->jointNames()) path.push_back({model.joint(name), false});
  path[1].joint.T_parent_joint = path[1].joint.T_parent_joint * SE3::exp(u1);
  // The foot's fixed joint closes the chain.
  for (const auto& j : model.joints())
    if (j.child_link == "lf_foot") path.push_back({j, false});
  const kinematics::KinematicChain moved("base_link", "lf_foot", path);
  CHECK(chain->forwardCorrected(q, u, M).between(moved.forward(q) * M).log().norm() < 1e-12);
  CHECK_THROWS_AS(chain->forwardCorrected(q, VecX::Zero(17), M), kinematics::KinematicsError);
}

TEST_CASE("a link made longer: the correction along originTranslation is the URDF with that origin's translation scaled") {
  const auto model = kinematics::loadDefaultRobot();
  const auto chain = leg();
  const VecX q = (VecX(3) << 0.2, 0.7, -1.3).finished();
  const SE3 M = SE3::fromXyzRpy(Vec3(0.01, -0.02, 0.03), Vec3(0.1, -0.2, 0.3));
  for (int i = 0; i < 3; ++i) {
    const double k = 1.03;
    VecX u = VecX::Zero(18);
    u.segment<3>(6 * i + 3) = (k - 1.0) * chain->originTranslation(i);
    std::vector<kinematics::PathStep> path;
    for (const std::string& name : chain->jointNames()) path.push_back({model.joint(name), false});
    SE3& O = path[static_cast<std::size_t>(i)].joint.T_parent_joint;
    O = SE3(O.so3(), k * O.translation());
    for (const auto& j : model.joints())
      if (j.child_link == "lf_foot") path.push_back({j, false});
    const kinematics::KinematicChain longer("base_link", "lf_foot", path);
    INFO("joint " << i);
    CHECK(chain->forwardCorrected(q, u, M).between(longer.forward(q) * M).log().norm() < 1e-12);
  }
  CHECK_THROWS_AS(chain->originTranslation(3), kinematics::KinematicsError);
  CHECK_THROWS_AS(chain->originTranslation(-1), kinematics::KinematicsError);
}

TEST_CASE("chain kinematic factor: Jacobians in every combination of origins, offsets and backlash match central differences") {
  const auto chain = leg();
  const auto pts = fgcal::test::se3TestPoints(31);
  std::mt19937 gen(5);
  std::normal_distribution<double> n(0.0, 0.3);
  constexpr Key kOrigins = key('u', 0);
  constexpr Key kBacklash = key('g', 0);
  int checked = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    VecX q(3), o(3), b(3), lag(3), u(18);
    for (int k = 0; k < 3; ++k) q[k] = n(gen), o[k] = 0.05 * n(gen), b[k] = 0.01 * n(gen), lag[k] = -0.5 * std::tanh(n(gen));
    for (int k = 0; k < 18; ++k) u[k] = 0.05 * n(gen);
    Values v;
    v.insert(kBoard, pts[i]);
    v.insert(kMount, pts[(i + 3) % pts.size()]);
    v.insert(kOrigins, u);
    v.insert(kOffsets, o);
    v.insert(kBacklash, b);
    for (int mask = 1; mask < 8; ++mask) {
      ChainCorrections c;
      if (mask & 1) c.origins = kOrigins;
      if (mask & 2) c.offsets = kOffsets;
      if (mask & 4) c.backlash = kBacklash, c.backlash_lag = lag;
      ChainKinematicFactor f(kBoard, kMount, c, chain, q, NoiseModel::isotropic(6, 0.01));
      if (f.error(v).head<3>().norm() > M_PI - 1e-3) continue;  // Log is not differentiable there
      const auto bad = checkFactorJacobians(f, v);
      INFO("mask " << mask << " " << (bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
      ++checked;
    }
  }
  CHECK(checked >= 90);  // of 7 x 31: points where Log is not differentiable are skipped
  CHECK_THROWS_AS(ChainKinematicFactor(kBoard, kMount, {kOrigins, std::nullopt, std::nullopt, VecX()}, chain,
                                       VecX::Zero(2), NoiseModel::isotropic(6, 0.01)),
                  std::invalid_argument);
  CHECK_THROWS_AS(ChainKinematicFactor(kBoard, kMount, {std::nullopt, std::nullopt, kBacklash, VecX::Zero(2)}, chain,
                                       VecX::Zero(3), NoiseModel::isotropic(6, 0.01)),
                  std::invalid_argument);
}

TEST_CASE("chain kinematic factor: backlash moves each joint by its lag times its play, as a zero offset would") {
  // A joint moving forward lags its encoder by half its play, one moving back
  // leads it, one crossing its play stands between: the factor with backlash
  // b and lag lambda is the kinematics at q + lambda b.
  const auto chain = leg();
  constexpr Key kBacklash = key('g', 0);
  const VecX q = (VecX(3) << 0.2, 0.7, -1.3).finished();
  const VecX b = (VecX(3) << 0.004, 0.003, 0.002).finished();
  const VecX lag = (VecX(3) << -0.5, 0.5, 0.2).finished();
  const SE3 M = SE3::fromXyzRpy(Vec3(0.01, -0.02, 0.03), Vec3(0.1, -0.2, 0.3));
  const SE3 L = chain->forward(q + lag.cwiseProduct(b)) * M;
  Values v;
  v.insert(kBoard, L);
  v.insert(kMount, M);
  v.insert(kBacklash, b);
  const ChainKinematicFactor f(kBoard, kMount, {std::nullopt, std::nullopt, kBacklash, lag}, chain, q,
                               NoiseModel::isotropic(6, 0.01));
  CHECK(f.error(v).norm() < 1e-12);
  v.insertOrAssign(kBacklash, VecX::Zero(3));
  CHECK(f.error(v).norm() > 1e-4);  // the encoder's reading is not where the joint stood
}
