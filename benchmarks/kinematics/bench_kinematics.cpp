// Per-call cost of forward kinematics, FK + Jacobian, and FK + Jacobian +
// covariance (J diag(sigma^2) J^T) for: our own robot's 3-joint leg, an ANYmal C
// leg (3 movable joints among 10 URDF joints), and the longest root-to-leaf
// chain of the shared URDFs (found by counting movable joints). orocos KDL
// (ChainFkSolverPos_recursive + ChainJntToJacSolver) runs the same chains when
// it is installed. The KDL covariance is accumulated column by column like ours
// so neither side allocates.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal/kinematics/robot_model.hpp"

#ifdef FGCAL_HAVE_KDL
#include <console_bridge/console.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <urdf_parser/urdf_parser.h>

#include "kdl_from_urdf.hpp"
#endif

using namespace fgcal;
using namespace fgcal::kinematics;

namespace {

struct Case {
  std::string label;
  std::string file;  // empty for the built-in robot
  KinematicChain chain;
};

// 64 joint configurations cycled through, so that no call sees the same q twice in a row.
std::vector<VecX> configurations(const KinematicChain& c) {
  std::mt19937 gen(1);
  std::vector<VecX> qs;
  for (int k = 0; k < 64; ++k) {
    VecX q(c.numJoints());
    for (int i = 0; i < q.size(); ++i) {
      const auto& l = c.joints()[static_cast<std::size_t>(i)].limits;
      const double lo = l.has_position_limits ? l.lower : -M_PI, hi = l.has_position_limits ? l.upper : M_PI;
      q[i] = std::uniform_real_distribution<double>(lo, hi)(gen);
    }
    qs.push_back(q);
  }
  return qs;
}

void fgcalFk(benchmark::State& st, const KinematicChain& c) {
  const auto qs = configurations(c);
  std::size_t k = 0;
  for (auto _ : st) {
    SE3 T = c.forward(qs[k++ & 63]);
    benchmark::DoNotOptimize(T);
  }
}

void fgcalFkJac(benchmark::State& st, const KinematicChain& c) {
  const auto qs = configurations(c);
  KinematicChain::Jacobian J(6, c.numJoints());
  std::size_t k = 0;
  for (auto _ : st) {
    SE3 T = c.forward(qs[k++ & 63], &J);
    benchmark::DoNotOptimize(T);
    benchmark::DoNotOptimize(J.data());
  }
}

void fgcalFkJacCov(benchmark::State& st, const KinematicChain& c) {
  const auto qs = configurations(c);
  const VecX sigma = c.sigmaVector(0.001);
  const SE3 T_tip_marker = SE3::fromXyzRpy(Vec3(0, 0, 0.02), Vec3(0, 0, 0.3));
  KinematicChain::Jacobian J(6, c.numJoints());
  Mat6 Sigma;
  std::size_t k = 0;
  for (auto _ : st) {
    SE3 T = c.forwardWithCovariance(qs[k++ & 63], sigma, &Sigma, T_tip_marker, &J);
    benchmark::DoNotOptimize(T);
    benchmark::DoNotOptimize(J.data());
    benchmark::DoNotOptimize(Sigma.data());
  }
}

#ifdef FGCAL_HAVE_KDL
struct KdlSetup {
  KDL::Chain chain;
  std::vector<KDL::JntArray> qs;
};

KdlSetup kdlSetup(const Case& cs) {
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_ERROR);  // undefined materials are noise here
  const auto model = cs.file.empty() ? urdf::parseURDF(defaultRobotUrdf()) : urdf::parseURDFFile(cs.file);
  KdlSetup s;
  s.chain = fgcal::test::kdlChainFromUrdf(*model, cs.chain.baseLink(), cs.chain.tipLink());
  for (const VecX& q : configurations(cs.chain)) {
    KDL::JntArray a(s.chain.getNrOfJoints());
    a.data = q;
    s.qs.push_back(a);
  }
  return s;
}

void kdlFk(benchmark::State& st, const KdlSetup& s) {
  KDL::ChainFkSolverPos_recursive fk(s.chain);
  KDL::Frame F;
  std::size_t k = 0;
  for (auto _ : st) {
    fk.JntToCart(s.qs[k++ & 63], F);
    benchmark::DoNotOptimize(F);
  }
}

