// calibration.yaml's estimated quantities beyond the poses, read for `fgcal
// evaluate` (see evaluate.hpp; keys in docs/outputs.md).
#include <algorithm>
#include <cmath>

#include "fgcal/apps/calibrate_options.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "io/calibration_yaml_read.hpp"
#include "io/text_format.hpp"
#include "io/yaml_read.hpp"

namespace fgcal::apps {

using detail::YNode;

namespace {

double sigmaOf(const YNode& n) {
  const double v = n.anyNumber();
  if (std::isnan(v) || v < 0.0) n.fail("expected a sigma >= 0 (or .inf), got " + n.found());
  return v;
}

// `key` with its sigmas under `sigma_key`, one each; `size` > 0 fixes the count.
std::vector<EstimateWithSigma> valuesWithSigmas(const YNode& cam, const std::string& key, const std::string& sigma_key,
                                                std::size_t size, const std::string& what) {
  const YNode v = cam.at(key, what);
  const std::vector<double> values = v.numbers();
  if (size > 0 && values.size() != size)
    v.fail("expected " + std::to_string(size) + " numbers (" + what + "), got " + v.found());
  const YNode s = cam.at(sigma_key, "the 1-sigma of each of " + key + " (" + std::to_string(values.size()) + ")");
  if (s.listSize("a list of sigmas") != values.size())
    s.fail("expected " + std::to_string(values.size()) + " sigmas, one per value of " + key + ", got " + s.found());
  std::vector<EstimateWithSigma> out;
  for (std::size_t i = 0; i < values.size(); ++i) out.push_back({values[i], sigmaOf(s[i])});
  return out;
}

EstimatedCamera readCamera(const YNode& n) {
  EstimatedCamera c;
  if (n.has("time_offset_ms")) {
    const double v = n.at("time_offset_ms", "").number();
    c.time_offset_ms = EstimateWithSigma{
        v, sigmaOf(n.at("time_offset_sigma_ms", "the 1-sigma of time_offset_ms, milliseconds"))};
  }
  if (n.has("readout_ms") && n.has("readout_sigma_ms")) {
    c.readout_ms = EstimateWithSigma{n.at("readout_ms", "").number(), sigmaOf(n.at("readout_sigma_ms", ""))};
    if (n.has("readout_observed")) c.readout_observed = n.at("readout_observed", "").boolean();
  }
  if (n.has("intrinsics")) c.intrinsics = valuesWithSigmas(n, "intrinsics", "intrinsics_sigma", 4, "fx, fy, cx, cy");
  if (n.has("distortion_coeffs"))
    c.distortion_coeffs =
        valuesWithSigmas(n, "distortion_coeffs", "distortion_coeffs_sigma", 0, "the distortion coefficients");
  return c;
}

// joint_offsets: or backlash: as calibration.yaml's reader reads them, by joint.
std::map<std::string, EstimatedJointOffset> jointsByName(const YNode& root, const char* field, const char* value,
                                                         const char* what) {
  std::map<std::string, EstimatedJointOffset> out;
  for (const JointOffsetResult& j : detail::readJointVector(root, field, value, what))
    out[j.joint] = EstimatedJointOffset{{j.offset_rad, j.sigma_rad}, j.observed};
  return out;
}

// Every quantity `estimated` lists is in the file.
void checkListed(const YNode& root, const EstimatedQuantities& q, const std::vector<std::string>& camera_names) {
  const YNode list = root.at("estimated", "");
  for (std::size_t i = 0; i < q.estimated.size(); ++i) {
    const std::string& e = q.estimated[i];
    const std::vector<std::string>& known = estimateNames();  // --estimate's names
    if (std::find(known.begin(), known.end(), e) == known.end())
      list[i].fail("expected time-offset, joint-offsets, intrinsics, backlash or rolling-shutter, got " +
                   list[i].found());
    if (e == "joint-offsets" && !root.has("joint_offsets"))
      throw InputError(root.file, "joint_offsets", "missing; expected it since `estimated` lists joint-offsets");
    if (e == "backlash" && !root.has("backlash"))
      throw InputError(root.file, "backlash", "missing; expected it since `estimated` lists backlash");
    for (const std::string& cam : camera_names) {
      const auto it = q.cameras.find(cam);
      const bool has_offset = it != q.cameras.end() && it->second.time_offset_ms;
      const bool has_intrinsics = it != q.cameras.end() && !it->second.intrinsics.empty();
      const bool has_readout = it != q.cameras.end() && it->second.readout_ms;
      if ((e == "time-offset" && !has_offset) || (e == "intrinsics" && !has_intrinsics) ||
          (e == "rolling-shutter" && !has_readout))
        throw InputError(root.file,
                         "cameras." + cam +
                             (e == "time-offset" ? ".time_offset_ms"
                                                 : e == "intrinsics" ? ".intrinsics" : ".readout_sigma_ms"),
                         "missing; expected it since `estimated` lists " + e);
    }
  }
}

}  // namespace

EstimatedQuantities parseEstimatedQuantities(const std::string& text, const std::string& file) {
  const YNode root = detail::parseYaml(text, file);
  root.requireMap("a calibration result with keys cameras and mount");
  EstimatedQuantities q;
  if (root.has("method")) q.method = root.at("method", "").string();
  if (root.has("estimated")) {
    const YNode list = root.at("estimated", "");
    const std::size_t n = list.listSize("a list of estimated quantities: time-offset, joint-offsets, intrinsics, backlash, "
                                              "rolling-shutter");
    for (std::size_t i = 0; i < n; ++i) q.estimated.push_back(list[i].string());
  }
  const YNode cams = root.at("cameras", "a mapping camera name -> result");
  cams.requireMap("a mapping camera name -> {T_base_cam, covariance, ...}");
  std::vector<std::string> camera_names;
  for (auto it = cams.node.begin(); it != cams.node.end(); ++it) {
    const std::string name = it->first.Scalar();
    camera_names.push_back(name);
    const YNode n{it->second, file, cams.childPath(name)};
    n.requireMap("a mapping with keys T_base_cam, covariance, images_used, rms_reprojection_px");
    EstimatedCamera c = readCamera(n);
    if (c.time_offset_ms || c.readout_ms || !c.intrinsics.empty() || !c.distortion_coeffs.empty())
      q.cameras[name] = std::move(c);
  }
  q.joint_offsets = jointsByName(root, "joint_offsets", "offset_rad", "the estimated zero offset, radians");
  q.backlash = jointsByName(root, "backlash", "rad", "the estimated gear play, radians");
  if (root.has("estimated")) checkListed(root, q, camera_names);
  return q;
}

}  // namespace fgcal::apps
