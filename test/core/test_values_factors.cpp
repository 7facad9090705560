// Values, keys, and the factor interface: the SE(3) prior and relative-pose
// factors' Jacobians at points with non-zero residuals.
#include <algorithm>
#include <random>

#include "fgcal/core/factor.hpp"
#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "sloppy_prior.hpp"

using namespace fgcal;
using fgcal::test::se3TestPoints;

TEST_CASE("values hold SE3, SO3 and R^n, with clear errors") {
  Values v;
  v.insert(key('x', 1), SE3::exp((Vec6() << 0.1, 0, 0, 1, 2, 3).finished()));
  v.insert(key('r', 0), SO3::exp(Vec3(0, 0.2, 0)));
  v.insert(key('p', 0), Eigen::Vector3d(1, 2, 3));
  v.insert(key('q', 0), VecX::Ones(5));
  CHECK(v.size() == 4);
  CHECK(v.variable(key('q', 0)).dim() == 5);
  CHECK(v.at<Eigen::Vector3d>(key('p', 0)).z() == 3.0);
  // find: the dense position in insertion order, or npos without throwing.
  CHECK(v.find(key('r', 0)) == 1);
  CHECK(v.find(key('q', 0)) == v.indexOf(key('q', 0)));
  CHECK(v.find(key('x', 2)) == Values::npos);
  CHECK_THROWS_WITH(v.at<SE3>(key('x', 2)), Catch::Contains("x2"));
  CHECK_THROWS_WITH(v.at<SO3>(key('x', 1)), Catch::Contains("another type"));
  CHECK_THROWS_WITH(v.insert(key('x', 1), SE3()), Catch::Contains("already"));
  // Copies are deep.
  Values w = v;
  w.insertOrAssign(key('p', 0), Eigen::Vector3d(0, 0, 0));
  CHECK(v.at<Eigen::Vector3d>(key('p', 0)).z() == 3.0);
  // Copies share their key index until one inserts: each then sees only its own keys.
  w.insert(key('w', 0), 1.5 * Eigen::Vector3d::Ones());
  v.insert(key('v', 0), SE3());
  CHECK(w.size() == 5);
  CHECK(v.size() == 5);
  CHECK(w.find(key('w', 0)) == 4);
  CHECK(v.find(key('w', 0)) == Values::npos);
  CHECK(v.find(key('v', 0)) == 4);
  CHECK(w.find(key('v', 0)) == Values::npos);
  CHECK(v.keys().back() == key('v', 0));
  CHECK(w.keys().back() == key('w', 0));
  // The original inserting into a shared index leaves the copy as it was.
  Values u = v;
  v.insert(key('v', 1), SE3());
  CHECK(u.size() == 5);
  CHECK(u.find(key('v', 1)) == Values::npos);
  CHECK(u.keys().size() == 5);
  CHECK(v.find(key('v', 1)) == 5);
  u = u;  // self-assignment keeps everything
  CHECK(u.size() == 5);
  CHECK(u.find(key('v', 0)) == 4);
  Values moved = std::move(w), empty;
  CHECK(moved.find(key('w', 0)) == 4);
  CHECK(empty.find(key('x', 1)) == Values::npos);
  CHECK(empty.keys().empty());
  w = moved;
  // Retraction through the type-erased interface.
  const double d[5] = {1, 2, 3, 4, 5};
  w.variable(key('q', 0)).retract(d);
  CHECK(w.at<VecX>(key('q', 0))[4] == 6.0);
  CHECK(keyToString(key('b', 1234)) == "b1234");
}

