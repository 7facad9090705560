// The cameras' and the mount's marginal covariances with the board poses
// eliminated one by one (Marginals::reducedCovariances) against the whole
// system's Marginals, which factorizes it: a calibration-shaped graph at
// a point that is not its optimum (non-zero residuals), the mount estimated
// and held fixed; and the preconditions it checks.
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/core/marginals.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

using namespace fgcal;

namespace {

constexpr Key kMount = key('m', 0);

SE3 randomPose(std::mt19937& gen, double rot, double trans) {
  std::normal_distribution<double> n;
  return SE3(SO3::exp(rot * Vec3(n(gen), n(gen), n(gen))), trans * Vec3(n(gen), n(gen), n(gen)));
}

/// A full (non-diagonal) covariance around `sigma`.
Mat6 randomCovariance(std::mt19937& gen, double sigma) {
  std::normal_distribution<double> n;
  Mat6 A;
  for (int i = 0; i < 36; ++i) A.data()[i] = n(gen);
  return sigma * sigma * (A * A.transpose() / 6.0 + Mat6::Identity());
}

struct CalibrationGraph {
  FactorGraph graph;
  Values values;
};

/// Two cameras, the mount with its prior, `boards` board poses each with its
/// kinematic factor and the fiducial factors of the cameras that saw it,
/// built as solveCalibration builds its graph; the values off the optimum.
CalibrationGraph makeGraph(unsigned seed, int boards) {
  std::mt19937 gen(seed);
  std::uniform_int_distribution<int> seen(0, 2);  // cam0, cam1, both
  CalibrationGraph g;
  for (int c = 0; c < 2; ++c) g.values.insert(key('c', c), randomPose(gen, 0.5, 0.5));
  g.values.insert(kMount, randomPose(gen, 0.2, 0.05));
  g.graph.emplace<PriorFactorSE3>(kMount, randomPose(gen, 0.2, 0.05), NoiseModel::fromCovariance(randomCovariance(gen, 0.01)));
  for (int j = 0; j < boards; ++j) {
    const Key b = key('b', j);
    g.values.insert(b, randomPose(gen, 1.0, 1.0));
    g.graph.emplace<KinematicFactor>(b, kMount, randomPose(gen, 1.0, 1.0),
                                     NoiseModel::fromCovariance(randomCovariance(gen, 0.003)));
    const int s = seen(gen);
    for (int c = 0; c < 2; ++c)
      if (s == 2 || s == c)
        g.graph.emplace<RelativePoseFactor>(key('c', c), b, randomPose(gen, 1.0, 1.0),
                                            NoiseModel::fromCovariance(randomCovariance(gen, 0.002)));
  }
  return g;
}

void checkClose(const MatX& a, const MatX& b) {
  INFO("reduced\n" << a << "\nfull\n" << b);
  REQUIRE(a.rows() == b.rows());
  REQUIRE(a.cols() == b.cols());
  CHECK((a - b).norm() <= 1e-9 * b.norm());
}

}  // namespace

TEST_CASE("reduced marginals equal the whole system's, mount estimated or fixed") {
  for (unsigned seed : {1u, 2u, 3u}) {
    INFO("seed " << seed);
    const CalibrationGraph g = makeGraph(seed, 60);
    const std::vector<Key> cams{key('c', 0), key('c', 1)};
    {
      const Marginals full(g.graph, g.values);
      const auto reduced = Marginals::reducedCovariances(g.graph, g.values, {cams[0], cams[1], kMount}, {});
      REQUIRE(reduced.size() == 3);
      checkClose(reduced[0], full.covariance(cams[0]));
      checkClose(reduced[1], full.covariance(cams[1]));
      checkClose(reduced[2], full.covariance(kMount));
    }
    {
      const Marginals full(g.graph, g.values, {kMount});
      const auto reduced = Marginals::reducedCovariances(g.graph, g.values, cams, {kMount});
      REQUIRE(reduced.size() == 2);
      checkClose(reduced[0], full.covariance(cams[0]));
      checkClose(reduced[1], full.covariance(cams[1]));
    }
  }
}

TEST_CASE("reduced marginals: what they cannot do is said, never computed wrong") {
  CalibrationGraph g = makeGraph(4, 10);
  const std::vector<Key> cams{key('c', 0), key('c', 1)};
  SECTION("a factor between two eliminated variables") {
    g.graph.emplace<RelativePoseFactor>(key('b', 0), key('b', 1), SE3(), NoiseModel::isotropic(6, 0.01));
    CHECK_THROWS_AS(Marginals::reducedCovariances(g.graph, g.values, cams, {kMount}), std::logic_error);
  }
  SECTION("an eliminated variable's factors not together") {
    g.graph.emplace<RelativePoseFactor>(key('c', 0), key('b', 0), SE3(), NoiseModel::isotropic(6, 0.01));
    CHECK_THROWS_AS(Marginals::reducedCovariances(g.graph, g.values, cams, {kMount}), std::logic_error);
  }
  SECTION("a robust kernel") {
    g.graph.emplace<PriorFactorSE3>(kMount, SE3(), NoiseModel::isotropic(6, 0.01), huber(1.0));
    CHECK_THROWS_AS(Marginals::reducedCovariances(g.graph, g.values, cams, {}), std::logic_error);
  }
  SECTION("a camera no factor constrains") {
    g.values.insert(key('c', 2), SE3());
    CHECK_THROWS_AS(Marginals::reducedCovariances(g.graph, g.values, {cams[0], cams[1], key('c', 2)}, {kMount}),
                    DegenerateSystem);
  }
}
