// Waypoint selection and minimum-jerk interpolation of the simulated leg.
#include "commands/simulate/leg_motion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "fgcal/apps/errors.hpp"

namespace fgcal::apps::sim {

VecX LegTrajectory::at(double t) const {
  if (waypoints_.empty()) return VecX();
  if (t <= times_.front()) return waypoints_.front();
  if (t >= times_.back()) return waypoints_.back();
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const size_t k = static_cast<size_t>(it - times_.begin());  // times_[k-1] <= t < times_[k]
  const double tau = (t - times_[k - 1]) / (times_[k] - times_[k - 1]);
  const double s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);  // minimum jerk
  return waypoints_[k - 1] + s * (waypoints_[k] - waypoints_[k - 1]);
}

JointPlay::JointPlay(const LegTrajectory& motor, VecX backlash)
    : motor_(&motor), half_(0.5 * backlash), none_((backlash.array() == 0.0).all()) {
  const auto& w = motor.waypoints();
  if (none_ || w.empty()) return;
  VecX y = w.front();
  for (Eigen::Index j = 0; j < y.size(); ++j)
    for (std::size_t k = 1; k < w.size(); ++k)
      if (w[k](j) != w[0](j)) {  // behind the first move
        y(j) -= w[k](j) > w[0](j) ? half_(j) : -half_(j);
        break;
      }
  start_.push_back(y);
  for (std::size_t k = 1; k < w.size(); ++k)
    start_.push_back(start_.back().cwiseMax(w[k] - half_).cwiseMin(w[k] + half_));
}

VecX JointPlay::at(double t) const {
  const VecX m = motor_->at(t);
  if (none_ || start_.empty()) return m;
  const auto& times = motor_->times();
  // The segment holding t starts at waypoint k (the last one past the end).
  const auto k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(
      0, std::upper_bound(times.begin(), times.end(), t) - times.begin() - 1));
  return start_[k].cwiseMax(m - half_).cwiseMin(m + half_);
}

namespace {

constexpr double kMaxAngle = 55.0 * M_PI / 180.0;  // a board seen well faces the camera within this

struct Candidate {
  VecX q;
  SE3 T_base_marker;
};

// The leg, its board and the cameras: how many cameras see the board well.
struct BoardView {
  const kinematics::KinematicChain& chain;
  const SE3& T_link_marker;
  const std::vector<SimCamera>& cameras;
  const vision::CharucoTarget& target;

  int camerasSeeing(const SE3& T_base_marker, double max_angle) const {
    int n = 0;
    for (const auto& c : cameras)
      if (viewQuality(c, T_base_marker, target).good(0.3, 0.9, max_angle)) ++n;
    return n;
  }
  bool seenByAll(const VecX& q, double max_angle) const {
    return camerasSeeing(chain.forward(q) * T_link_marker, max_angle) == static_cast<int>(cameras.size());
  }
};

// Configurations in which the board is seen well: by every camera when at
// least 20 are found, else by at least one. The workspace samples first, then
// up to four rounds of samples around what was found (a narrow workspace
// leaves few uniform hits).
std::vector<Candidate> candidatePool(const BoardView& view, const Workspace& ws, Rng& rng) {
  const int n_cams = static_cast<int>(view.cameras.size());
  VecX lo, hi;
  jointRanges(view.chain, &lo, &hi);
  std::vector<Candidate> all_cams, any_cam;
  auto consider = [&](const VecX& q, const SE3& T_base_link) {
    const SE3 T = T_base_link * view.T_link_marker;
    const int n = view.camerasSeeing(T, kMaxAngle);
    if (n == n_cams) all_cams.push_back({q, T});
    if (n > 0) any_cam.push_back({q, T});
  };
  for (size_t k = 0; k < ws.samples.size(); ++k) consider(ws.samples[k], ws.T_base_link[k]);
  for (int round = 0; round < 4 && all_cams.size() < 400 && !any_cam.empty(); ++round) {
    const std::vector<Candidate> seeds = all_cams.size() >= 10 ? all_cams : any_cam;
    for (int k = 0; k < 1500; ++k) {
      VecX q = seeds[rng.index(seeds.size())].q;
      for (int i = 0; i < q.size(); ++i)
        q(i) = std::clamp(q(i) + 0.08 * (hi(i) - lo(i)) * rng.normal(), lo(i), hi(i));
      consider(q, view.chain.forward(q));
    }
  }
  if (any_cam.empty())
    throw DataError("simulate: the board on '" + view.chain.tipLink() +
                    "' never comes in view of the cameras within the joint limits of the chain from '" +
                    view.chain.baseLink() + "'; choose another marker link");
  return all_cams.size() >= 20 ? all_cams : any_cam;
}

// The candidate nearest the typical raised pose the mount was designed for.
size_t startIndex(const std::vector<Candidate>& pool, const VecX& q_typical) {
  size_t start = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < pool.size(); ++k) {
    const double d = (pool[k].q - q_typical).norm();
    if (d < best_d) best_d = d, start = k;
  }
  return start;
}