TEST_CASE("prior and relative-pose factor Jacobians match central differences") {
  const auto pts = se3TestPoints(21);
  const auto noise = NoiseModel::isotropic(6, 0.1);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    Values v;
    v.insert(key('a', 0), pts[i]);
    v.insert(key('b', 0), pts[(i + 4) % pts.size()]);
    const SE3 z = pts[(i + 7) % pts.size()];  // a measurement that does not fit: non-zero residual
    PriorFactorSE3 prior(key('a', 0), z, noise);
    RelativePoseFactor rel(key('a', 0), key('b', 0), z, noise);
    // Residuals within the injectivity radius of Log, where it is differentiable.
    if (prior.error(v).head<3>().norm() < M_PI - 1e-3) {
      const auto bad = checkFactorJacobians(prior, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
    }
    if (rel.error(v).head<3>().norm() < M_PI - 1e-3) {
      const auto bad = checkFactorJacobians(rel, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
    }
  }
}

namespace {
// The relative-pose residual with the classic mistake: no Jr^-1 of Log.
class WrongRelativeFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  WrongRelativeFactor(Key a, Key b, const SE3& z) : TypedFactor({a, b}, NoiseModel::isotropic(6, 1.0)), z_(z) {}
  Residual evaluateTyped(const SE3& A, const SE3& B, Jacobian<SE3>* JA, Jacobian<SE3>* JB) const override {
    const SE3 D = A.between(B);
    if (JA) *JA = -D.inverse().adjoint();
    if (JB) JB->setIdentity();
    return z_.inverse().compose(D).log();
  }

 private:
  SE3 z_;
};
}  // namespace

TEST_CASE("the factor Jacobian check names the wrong block") {
  Values v;
  v.insert(key('a', 0), se3TestPoints()[5]);
  v.insert(key('b', 0), se3TestPoints()[6]);
  WrongRelativeFactor f(key('a', 0), key('b', 0), se3TestPoints()[8]);
  const auto bad = checkFactorJacobians(f, v);
  REQUIRE(bad.size() == 2);
  CHECK(bad[0].key == key('a', 0));
  CHECK(bad[0].message.find("a0") != std::string::npos);
  // At zero residual the mistake is invisible, which is why we test away from it.
  WrongRelativeFactor exact(key('a', 0), key('b', 0), v.at<SE3>(key('a', 0)).between(v.at<SE3>(key('b', 0))));
  CHECK(checkFactorJacobians(exact, v).empty());
}

TEST_CASE("the factor Jacobian check also checks the solver's fast path that evaluate() does not show") {
  // Right Jacobians in evaluate(), a fast path that takes Log's Jacobian as
  // the identity: only the comparison of the path's H and g with those formed
  // from evaluate() finds it, away from a zero residual.
  Values v;
  v.insert(key('a', 0), se3TestPoints()[5]);
  const test::SloppyPrior f(key('a', 0), se3TestPoints()[8], NoiseModel::isotropic(6, 0.1));
  const auto bad = checkFactorJacobians(f, v);
  REQUIRE_FALSE(bad.empty());
  CHECK(bad[0].key == key('a', 0));
  CHECK(bad[0].message.find("fast path") != std::string::npos);
  CHECK(std::any_of(bad.begin(), bad.end(), [](const JacobianMismatch& m) {
    return m.message.find("block (a0, a0) of J^T J") != std::string::npos;
  }));
  // At zero residual the shortcut is exact.
  const test::SloppyPrior exact(key('a', 0), v.at<SE3>(key('a', 0)), NoiseModel::isotropic(6, 0.1));
  CHECK(checkFactorJacobians(exact, v).empty());
}

