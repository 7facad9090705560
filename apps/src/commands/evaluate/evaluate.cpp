// Errors of a calibration against ground truth (see evaluate.hpp).
#include "fgcal/apps/evaluate.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Cholesky>

#include "fgcal/apps/camchain.hpp"
#include "fgcal/apps/errors.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

ScalarError scalarError(const EstimateWithSigma& e, double truth) {
  ScalarError s;
  s.estimate = e.value;
  s.truth = truth;
  s.sigma = e.sigma;
  s.error = e.value - truth;
  s.sigmas = e.sigma > 0.0 && std::isfinite(e.sigma) ? s.error / e.sigma : std::numeric_limits<double>::quiet_NaN();
  return s;
}

std::vector<ScalarError> listErrors(const std::vector<EstimateWithSigma>& est, const std::vector<double>& truth,
                                    const std::string& field) {
  if (est.size() != truth.size())
    throw InputError("ground truth", field,
                     "the calibration has " + std::to_string(est.size()) + " values and the ground truth " +
                         std::to_string(truth.size()) + "; expected the same camera model on both sides");
  std::vector<ScalarError> out;
  for (std::size_t i = 0; i < est.size(); ++i) out.push_back(scalarError(est[i], truth[i]));
  return out;
}

// The estimated quantities of one camera against its truth.
void evaluateCamera(const std::string& name, const EstimatedCamera& est, const GroundTruth& truth, Evaluation* ev) {
  if (est.time_offset_ms) {
    const auto t = truth.time_offset_ms.find(name);
    if (t != truth.time_offset_ms.end()) ev->time_offsets_ms[name] = scalarError(*est.time_offset_ms, t->second);
    else ev->without_truth.push_back(name + ".time_offset_ms");
  }
  if (est.readout_ms) {
    const auto t = truth.readout_ms.find(name);
    if (!est.readout_observed) ev->readouts_not_observed.push_back(name);
    else if (t != truth.readout_ms.end()) ev->readouts_ms[name] = scalarError(*est.readout_ms, t->second);
    else ev->without_truth.push_back(name + ".readout_ms");
  }
  if (!est.intrinsics.empty()) {
    const auto t = truth.intrinsics.find(name);
    if (t != truth.intrinsics.end())
      ev->intrinsics[name] = listErrors(est.intrinsics, t->second, "cameras." + name + ".intrinsics");
    else ev->without_truth.push_back(name + ".intrinsics");
  }
  if (!est.distortion_coeffs.empty()) {
    const auto t = truth.distortion_coeffs.find(name);
    if (t != truth.distortion_coeffs.end())
      ev->distortion_coeffs[name] =
          listErrors(est.distortion_coeffs, t->second, "cameras." + name + ".distortion_coeffs");
    else ev->without_truth.push_back(name + ".distortion_coeffs");
  }
}

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
  if (truth.T_link_marker)
    ev.mount = poseError(result.mount.T_link_marker, result.mount.covariance, *truth.T_link_marker);
  else
    ev.mount_not_scored = "the ground truth holds no mount: neither mount.T_link_marker nor robot.T_link_marker";
  return ev;
}

Evaluation evaluate(const CalibrationOutput& result, const EstimatedQuantities& estimates, const GroundTruth& truth) {
  Evaluation ev = evaluate(result, truth);
  ev.method = estimates.method;
  for (const auto& [name, cam] : estimates.cameras) evaluateCamera(name, cam, truth, &ev);
  const auto score = [&](const std::map<std::string, EstimatedJointOffset>& estimated,
                         const std::map<std::string, double>& truths, const std::string& field,
                         std::map<std::string, ScalarError>& scored,
                         std::map<std::string, EstimatedJointOffset>& not_observed) {
    for (const auto& [joint, est] : estimated) {
      if (!est.observed) {
        not_observed[joint] = est;
        continue;
      }
      const auto t = truths.find(joint);
      if (t != truths.end()) scored[joint] = scalarError(est.offset_rad, t->second);
      else ev.without_truth.push_back(field + "." + joint);
    }
  };
  score(estimates.joint_offsets, truth.joint_offsets_rad, "joint_offsets", ev.joint_offsets_rad,
        ev.joint_offsets_not_observed);
  score(estimates.backlash, truth.backlash_rad, "backlash", ev.backlash_rad, ev.backlash_not_observed);
  return ev;
}

std::optional<InputError> swappedEvaluateArguments(const std::string& calibration_path,
                                                   const std::string& truth_path) {
  try {
    const std::string text = readTextFile(truth_path, "ground truth");
    if (!looksLikeKalibrCamchain(text)) parseCalibrationYaml(text, truth_path);
  } catch (const std::exception&) {
    return std::nullopt;  // not a result either: the caller's own error stands
  }
  return InputError(calibration_path, "",
                    "expected a calibration result first, then the ground truth (fgcal evaluate RESULT TRUTH); "
                    "this file is not a calibration result, and the second argument " +
                        truth_path + " is one: the arguments look swapped");
}

