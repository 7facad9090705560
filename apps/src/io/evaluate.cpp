// Errors of a calibration against ground truth (see evaluate.hpp).
#include "fgcal/apps/evaluate.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Cholesky>

#include "fgcal/apps/errors.hpp"
#include "text_format.hpp"

namespace fgcal::apps {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Angle difference wrapped to [-pi, pi).
double wrapAngle(double a) {
  double w = std::fmod(a + M_PI, 2.0 * M_PI);
  if (w < 0) w += 2.0 * M_PI;
  return w - M_PI;
}

}  // namespace

PoseError poseError(const SE3& est, const Mat6& cov, const SE3& truth) {
  PoseError e;
  const Vec3 dt = est.translation() - truth.translation();
  e.x_mm = std::abs(dt.x()) * 1000.0;
  e.y_mm = std::abs(dt.y()) * 1000.0;
  e.z_mm = std::abs(dt.z()) * 1000.0;
  const Vec3 drpy = est.so3().rpy() - truth.so3().rpy();
  e.roll_deg = std::abs(wrapAngle(drpy[0])) * kRadToDeg;
  e.pitch_deg = std::abs(wrapAngle(drpy[1])) * kRadToDeg;
  e.yaw_deg = std::abs(wrapAngle(drpy[2])) * kRadToDeg;
  e.translation_mm = dt.norm() * 1000.0;
  e.rotation_deg = truth.so3().between(est.so3()).log().norm() * kRadToDeg;
  // truth = est Exp(xi) with xi ~ N(0, cov) for a consistent estimate.
  const Vec6 xi = est.minus(truth);
  const Eigen::LLT<Mat6> llt(cov);
  if (llt.info() == Eigen::Success && cov.allFinite() && cov.diagonal().minCoeff() > 0.0) {
    e.nees = xi.dot(llt.solve(xi));
  } else {
    e.nees = std::numeric_limits<double>::quiet_NaN();
  }
  return e;
}

Evaluation evaluate(const CalibrationOutput& result, const GroundTruth& truth) {
  std::vector<std::string> no_truth, no_result;
  for (const CameraResult& c : result.cameras)
    if (!truth.T_base_cam.count(c.name)) no_truth.push_back(c.name);
  for (const auto& [name, T] : truth.T_base_cam) {
    bool found = false;
    for (const CameraResult& c : result.cameras) found = found || c.name == name;
    if (!found) no_result.push_back(name);
  }
  if (!no_truth.empty() || !no_result.empty()) {
    std::string d = "expected the same cameras in the calibration and the ground truth";
    if (!no_truth.empty()) d += "; without ground truth: " + detail::joinNames(no_truth);
    if (!no_result.empty()) d += "; without calibration result: " + detail::joinNames(no_result);
    throw InputError("ground truth", "cameras", d);
  }
  Evaluation ev;
  for (const CameraResult& c : result.cameras)
    ev.cameras[c.name] = poseError(c.T_base_cam, c.covariance, truth.T_base_cam.at(c.name));
  if (truth.T_link_marker) ev.mount = poseError(result.mount.T_link_marker, result.mount.covariance, *truth.T_link_marker);
  return ev;
}

std::string formatEvaluationTable(const Evaluation& ev) {
  std::string s;
  char line[256];
  std::snprintf(line, sizeof(line), "%-16s %8s %8s %8s %9s %9s %9s %9s %9s %8s\n", "pose", "x mm", "y mm", "z mm",
                "roll deg", "pitch deg", "yaw deg", "|t| mm", "angle deg", "NEES");
  s += line;
  const auto row = [&](const std::string& name, const PoseError& e) {
    std::snprintf(line, sizeof(line), "%-16.16s %8.3f %8.3f %8.3f %9.4f %9.4f %9.4f %9.3f %9.4f %8.2f\n", name.c_str(),
                  e.x_mm, e.y_mm, e.z_mm, e.roll_deg, e.pitch_deg, e.yaw_deg, e.translation_mm, e.rotation_deg, e.nees);
    s += line;
  };
  for (const auto& [name, e] : ev.cameras) row(name, e);
  if (ev.mount) row("mount", *ev.mount);
  s += "Absolute errors in the base frame (mount: in its link); NEES ~ 6 on average for honest covariances "
       "(nan: no covariance).\n";
  return s;
}

}  // namespace fgcal::apps