namespace {
// The solver's fast path of a factor's type.
const internal::NormalEquations& fastPath(const Factor& f) {
  const internal::NormalEquations* path = internal::normalEquationsFor(typeid(f));
  REQUIRE(path != nullptr);
  return *path;
}

// The blocks of a factor's fast path against J^T J and J^T r formed from
// evaluate() and the noise model (independently of checkFactorJacobians,
// which compares the same).
void checkNormalBlocks(const Factor& f, const Values& v) {
  const std::size_t n = f.keys().size();
  std::vector<const Variable*> vars;
  for (Key k : f.keys()) vars.push_back(&v.variableAt(v.indexOf(k)));
  std::vector<MatX> Js;
  const VecX rw = f.noiseModel().whiten(f.error(v, &Js));
  for (MatX& J : Js) J = f.noiseModel().sqrtInformation() * J;

  std::vector<Vec6> g(n);
  std::vector<Mat6> H(n * (n + 1) / 2);
  std::vector<double*> gp, hp;
  for (auto& x : g) gp.push_back(x.data());
  for (auto& x : H) hp.push_back(x.data());
  Vec6 r;
  fastPath(f).whitened(f, vars.data(), r.data(), gp.data(), hp.data());
  CHECK((r - rw).norm() <= 1e-12 * (1.0 + rw.norm()));
  Vec6 r_only;
  fastPath(f).whitened(f, vars.data(), r_only.data(), nullptr, nullptr);
  CHECK(r_only == r);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const VecX gi = Js[i].transpose() * rw;
    CHECK((g[i] - gi).norm() <= 1e-10 * (1.0 + gi.norm()));
    for (std::size_t j = i; j < n; ++j, ++k) {
      const MatX Hij = Js[i].transpose() * Js[j];
      INFO("block (" << i << ", " << j << ")");
      CHECK((H[k] - Hij).norm() <= 1e-10 * (1.0 + Hij.norm()));
    }
  }
}
}  // namespace

TEST_CASE("the factors' own normal-equation blocks equal J^T J and J^T r formed through J") {
  const auto pts = se3TestPoints(23);  // identity, near identity, near pi, random
  const MatX S = [] {
    MatX A = MatX::Random(6, 6);
    return MatX(A * A.transpose() + 0.1 * MatX::Identity(6, 6));
  }();
  Vec6 sigmas;
  sigmas << 0.01, 0.02, 0.03, 1.0, 2.0, 3.0;
  for (const auto& noise : {NoiseModel::fromCovariance(S), NoiseModel::diagonal(sigmas), NoiseModel::isotropic(6, 0.1)})
    for (std::size_t i = 0; i < pts.size(); ++i) {
      Values v;
      v.insert(key('a', 0), pts[i]);
      v.insert(key('b', 0), pts[(i + 3) % pts.size()]);
      const SE3 z = pts[(i + 5) % pts.size()];
      checkNormalBlocks(PriorFactorSE3(key('a', 0), z, noise), v);
      checkNormalBlocks(RelativePoseFactor(key('a', 0), key('b', 0), z, noise), v);
      checkNormalBlocks(RelativePoseFactor(key('b', 0), key('a', 0), z, noise), v);
      checkNormalBlocks(KinematicFactor(key('a', 0), key('b', 0), z, noise), v);
      CHECK(checkFactorJacobians(RelativePoseFactor(key('a', 0), key('b', 0), z, noise), v).empty());
    }
  // A user's factor has none: the solver goes through its evaluate().
  const WrongRelativeFactor plain(key('a', 0), key('b', 0), pts[3]);
  CHECK(internal::normalEquationsFor(typeid(plain)) == nullptr);
}

TEST_CASE("a factor refuses a noise model of another dimension than its residual") {
  // The SE(3) factors read W as 6x6: a 3-dimensional model would be read past its end.
  CHECK_THROWS_WITH(PriorFactorSE3(key('a', 0), SE3(), NoiseModel::isotropic(3, 0.1)),
                    Catch::Contains("dimension 6") && Catch::Contains("dimension 3"));
  CHECK_THROWS_WITH(RelativePoseFactor(key('a', 0), key('b', 0), SE3(), NoiseModel::isotropic(7, 0.1)),
                    Catch::Contains("noise model of dimension 7"));
  CHECK_NOTHROW(PriorFactorSE3(key('a', 0), SE3(), NoiseModel::isotropic(6, 0.1)));

  struct OnTwo final : TypedFactor<6, SE3, SE3> {
    explicit OnTwo(std::vector<Key> keys) : TypedFactor(std::move(keys), NoiseModel::isotropic(6, 1.0)) {}
    Residual evaluateTyped(const SE3& a, const SE3& b, Jacobian<SE3>*, Jacobian<SE3>*) const override {
      return a.between(b).log();
    }
  };
  CHECK_THROWS_WITH(OnTwo({key('a', 0)}), Catch::Contains("2 variable(s) got 1 key(s)"));
  CHECK_NOTHROW(OnTwo({key('a', 0), key('b', 0)}));
}