void kdlFkJac(benchmark::State& st, const KdlSetup& s, bool with_covariance) {
  KDL::ChainFkSolverPos_recursive fk(s.chain);
  KDL::ChainJntToJacSolver jac(s.chain);
  KDL::Frame F;
  KDL::Jacobian J(s.chain.getNrOfJoints());
  const double var = 0.001 * 0.001;
  Mat6 Sigma;
  std::size_t k = 0;
  for (auto _ : st) {
    const KDL::JntArray& q = s.qs[k++ & 63];
    fk.JntToCart(q, F);
    jac.JntToJac(q, J);
    if (with_covariance) {
      Sigma.setZero();
      for (unsigned i = 0; i < s.chain.getNrOfJoints(); ++i) {
        const Vec6 c = J.data.col(i);
        Sigma.noalias() += (var * c) * c.transpose();
      }
      benchmark::DoNotOptimize(Sigma.data());
    }
    benchmark::DoNotOptimize(F);
    benchmark::DoNotOptimize(J.data.data());
  }
}
#endif

// The root-to-leaf chain with the most movable joints (then the most URDF
// joints) among the shared URDFs.
bool longestSharedChain(Case* out) {
  const std::filesystem::path dir = std::filesystem::path(FGCAL_SHARED_DATA_DIR) / "urdf";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return false;
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".urdf") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  bool found = false;
  for (const auto& f : files) {
    const RobotModel m = RobotModel::fromFile(f.string());
    for (const std::string& leaf : m.leafLinks()) {
      KinematicChain c = m.chain(m.rootLink(), leaf);
      if (!found || c.numJoints() > out->chain.numJoints() ||
          (c.numJoints() == out->chain.numJoints() && c.numPathJoints() > out->chain.numPathJoints())) {
        *out = Case{f.filename().string() + " " + m.rootLink() + "->" + leaf, f.string(), std::move(c)};
        found = true;
      }
    }
  }
  return found;
}

std::string shape(const KinematicChain& c) {
  return "(" + std::to_string(c.numJoints()) + " movable of " + std::to_string(c.numPathJoints()) + " joints)";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<Case> cases;
  const RobotModel robot = loadDefaultRobot();
  cases.push_back(Case{"fgcal_quadruped base_link->lf_foot", "", robot.chain("base_link", "lf_foot")});
  const std::filesystem::path anymal = std::filesystem::path(FGCAL_SHARED_DATA_DIR) / "urdf" / "anymal_c.urdf";
  if (std::filesystem::exists(anymal)) {
    cases.push_back(
        Case{"anymal_c.urdf base->LF_FOOT", anymal.string(), RobotModel::fromFile(anymal.string()).chain("base", "LF_FOOT")});
  }
  Case longest{"", "", robot.chain("base_link", "base_link")};
  if (longestSharedChain(&longest)) {
    cases.push_back(longest);
  } else {
    std::cerr << "shared URDFs not found under " << FGCAL_SHARED_DATA_DIR << "/urdf: timing the built-in robot only\n";
  }

  // Kept alive for the whole run: the registered lambdas refer to them.
  static std::vector<Case> keep;
  keep = cases;
#ifdef FGCAL_HAVE_KDL
  static std::vector<KdlSetup> kdl;
  for (const auto& cs : keep) kdl.push_back(kdlSetup(cs));
#endif
  for (std::size_t i = 0; i < keep.size(); ++i) {
    const Case& cs = keep[i];
    const std::string name = cs.label + " " + shape(cs.chain);
    benchmark::RegisterBenchmark(("fgcal FK            | " + name).c_str(), fgcalFk, std::cref(cs.chain));
    benchmark::RegisterBenchmark(("fgcal FK+J          | " + name).c_str(), fgcalFkJac, std::cref(cs.chain));
    benchmark::RegisterBenchmark(("fgcal FK+J+Sigma    | " + name).c_str(), fgcalFkJacCov, std::cref(cs.chain));
#ifdef FGCAL_HAVE_KDL
    const KdlSetup& ks = kdl[i];
    benchmark::RegisterBenchmark(("KDL   FK            | " + name).c_str(), kdlFk, std::cref(ks));
    benchmark::RegisterBenchmark(("KDL   FK+J          | " + name).c_str(), kdlFkJac, std::cref(ks), false);
    benchmark::RegisterBenchmark(("KDL   FK+J+Sigma    | " + name).c_str(), kdlFkJac, std::cref(ks), true);
#endif
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