// The next waypoint after q_cur: of 60 random candidates at least 0.15 rad
// away, the one whose board pose is most novel against every pose visited,
// whose straight joint-space path keeps the board in view, and which is not
// too far; any other candidate when all are too close. Returns its index in
// the pool and the largest joint change to it.
std::pair<size_t, double> nextWaypoint(const BoardView& view, const std::vector<Candidate>& pool, const VecX& q_cur,
                                       const std::vector<SE3>& visited, Rng& rng) {
  const int kTries = 60, kPathChecks = 6;
  double best_score = -std::numeric_limits<double>::infinity();
  size_t best = pool.size();
  double best_delta = 0.0;
  for (int t = 0; t < kTries; ++t) {
    const size_t k = rng.index(pool.size());
    const Candidate& c = pool[k];
    const double delta = (c.q - q_cur).cwiseAbs().maxCoeff();
    if (delta < 0.15) continue;
    // Novelty: distance to every pose visited so far (rotation plus 2 rad/m).
    double novelty = std::numeric_limits<double>::infinity();
    for (const SE3& v : visited) {
      const double rot = v.so3().between(c.T_base_marker.so3()).log().norm();
      const double pos = (v.translation() - c.T_base_marker.translation()).norm();
      novelty = std::min(novelty, rot + 2.0 * pos);
    }
    novelty = std::min(novelty, 1.0);
    // The segment is a straight line in joint space: keep it in view.
    int seen = 0;
    for (int j = 1; j <= kPathChecks; ++j) {
      const VecX q = q_cur + (c.q - q_cur) * (static_cast<double>(j) / (kPathChecks + 1));
      if (view.seenByAll(q, 65.0 * M_PI / 180.0)) ++seen;
    }
    const double score = novelty + 0.8 * seen / kPathChecks - 0.5 * std::max(0.0, delta - 1.2);
    if (score > best_score) best_score = score, best = k, best_delta = delta;
  }
  if (best == pool.size()) {  // every try too close: take any other point
    best = rng.index(pool.size());
    best_delta = (pool[best].q - q_cur).cwiseAbs().maxCoeff();
  }
  return {best, best_delta};
}

}  // namespace

LegTrajectory planLegMotion(const kinematics::KinematicChain& chain, const SE3& T_link_marker,
                            const std::vector<SimCamera>& cameras, const vision::CharucoTarget& target,
                            const Workspace& ws, double duration, Rng& rng) {
  const BoardView view{chain, T_link_marker, cameras, target};
  const std::vector<Candidate> pool = candidatePool(view, ws, rng);
  const size_t start = startIndex(pool, ws.q_typical);
  std::vector<double> times{0.0};
  std::vector<VecX> waypoints{pool[start].q};
  std::vector<SE3> visited{pool[start].T_base_marker};
  while (times.back() < duration) {
    const auto [next, delta] = nextWaypoint(view, pool, waypoints.back(), visited, rng);
    times.push_back(times.back() + std::clamp(0.5 + 0.7 * delta, 0.5, 1.5));
    waypoints.push_back(pool[next].q);
    visited.push_back(pool[next].T_base_marker);
  }
  return LegTrajectory(std::move(times), std::move(waypoints));
}

}  // namespace fgcal::apps::sim