namespace {
// Every output of a's and b's fast path alone against the pair call,
// within rounding; the residual-only pair call gives the same residual bits.
void checkPair(const Factor& a, const Factor& b, const Values& va, const Values& vb) {
  const auto collect = [](const Factor& f, const Values& v) {
    std::vector<const Variable*> vars;
    for (Key k : f.keys()) vars.push_back(&v.variable(k));
    return vars;
  };
  const auto varsA = collect(a, va), varsB = collect(b, vb);
  struct Out {
    Vec6 r;
    std::vector<Vec6> g;
    std::vector<Mat6> H;
    std::vector<double*> gp, hp;
    explicit Out(std::size_t n) : g(n), H(n * (n + 1) / 2) {
      for (auto& x : g) gp.push_back(x.data());
      for (auto& x : H) hp.push_back(x.data());
    }
  };
  Out sa(varsA.size()), sb(varsB.size()), pa(varsA.size()), pb(varsB.size());
  const internal::NormalEquations& path = fastPath(a);
  REQUIRE(&fastPath(b) == &path);
  REQUIRE(path.pairs());
  path.whitened(a, varsA.data(), sa.r.data(), sa.gp.data(), sa.hp.data());
  path.whitened(b, varsB.data(), sb.r.data(), sb.gp.data(), sb.hp.data());
  path.whitenedPair(a, b, varsA.data(), varsB.data(), pa.r.data(), pa.gp.data(), pa.hp.data(), pb.r.data(),
                    pb.gp.data(), pb.hp.data());
  const auto close = [](const auto& x, const auto& y) {
    return (x - y).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, y.cwiseAbs().maxCoeff());
  };
  for (const auto& [single, paired] : {std::pair<const Out*, const Out*>{&sa, &pa}, {&sb, &pb}}) {
    CHECK(close(paired->r, single->r));
    for (std::size_t i = 0; i < single->g.size(); ++i) CHECK(close(paired->g[i], single->g[i]));
    for (std::size_t i = 0; i < single->H.size(); ++i) CHECK(close(paired->H[i], single->H[i]));
  }
  Vec6 ra, rb;
  path.whitenedPair(a, b, varsA.data(), varsB.data(), ra.data(), nullptr, nullptr, rb.data(), nullptr, nullptr);
  CHECK((ra.array() == pa.r.array()).all());
  CHECK((rb.array() == pb.r.array()).all());
}
}  // namespace

