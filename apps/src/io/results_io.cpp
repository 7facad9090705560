// calibration.yaml, ground_truth.yaml and the URDF snippet (see results_io.hpp).
#include "fgcal/apps/results_io.hpp"

#include <cmath>

#include "fgcal/apps/errors.hpp"
#include "io/calibration_yaml_read.hpp"
#include "io/text_format.hpp"
#include "io/yaml_read.hpp"

namespace fgcal::apps {

using detail::formatDouble;
using detail::formatList;
using detail::formatMatrixBlock;
using detail::YNode;
using detail::yamlScalar;

Mat3 rpyJacobian(const SO3& R) {
  // For R = Rz(yaw) Ry(pitch) Rx(roll), the body-frame angular velocity is
  // w = E [roll' pitch' yaw']' with E = [[1 0 -sp] [0 cr sr cp] [0 -sr cr cp]];
  // the right perturbation R Exp(w) is a body-frame rotation, so
  // d rpy / d w = E^-1.
  const Vec3 rpy = R.rpy();
  const double sr = std::sin(rpy[0]), cr = std::cos(rpy[0]);
  const double cp = std::cos(rpy[1]), tp = std::tan(rpy[1]);
  Mat3 J;
  J << 1.0, sr * tp, cr * tp,  //
      0.0, cr, -sr,            //
      0.0, sr / cp, cr / cp;
  return J;
}

Vec6 sigmaMmDeg(const SE3& T, const Mat6& cov) {
  // Position of T Exp(xi): t + R Jl(w) v ≈ t + R v, so Sigma_xyz = R Sigma_vv R^T.
  const Mat3& R = T.rotation();
  const Mat3 S_xyz = R * cov.bottomRightCorner<3, 3>() * R.transpose();
  const Mat3 J = rpyJacobian(T.so3());
  const Mat3 S_rpy = J * cov.topLeftCorner<3, 3>() * J.transpose();
  constexpr double kRadToDeg = 180.0 / M_PI;
  Vec6 s;
  for (int i = 0; i < 3; ++i) {
    s[i] = std::sqrt(std::max(0.0, S_xyz(i, i))) * 1000.0;
    s[3 + i] = std::sqrt(std::max(0.0, S_rpy(i, i))) * kRadToDeg;
  }
  return s;
}

namespace {

std::string poseBlock(const std::string& key, const SE3& T, const Mat6& cov, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  std::string s;
  s += pad + key + ":  # 4x4 row-major" + formatMatrixBlock(T.matrix(), indent + 2) + "\n";
  s += pad + "covariance:  # 6x6 [wx wy wz vx vy vz], right perturbation" + formatMatrixBlock(cov, indent + 2) + "\n";
  s += pad + "sigma_mm_deg: " + formatList(sigmaMmDeg(T, cov)) + "  # 1-sigma x y z (mm), roll pitch yaw (deg)\n";
  return s;
}

/// The top-level `quality:` block (quality.hpp; docs/outputs.md).
std::string qualityBlock(const Quality& q) {
  std::string s = "quality:  # the result's verdict on itself: ok | check | unusable (docs/outputs.md)\n";
  s += std::string("  verdict: ") + toString(q.verdict) + "\n";
  s += q.findings.empty() ? "  findings: []\n" : "  findings:\n";
  for (const Finding& f : q.findings) {
    s += "    - check: " + yamlScalar(f.check) + "\n";
    s += std::string("      severity: ") + toString(f.severity) + "\n";
    std::string fields;
    for (const std::string& x : f.fields) fields += (fields.empty() ? "" : ", ") + yamlScalar(x);
    s += "      fields: [" + fields + "]\n";
    s += "      message: " + detail::yamlQuoted(f.message) + "\n";
    if (!f.estimate.empty()) {
      s += "      estimate:\n";
      for (const auto& [k, v] : f.estimate) s += "        " + yamlScalar(k) + ": " + v + "\n";
    }
    if (!f.command.empty()) s += "      command: " + detail::yamlQuoted(f.command) + "\n";
  }
  if (!q.statistics.empty()) {
    s += "  statistics:  # each test's chi-square, its dof on a correct input, P(larger)\n";
    for (const Statistic& t : q.statistics)
      s += "    - {test: " + detail::yamlQuoted(t.test) + ", chi2: " + formatDouble(t.chi2) +
           ", dof: " + formatDouble(t.dof) + ", p: " + formatDouble(t.p) + "}\n";
  }
  return s;
}

std::string xyz(double a, double b, double c) {
  return detail::formatDoubleCsv(a) + " " + detail::formatDoubleCsv(b) + " " + detail::formatDoubleCsv(c);
}

}  // namespace

RelativePoseResult relativePose(const CameraResult& a, const CameraResult& b, const Mat6& cross) {
  RelativePoseResult r;
  r.a = a.name;
  r.b = b.name;
  r.T_a_b = a.T_base_cam.inverse() * b.T_base_cam;
  // T_a Exp(x_a), T_b Exp(x_b): T_a_b Exp(x_b - Ad(T_a_b^-1) x_a) to first order.
  const Mat6 A = r.T_a_b.inverse().adjoint();
  const Mat6 AS = A * cross;
  r.covariance = b.covariance + A * a.covariance * A.transpose() - AS - AS.transpose();
  r.covariance = 0.5 * (r.covariance + r.covariance.transpose());
  return r;
}

namespace {

/// One camera's entry of `cameras:`.
std::string cameraBlock(const CameraResult& c) {
  std::string s = "  " + yamlScalar(c.name) + ":\n";
  s += poseBlock("T_base_cam", c.T_base_cam, c.covariance, 4);
  s += "    xyz_rpy: " + formatList(c.T_base_cam.xyzRpy()) + "  # metres, radians (URDF <origin>)\n";
  s += "    images_used: " + std::to_string(c.images_used) + "\n";
  s += "    rms_reprojection_px: " + formatDouble(c.rms_reprojection_px) + "\n";
  if (c.time_offset_ms) {
    s += "    time_offset_ms: " + formatDouble(*c.time_offset_ms) + "  # an image stamped t was exposed at t + offset\n";
    s += "    time_offset_sigma_ms: " + formatDouble(c.time_offset_sigma_ms.value_or(0.0)) + "\n";
  }
  if (c.readout_ms) {
    s += "    readout_ms: " + formatDouble(*c.readout_ms) +
         (c.readout_sigma_ms ? "  # rolling shutter: row v exposed at t + time_offset + v / (rows - 1) * readout\n"
                             : "  # rig.yaml's, held (not estimated)\n");
    if (c.readout_sigma_ms) {
      s += "    readout_sigma_ms: " + formatDouble(*c.readout_sigma_ms) + "\n";
      if (!c.readout_observed) s += "    readout_observed: false  # the data do not tell it: the prior is written\n";
    }
  }
  if (c.sigma_from_urdf_mm_deg)
    s += "    sigma_from_urdf_mm_deg: " + formatList(*c.sigma_from_urdf_mm_deg) +
         "  # of sigma_mm_deg, what the URDF's tolerance (robot.kinematic_sigma) adds; relative poses between "
         "cameras do not depend on it\n";
  if (c.images_skipped.empty()) {
    s += "    images_skipped: {}\n";
  } else {
    s += "    images_skipped:  # reason: count\n";
    for (const auto& [reason, n] : c.images_skipped)
      s += "      " + detail::yamlQuoted(reason) + ": " + std::to_string(n) + "\n";
  }
  if (!c.intrinsics.empty()) {
    s += "    intrinsics: " + formatList(c.intrinsics) + "  # estimated fx, fy, cx, cy (pixels)\n";
    s += "    intrinsics_sigma: " + formatList(c.intrinsics_sigma) + "  # 1-sigma\n";
    if (!c.distortion_coeffs.empty()) {  // none for a camera without distortion
      s += "    distortion_coeffs: " + formatList(c.distortion_coeffs) + "  # estimated\n";
      s += "    distortion_coeffs_sigma: " + formatList(c.distortion_coeffs_sigma) + "  # 1-sigma\n";
    }
  }
  return s;
}

/// T_a_b for every pair of cameras in file order.
std::string relativePoseBlocks(const CalibrationOutput& out) {
  std::string s;
  for (std::size_t i = 0; i < out.cameras.size(); ++i)
    for (std::size_t j = i + 1; j < out.cameras.size(); ++j) {
      const CameraResult &a = out.cameras[i], &b = out.cameras[j];
      RelativePoseResult rel = relativePose(a, b, Mat6::Zero());
      for (const RelativePoseResult& r : out.relative_poses)
        if (r.a == a.name && r.b == b.name) rel = r;
      const std::string key = "T_" + a.name + "_" + b.name;
      s += yamlScalar(key) + ":  # pose of " + b.name + " in " + a.name +
           ", with its own covariance (what both cameras share cancels when they were solved together)\n";
      s += poseBlock(yamlScalar(key), rel.T_a_b, rel.covariance, 2);
    }
  return s;
}

/// joint_offsets: or backlash: (`header` with its comment), each joint's
/// `value` key, sigma_rad and observed; "" when there are none.
std::string jointVectorBlock(const std::string& header, const char* value, const std::vector<JointOffsetResult>& v) {
  if (v.empty()) return "";
  std::string s = header;
  for (const JointOffsetResult& j : v)
    s += "  " + yamlScalar(j.joint) + ":\n    " + value + ": " + formatDouble(j.offset_rad) +
         "\n    sigma_rad: " + formatDouble(j.sigma_rad) + "\n    observed: " + (j.observed ? "true" : "false") + "\n";
  return s;
}

std::string originsBlock(const std::vector<OriginResult>& origins) {
  if (origins.empty()) return "";
  std::string s =
      "kinematic_origins:  # robot.kinematic_sigma: the transform before each joint is the URDF's times "
      "Exp(correction), [wx wy wz vx vy vz]; observed: false = the data do not tell it, it rests on the prior\n";
  for (const OriginResult& o : origins) {
    std::string obs;
    for (bool b : o.observed) obs += std::string(obs.empty() ? "" : ", ") + (b ? "true" : "false");
    s += "  " + yamlScalar(o.joint) + ":\n    correction: " + formatList(o.correction) +
         "\n    sigma: " + formatList(o.sigma) + "\n    observed: [" + obs + "]\n";
  }
  return s;
}

/// method:, estimated: and info: (the run's stamp).
std::string runBlock(const CalibrationOutput& out) {
  std::string s = "method: " + yamlScalar(out.method.empty() ? std::string("unknown") : out.method) + "\n";
  std::string estimated;
  for (const std::string& e : out.estimated) estimated += (estimated.empty() ? "" : ", ") + yamlScalar(e);
  s += "estimated: [" + estimated + "]\n";
  if (out.info.empty()) return s + "info: {}\n";
  s += "info:\n";
  for (const auto& [k, v] : out.info) s += "  " + yamlScalar(k) + ": " + detail::yamlQuoted(v) + "\n";
  return s;
}

}  // namespace

std::string formatCalibrationYaml(const CalibrationOutput& out) {
  std::string s;
  s += "# fgcal calibration result (docs/outputs.md). Units: metres, radians.\n";
  s += "# Covariances: 6x6 row-major, [wx wy wz vx vy vz], right perturbation T * Exp(xi).\n";
  s += qualityBlock(out.quality);
  s += "cameras:\n";
  for (const CameraResult& c : out.cameras) s += cameraBlock(c);
  s += relativePoseBlocks(out);
  s += "mount:\n";
  s += poseBlock("T_link_marker", out.mount.T_link_marker, out.mount.covariance, 2);
  s += std::string("  estimated: ") + (out.mount.estimated ? "true" : "false") + "\n";
  s += jointVectorBlock(
      "joint_offsets:  # the joint stood at its reading + offset_rad; observed: false = the data do not tell it, "
      "offset_rad and sigma_rad are the prior's\n",
      "offset_rad", out.joint_offsets);
  s += jointVectorBlock(
      "backlash:  # gear play: the joint lags its reading by rad / 2 against its motion; observed: false = the "
      "data do not tell it (the joint never moved both ways, or too little), rad and sigma_rad are the prior's\n",
      "rad", out.backlash);
  s += originsBlock(out.kinematic_origins);
  s += runBlock(out);
  return s;
}

namespace {

/// A camera's estimated intrinsics (`in`: its intrinsics key): the four
/// groups come together; a camera model without distortion has none.
void readEstimatedIntrinsics(const YNode& n, const YNode& in, CameraResult& c) {
  const auto numbers = [&](const char* key, const std::string& expected, bool sigmas = false) {
    const YNode k = n.at(key, expected);
    k.listSize(expected);
    return sigmas ? k.sigmas() : k.numbers();
  };
  c.intrinsics = numbers("intrinsics", "[fx, fy, cx, cy]");
  if (c.intrinsics.size() != 4) in.fail("expected 4 numbers [fx, fy, cx, cy], got " + std::to_string(c.intrinsics.size()));
  c.intrinsics_sigma = numbers("intrinsics_sigma", "4 numbers, the 1-sigma of intrinsics", true);
  if (n.maybe("distortion_coeffs").node.IsDefined()) {
    c.distortion_coeffs = numbers("distortion_coeffs", "the estimated distortion coefficients");
    c.distortion_coeffs_sigma = numbers("distortion_coeffs_sigma", "the 1-sigma of distortion_coeffs", true);
  }
  if (c.intrinsics_sigma.size() != 4)
    n.at("intrinsics_sigma", "").fail("expected 4 numbers, got " + std::to_string(c.intrinsics_sigma.size()));
  if (c.distortion_coeffs_sigma.size() != c.distortion_coeffs.size())
    n.at("distortion_coeffs_sigma", "")
        .fail("expected " + std::to_string(c.distortion_coeffs.size()) + " numbers (one per coefficient), got " +
              std::to_string(c.distortion_coeffs_sigma.size()));
}

/// One camera's result, `n` its mapping under cameras.
CameraResult readCameraResult(const std::string& name, const YNode& n) {
  CameraResult c;
  c.name = name;
  n.requireMap("a mapping with keys T_base_cam, covariance, images_used, rms_reprojection_px");
  c.T_base_cam = n.at("T_base_cam", "the camera pose in the base frame, 4x4").transform();
  c.covariance = n.at("covariance", "a 6x6 covariance").matrix(6, 6, true);
  c.images_used = n.at("images_used", "the number of images used").integer(0);
  c.rms_reprojection_px = n.at("rms_reprojection_px", "the RMS reprojection error in pixels").anyNumber();
  const YNode sk = n.maybe("images_skipped");
  if (sk.node.IsDefined()) {
    sk.requireMap("a mapping reason -> count");
    for (auto s = sk.node.begin(); s != sk.node.end(); ++s) {
      const std::string reason = s->first.Scalar();
      c.images_skipped[reason] = YNode{s->second, n.file, sk.childPath(reason)}.integer(0);
    }
  }
  const YNode to = n.maybe("time_offset_ms");
  if (to.node.IsDefined()) {
    c.time_offset_ms = to.number();
    c.time_offset_sigma_ms = n.at("time_offset_sigma_ms", "the 1-sigma of time_offset_ms, milliseconds").nonNegative();
  }
  if (const YNode ro = n.maybe("readout_ms"); ro.node.IsDefined()) {
    c.readout_ms = ro.number();  // an estimate of a global shutter may fall below 0 within its sigma
    if (const YNode rs = n.maybe("readout_sigma_ms"); rs.node.IsDefined()) c.readout_sigma_ms = rs.nonNegative();
    if (const YNode rb = n.maybe("readout_observed"); rb.node.IsDefined()) c.readout_observed = rb.boolean();
  }
  const YNode in = n.maybe("intrinsics");
  if (in.node.IsDefined()) readEstimatedIntrinsics(n, in, c);
  if (const YNode su = n.maybe("sigma_from_urdf_mm_deg"); su.node.IsDefined()) {
    const std::vector<double> v = su.sigmas();
    if (v.size() != 6) su.fail("expected 6 sigmas [x y z mm, roll pitch yaw deg], got " + std::to_string(v.size()));
    c.sigma_from_urdf_mm_deg = Vec6(Eigen::Map<const Vec6>(v.data()));
  }
  return c;
}

/// kinematic_origins: when present (robot.kinematic_sigma).
std::vector<OriginResult> readKinematicOrigins(const YNode& root) {
  std::vector<OriginResult> out;
  const YNode ko = root.maybe("kinematic_origins");
  if (!ko.node.IsDefined()) return out;
  ko.requireMap("a mapping joint -> {correction, sigma, observed}");
  for (auto it = ko.node.begin(); it != ko.node.end(); ++it) {
    OriginResult o;
    o.joint = it->first.Scalar();
    const YNode n{it->second, root.file, ko.childPath(o.joint)};
    const auto six = [&](const char* key, bool sigma) {
      const YNode v = n.at(key, "6 numbers [wx wy wz vx vy vz]");
      const std::vector<double> x = sigma ? v.sigmas() : v.numbers();
      if (x.size() != 6) v.fail("expected 6 numbers [wx wy wz vx vy vz], got " + std::to_string(x.size()));
      return Vec6(Eigen::Map<const Vec6>(x.data()));
    };
    o.correction = six("correction", false);
    o.sigma = six("sigma", true);
    const YNode obs = n.at("observed", "6 booleans");
    if (obs.listSize("a list of 6 booleans") != 6) obs.fail("expected 6 booleans, got " + obs.found());
    for (std::size_t k = 0; k < 6; ++k) o.observed[k] = obs[k].boolean();
    out.push_back(o);
  }
  return out;
}

MountResult readMountResult(const YNode& root) {
  const YNode m = root.at("mount", "the board mount result {T_link_marker, covariance, estimated}");
  m.requireMap("a mapping with keys T_link_marker, covariance, estimated");
  MountResult mount;
  mount.T_link_marker = m.at("T_link_marker", "the board pose in its link, 4x4").transform();
  mount.covariance = m.at("covariance", "a 6x6 covariance").matrix(6, 6, true);
  mount.estimated = m.at("estimated", "true or false").boolean();
  return mount;
}

Severity readSeverity(const YNode& n) {
  const std::string v = n.string();
  for (Severity s : {Severity::Note, Severity::Check, Severity::Unusable})
    if (v == toString(s)) return s;
  n.fail("expected note, check or unusable");
}

/// quality: optional (a result written before it existed has none).
Quality readQuality(const YNode& root) {
  Quality q;
  const YNode block = root.maybe("quality");
  if (!block.node.IsDefined()) return q;
  block.requireMap("a mapping with verdict and findings");
  const YNode findings = block.maybe("findings");
  if (findings.node.IsDefined()) {
    const std::size_t n = findings.listSize("a list of findings {check, severity, fields, message}");
    for (std::size_t i = 0; i < n; ++i) {
      const YNode f = findings[i];
      f.requireMap("a finding {check, severity, fields, message}");
      Finding out;
      out.check = f.at("check", "the check's id").string();
      out.severity = readSeverity(f.at("severity", "note, check or unusable"));
      const YNode fields = f.maybe("fields");
      if (fields.node.IsDefined()) {
        const std::size_t k = fields.listSize("a list of rig.yaml fields or inputs");
        for (std::size_t j = 0; j < k; ++j) out.fields.push_back(fields[j].string());
      }
      const YNode message = f.maybe("message");
      if (message.node.IsDefined() && message.node.IsScalar()) out.message = message.node.Scalar();
      const YNode estimate = f.maybe("estimate");
      if (estimate.node.IsDefined()) {
        estimate.requireMap("a mapping name -> value");
        for (auto it = estimate.node.begin(); it != estimate.node.end(); ++it) {
          YAML::Emitter e;
          e << YAML::Flow << it->second;
          out.estimate.emplace_back(it->first.Scalar(), e.c_str());
        }
      }
      const YNode command = f.maybe("command");
      if (command.node.IsDefined() && command.node.IsScalar()) out.command = command.node.Scalar();
      q.add(std::move(out));
    }
  }
  const YNode stats = block.maybe("statistics");
  if (stats.node.IsDefined()) {
    const std::size_t n = stats.listSize("a list of {test, chi2, dof, p}");
    for (std::size_t i = 0; i < n; ++i) {
      const YNode t = stats[i];
      t.requireMap("a statistic {test, chi2, dof, p}");
      q.statistics.push_back({t.at("test", "the test's name").string(), t.at("chi2", "a number").anyNumber(),
                              t.at("dof", "a number").anyNumber(), t.at("p", "a probability").anyNumber()});
    }
  }
  // The verdict as written; a file that says ok over a check-level finding is
  // read as the findings make it.
  const YNode verdict = block.at("verdict", "ok, check or unusable");
  const std::string v = verdict.string();
  Verdict written = Verdict::Ok;
  if (v == "check") written = Verdict::Check;
  else if (v == "unusable") written = Verdict::Unusable;
  else if (v != "ok") verdict.fail("expected ok, check or unusable");
  if (static_cast<int>(written) > static_cast<int>(q.verdict)) q.verdict = written;
  return q;
}

/// method, estimated and info: each optional.
void readRunFields(const YNode& root, CalibrationOutput& out) {
  const YNode method = root.maybe("method");
  if (method.node.IsDefined()) out.method = method.string();
  const YNode estimated = root.maybe("estimated");
  if (estimated.node.IsDefined()) {
    const std::size_t n = estimated.listSize("a list of estimated quantities, e.g. [intrinsics]");
    for (std::size_t i = 0; i < n; ++i) out.estimated.push_back(estimated[i].string());
  }
  const YNode info = root.maybe("info");
  if (info.node.IsDefined()) {
    info.requireMap("a mapping key -> text");
    for (auto it = info.node.begin(); it != info.node.end(); ++it) {
      const YNode v{it->second, root.file, info.childPath(it->first.Scalar())};
      out.info.emplace_back(it->first.Scalar(), v.node.IsScalar() ? v.node.Scalar() : v.found());
    }
  }
}

}  // namespace

CalibrationOutput parseCalibrationYaml(const std::string& text, const std::string& file) {
  const YNode root = detail::parseYaml(text, file);
  root.requireMap("a calibration result with keys cameras and mount");
  CalibrationOutput out;
  const YNode cams = root.at("cameras", "a mapping camera name -> result");
  cams.requireMap("a mapping camera name -> {T_base_cam, covariance, images_used, ...}");
  for (auto it = cams.node.begin(); it != cams.node.end(); ++it) {
    const std::string name = it->first.Scalar();
    out.cameras.push_back(readCameraResult(name, YNode{it->second, file, cams.childPath(name)}));
  }
  out.mount = readMountResult(root);
  out.joint_offsets = detail::readJointVector(root, "joint_offsets", "offset_rad", "the joint's zero offset, radians");
  out.backlash = detail::readJointVector(root, "backlash", "rad", "the joint's gear play, radians");
  out.kinematic_origins = readKinematicOrigins(root);
  for (std::size_t i = 0; i < out.cameras.size(); ++i)
    for (std::size_t j = i + 1; j < out.cameras.size(); ++j) {
      const std::string key = "T_" + out.cameras[i].name + "_" + out.cameras[j].name;
      const YNode n = root.maybe(key);
      if (!n.node.IsDefined() || !n.node.IsMap()) continue;  // a matrix alone: written before covariances were
      RelativePoseResult r;
      r.a = out.cameras[i].name;
      r.b = out.cameras[j].name;
      r.T_a_b = n.at(key, "the pose of " + r.b + " in " + r.a + ", 4x4").transform();
      r.covariance = n.at("covariance", "a 6x6 covariance").matrix(6, 6, true);
      out.relative_poses.push_back(r);
    }
  out.quality = readQuality(root);
  readRunFields(root, out);
  return out;
}

CalibrationOutput loadCalibrationYaml(const std::string& path) {
  return parseCalibrationYaml(readTextFile(path, "calibration result"), path);
}

std::string formatUrdfSnippet(const CalibrationOutput& out, const std::string& base_link) {
  std::string s = "<!-- fgcal calibration: camera frames in " + detail::xmlEscape(base_link) +
                  " (method " + detail::xmlEscape(out.method) + "). Paste inside <robot>. -->\n";
  for (const CameraResult& c : out.cameras) {
    const auto p = c.T_base_cam.xyzRpy();
    const std::string name = detail::xmlEscape(c.name);
    s += "<link name=\"" + name + "\"/>\n";
    s += "<joint name=\"" + name + "_joint\" type=\"fixed\">\n";
    s += "  <parent link=\"" + detail::xmlEscape(base_link) + "\"/>\n";
    s += "  <child link=\"" + name + "\"/>\n";
    s += "  <origin xyz=\"" + xyz(p[0], p[1], p[2]) + "\" rpy=\"" + xyz(p[3], p[4], p[5]) + "\"/>\n";
    s += "</joint>\n";
  }
  return s;
}

std::string formatGroundTruthYaml(const GroundTruth& truth) {
  std::string s = "# fgcal ground truth (same keys as calibration.yaml). Units: metres, radians, pixels; time "
                  "offsets in ms.\n";
  s += "cameras:\n";
  for (const auto& [name, T] : truth.T_base_cam) {
    s += "  " + yamlScalar(name) + ":\n    T_base_cam:" + formatMatrixBlock(T.matrix(), 6) + "\n";
    if (const auto it = truth.time_offset_ms.find(name); it != truth.time_offset_ms.end())
      s += "    time_offset_ms: " + formatDouble(it->second) + "  # an image stamped t was exposed at t + offset\n";
    if (const auto it = truth.intrinsics.find(name); it != truth.intrinsics.end())
      s += "    intrinsics: " + formatList(it->second) + "  # fx, fy, cx, cy\n";
    if (const auto it = truth.distortion_coeffs.find(name); it != truth.distortion_coeffs.end())
      s += "    distortion_coeffs: " + formatList(it->second) + "\n";
    if (const auto it = truth.readout_ms.find(name); it != truth.readout_ms.end())
      s += "    readout_ms: " + formatDouble(it->second) +
           "  # row v starts exposing at stamp + v / (rows - 1) * readout\n";
    if (const auto it = truth.exposure_ms.find(name); it != truth.exposure_ms.end())
      s += "    exposure_ms: " + formatDouble(it->second) +
           "  # each row integrates [its start, its start + exposure]\n";
  }
  if (truth.T_link_marker)
    s += "mount:\n  T_link_marker:" + formatMatrixBlock(truth.T_link_marker->matrix(), 4) + "\n";
  if (!truth.joint_offsets_rad.empty()) {
    s += "joint_offsets:  # forward kinematics at q + offset_rad (q as in joints.csv) is the truth\n";
    for (const auto& [joint, o] : truth.joint_offsets_rad)
      s += "  " + yamlScalar(joint) + ": {offset_rad: " + formatDouble(o) + "}\n";
  }
  if (!truth.kinematic_origins.empty()) {
    s += "kinematic_origins:  # the real leg: each joint's URDF origin times Exp(correction), [wx wy wz vx vy vz]\n";
    for (const auto& [joint, u] : truth.kinematic_origins)
      s += "  " + yamlScalar(joint) + ": {correction: " + formatList(u) + "}\n";
  }
  if (!truth.backlash_rad.empty()) {
    s += "backlash:  # dead zone between the motor (joints.csv) and the joint; moving, the joint lags by rad / 2\n";
    for (const auto& [joint, b] : truth.backlash_rad)
      s += "  " + yamlScalar(joint) + ": {rad: " + formatDouble(b) + "}\n";
  }
  if (truth.encoder_resolution_rad)
    s += "encoder_resolution_rad: " + formatDouble(*truth.encoder_resolution_rad) +
         "  # joints.csv readings are multiples of it\n";
  return s;
}

GroundTruth parseGroundTruth(const std::string& text, const std::string& file) {
  const YNode root = detail::parseYaml(text, file);
  root.requireMap("a mapping with keys cameras and (optionally) mount and joint_offsets");
  GroundTruth gt;
  const YNode cams = root.at("cameras", "a mapping camera name -> {T_base_cam}");
  cams.requireMap("a mapping camera name -> {T_base_cam}");
  for (auto it = cams.node.begin(); it != cams.node.end(); ++it) {
    const std::string name = it->first.Scalar();
    const YNode n{it->second, file, cams.childPath(name)};
    n.requireMap("a mapping with key T_base_cam");
    gt.T_base_cam[name] = n.at("T_base_cam", "the true camera pose in the base frame, 4x4").transform();
    if (const YNode t = n.maybe("time_offset_ms"); t.node.IsDefined()) gt.time_offset_ms[name] = t.number();
    if (const YNode k = n.maybe("intrinsics"); k.node.IsDefined()) {
      if (k.listSize("4 numbers fx, fy, cx, cy") != 4) k.fail("expected 4 numbers fx, fy, cx, cy, got " + k.found());
      gt.intrinsics[name] = k.numbers();
    }
    if (const YNode d = n.maybe("distortion_coeffs"); d.node.IsDefined()) gt.distortion_coeffs[name] = d.numbers();
    if (const YNode r = n.maybe("readout_ms"); r.node.IsDefined()) gt.readout_ms[name] = r.number();
    if (const YNode e = n.maybe("exposure_ms"); e.node.IsDefined()) gt.exposure_ms[name] = e.number();
  }
  // The mount: fgcal's own spelling (mount.T_link_marker, as calibration.yaml)
  // or rig.yaml's (robot.T_link_marker), which other generators write.
  const YNode m = root.maybe("mount");
  if (m.node.IsDefined()) {
    m.requireMap("a mapping with key T_link_marker");
    gt.T_link_marker = m.at("T_link_marker", "the true board pose in its link, 4x4").transform();
  }
  const YNode robot = root.maybe("robot");
  if (robot.node.IsDefined() && robot.node.IsMap()) {
    if (const YNode r = robot.maybe("T_link_marker"); r.node.IsDefined()) {
      const SE3 T = r.transform();
      if (gt.T_link_marker && !(gt.T_link_marker->matrix() - T.matrix()).isZero(1e-12))
        r.fail("expected the same mount as mount.T_link_marker, or only one of the two; they differ");
      gt.T_link_marker = T;
    }
  }
  const YNode joints = root.maybe("joint_offsets");
  if (joints.node.IsDefined()) {
    joints.requireMap("a mapping joint name -> {offset_rad}");
    for (auto it = joints.node.begin(); it != joints.node.end(); ++it) {
      const std::string joint = it->first.Scalar();
      const YNode j{it->second, file, joints.childPath(joint)};
      j.requireMap("a mapping with key offset_rad");
      gt.joint_offsets_rad[joint] = j.at("offset_rad", "the true zero offset in radians").number();
    }
  }
  // The same key as calibration.yaml's; a result read as truth has more keys per joint.
  const YNode origins = root.maybe("kinematic_origins");
  if (origins.node.IsDefined()) {
    origins.requireMap("a mapping joint name -> {correction}");
    for (auto it = origins.node.begin(); it != origins.node.end(); ++it) {
      const std::string joint = it->first.Scalar();
      const YNode j{it->second, file, origins.childPath(joint)};
      j.requireMap("a mapping with key correction");
      const YNode c = j.at("correction", "6 numbers [wx wy wz vx vy vz]");
      const std::vector<double> v = c.numbers();
      if (v.size() != 6) c.fail("expected 6 numbers [wx wy wz vx vy vz], got " + std::to_string(v.size()));
      gt.kinematic_origins[joint] = Vec6(Eigen::Map<const Vec6>(v.data()));
    }
  }
  // calibration.yaml's key too; a result read as truth has a sigma per joint.
  const YNode backlash = root.maybe("backlash");
  if (backlash.node.IsDefined()) {
    backlash.requireMap("a mapping joint name -> {rad}");
    for (auto it = backlash.node.begin(); it != backlash.node.end(); ++it) {
      const std::string joint = it->first.Scalar();
      const YNode j{it->second, file, backlash.childPath(joint)};
      j.requireMap("a mapping with key rad");
      gt.backlash_rad[joint] = j.at("rad", "the true backlash in radians").number();
    }
  }
  if (const YNode r = root.maybe("encoder_resolution_rad"); r.node.IsDefined()) gt.encoder_resolution_rad = r.number();
  return gt;
}

GroundTruth loadGroundTruth(const std::string& path) {
  return parseGroundTruth(readTextFile(path, "ground truth"), path);
}

namespace detail {

std::vector<JointOffsetResult> readJointVector(const YNode& root, const char* field, const char* value,
                                               const char* what) {
  std::vector<JointOffsetResult> out;
  const YNode jo = root.maybe(field);
  if (!jo.node.IsDefined()) return out;
  jo.requireMap(std::string("a mapping joint -> {") + value + ", sigma_rad, observed}");
  for (auto it = jo.node.begin(); it != jo.node.end(); ++it) {
    JointOffsetResult j;
    j.joint = it->first.Scalar();
    const YNode n{it->second, root.file, jo.childPath(j.joint)};
    n.requireMap(std::string("a mapping with keys ") + value + ", sigma_rad, observed");
    j.offset_rad = n.at(value, what).number();
    j.sigma_rad = n.at("sigma_rad", "its 1-sigma, radians").nonNegative();
    const YNode ob = n.maybe("observed");
    if (ob.node.IsDefined()) j.observed = ob.boolean();
    out.push_back(std::move(j));
  }
  return out;
}

}  // namespace detail

}  // namespace fgcal::apps