Evaluation evaluateFiles(const std::string& calibration_path, const std::string& truth_path) {
  const std::string text = readTextFile(calibration_path, "calibration result");
  CalibrationOutput result;
  try {
    result = parseCalibrationYaml(text, calibration_path);
  } catch (const InputError&) {
    if (auto swapped = swappedEvaluateArguments(calibration_path, truth_path)) throw *swapped;
    throw;
  }
  const EstimatedQuantities estimates = parseEstimatedQuantities(text, calibration_path);
  return evaluate(result, estimates, loadGroundTruth(truth_path));
}

namespace {

// One section of the estimated quantities: a header, then name, parameter,
// estimate, truth, error, sigma and error / sigma per row, values * scale.
struct Section {
  std::string s;
  int scored = 0, within3 = 0;
  void header(const char* title, const std::string& unit) {
    char line[256];
    std::snprintf(line, sizeof(line), "\n%-16s %-8s %13s %13s %13s %13s %11s\n", title, "",
                  ("estimate " + unit).c_str(), ("truth " + unit).c_str(), ("error " + unit).c_str(),
                  ("sigma " + unit).c_str(), "error/sigma");
    s += line;
  }
  void row(const std::string& name, const std::string& param, const ScalarError& e, double scale, int decimals) {
    char line[320];
    std::snprintf(line, sizeof(line), "%-16.16s %-8s %13.*f %13.*f %13.*f %13.*f %11.2f\n", name.c_str(),
                  param.c_str(), decimals, e.estimate * scale, decimals, e.truth * scale, decimals, e.error * scale,
                  decimals, e.sigma * scale, e.sigmas);
    s += line;
    ++scored;
    within3 += std::abs(e.sigmas) <= 3.0 ? 1 : 0;
  }
};

std::string formatEstimatedQuantities(const Evaluation& ev) {
  Section sec;
  if (!ev.time_offsets_ms.empty()) {
    sec.header("time offset", "ms");
    for (const auto& [name, e] : ev.time_offsets_ms) sec.row(name, "", e, 1.0, 4);
  }
  if (!ev.readouts_ms.empty() || !ev.readouts_not_observed.empty()) {
    sec.header("readout", "ms");
    for (const auto& [name, e] : ev.readouts_ms) sec.row(name, "", e, 1.0, 4);
    for (const std::string& name : ev.readouts_not_observed)
      sec.s += name + ": readout not observed by the data: not scored\n";
  }
  const auto joints = [&](const char* title, const std::map<std::string, ScalarError>& scored,
                          const std::map<std::string, EstimatedJointOffset>& not_observed) {
    if (scored.empty() && not_observed.empty()) return;
    sec.header(title, "mrad");
    for (const auto& [joint, e] : scored) sec.row(joint, "", e, 1000.0, 4);
    char line[256];
    for (const auto& [joint, e] : not_observed) {
      std::snprintf(line, sizeof(line), "%-16.16s %-8s not observed by the data: not scored (estimate %.4f, sigma %.4f mrad)\n",
                    joint.c_str(), "", e.offset_rad.value * 1000.0, e.offset_rad.sigma * 1000.0);
      sec.s += line;
    }
  };
  joints("joint offset", ev.joint_offsets_rad, ev.joint_offsets_not_observed);
  joints("backlash", ev.backlash_rad, ev.backlash_not_observed);
  if (!ev.intrinsics.empty() || !ev.distortion_coeffs.empty()) {
    sec.header("intrinsics", "px");
    static const char* kNames[4] = {"fx", "fy", "cx", "cy"};
    for (const auto& [name, errors] : ev.intrinsics)
      for (std::size_t i = 0; i < errors.size() && i < 4; ++i) sec.row(name, kNames[i], errors[i], 1.0, 4);
    for (const auto& [name, errors] : ev.distortion_coeffs)
      for (std::size_t i = 0; i < errors.size(); ++i)
        sec.row(name, "coeff " + std::to_string(i), errors[i], 1.0, 6);
  }
  if (!ev.without_truth.empty())
    sec.s += "\nNo ground truth for (not scored): " + detail::joinNames(ev.without_truth) + "\n";
  if (sec.scored > 0) {
    if (!ev.method.empty()) sec.s += "Method: " + ev.method + ". ";
    sec.s += std::to_string(sec.within3) + " of " + std::to_string(sec.scored) +
             " estimated quantities within 3 sigma of the truth (error/sigma nan: no sigma; distortion "
             "coefficients unitless).\n";
  }
  return sec.s;
}

}  // namespace

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
  if (!ev.mount && !ev.mount_not_scored.empty()) s += "mount: not scored (" + ev.mount_not_scored + ")\n";
  s += "Absolute errors in the base frame (mount: in its link); NEES ~ 6 on average for honest covariances "
       "(nan: no covariance).\n";
  s += formatEstimatedQuantities(ev);
  return s;
}

}  // namespace fgcal::apps