TEST_CASE("two like factors evaluated as a pair equal each evaluated alone, at any rotation") {
  // First residual rotations below 0.1 rad (where the pair forms the log on
  // both lanes) with translations of metres; full, diagonal and isotropic
  // noise, mixed in a pair.
  const auto pts = se3TestPoints(29);
  const MatX S = [] {
    MatX A = MatX::Random(6, 6);
    return MatX(A * A.transpose() + 0.1 * MatX::Identity(6, 6));
  }();
  Vec6 sigmas;
  sigmas << 0.01, 0.02, 0.03, 1.0, 2.0, 3.0;
  const std::vector<NoiseModel::Ptr> noises = {NoiseModel::fromCovariance(S), NoiseModel::diagonal(sigmas),
                                               NoiseModel::isotropic(6, 0.1)};
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto small = [&](double angle) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d[i] = u(gen);
    d.head<3>() *= angle / std::sqrt(3.0);
    d.tail<3>() *= 2.0;
    return d;
  };
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& na = noises[i % 3];
    const auto& nb = noises[(i + 1) % 3];
    const double angle = i == 0 ? 0.0 : 0.09 * (static_cast<double>(i % 5) + 1.0) / 5.0;
    Values va, vb;
    va.insert(key('a', 0), pts[i]);
    va.insert(key('b', 0), pts[(i + 3) % pts.size()]);
    vb.insert(key('a', 1), pts[(i + 7) % pts.size()]);
    vb.insert(key('b', 1), pts[(i + 11) % pts.size()]);
    // Measurements the estimate misses by a small rotation and any translation.
    const SE3 za = va.at<SE3>(key('a', 0)).plus(small(angle));
    const SE3 zb = vb.at<SE3>(key('a', 1)).plus(small(angle / 2));
    checkPair(PriorFactorSE3(key('a', 0), za, na), PriorFactorSE3(key('a', 1), zb, nb), va, vb);
    const SE3 da = va.at<SE3>(key('a', 0)).between(va.at<SE3>(key('b', 0))).plus(small(angle));
    const SE3 db = vb.at<SE3>(key('a', 1)).between(vb.at<SE3>(key('b', 1))).plus(small(angle / 3));
    checkPair(RelativePoseFactor(key('a', 0), key('b', 0), da, na),
              RelativePoseFactor(key('a', 1), key('b', 1), db, nb), va, vb);
  }
  // Just inside the series range (0.0998 rad; the pair takes up to 0.0999).
  {
    Values va, vb;
    va.insert(key('a', 0), pts[4]);
    vb.insert(key('a', 1), pts[8]);
    Vec6 d;
    d << 0.0998, 0.0, 0.0, 1.0, -2.0, 3.0;
    checkPair(PriorFactorSE3(key('a', 0), va.at<SE3>(key('a', 0)).plus(d), noises[0]),
              PriorFactorSE3(key('a', 1), vb.at<SE3>(key('a', 1)).plus(-d), noises[2]), va, vb);
  }
  // Only like with like: each type its own path (the linearizer pairs
  // factors of one path only); the kinematic factor's does not pair.
  const PriorFactorSE3 prior(key('a', 0), pts[1], noises[0]);
  const RelativePoseFactor rel(key('a', 0), key('b', 0), pts[2], noises[0]);
  const KinematicFactor kin(key('a', 0), key('b', 0), pts[3], noises[0]);
  CHECK(&fastPath(prior) != &fastPath(rel));
  CHECK_FALSE(fastPath(kin).pairs());
  // Rotations outside the series range (0.15 rad, 1 rad, near pi) in one
  // lane or in both: each lane's log alone, the rest on both lanes.
  const std::vector<Vec6> far = {(Vec6() << 0.15, 0, 0, 0.1, 0.2, 0.3).finished(),
                                 (Vec6() << 0.3, -0.8, 0.5, 1.0, -2.0, 0.5).finished(),
                                 (Vec6() << 0.0, 3.1, 0.0, -1.0, 0.5, 2.0).finished()};
  for (std::size_t i = 0; i < far.size(); ++i)
    for (bool both : {false, true}) {
      INFO("far rotation " << i << (both ? " in both lanes" : " in one lane"));
      Values va, vb;
      va.insert(key('a', 0), pts[5]);
      va.insert(key('b', 0), pts[9]);
      vb.insert(key('a', 1), pts[6]);
      vb.insert(key('b', 1), pts[10]);
      const Vec6 near = (Vec6() << 0.01, -0.02, 0.03, 0.5, 0.1, -0.2).finished();
      const Vec6 da = both ? Vec6(-far[(i + 1) % far.size()]) : near;
      checkPair(PriorFactorSE3(key('a', 0), va.at<SE3>(key('a', 0)).plus(da), noises[0]),
                PriorFactorSE3(key('a', 1), vb.at<SE3>(key('a', 1)).plus(far[i]), noises[1]), va, vb);
      checkPair(RelativePoseFactor(key('a', 0), key('b', 0),
                                   va.at<SE3>(key('a', 0)).between(va.at<SE3>(key('b', 0))).plus(da), noises[2]),
                RelativePoseFactor(key('a', 1), key('b', 1),
                                   vb.at<SE3>(key('a', 1)).between(vb.at<SE3>(key('b', 1))).plus(far[i]), noises[0]),
                va, vb);
    }
}
