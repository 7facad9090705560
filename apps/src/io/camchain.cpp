// Kalibr camchain.yaml writer, reader and relative-pose evaluation (see camchain.hpp).
#include "fgcal/apps/camchain.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"
#include "io/text_format.hpp"
#include "io/yaml_read.hpp"

namespace fgcal::apps {

using detail::formatDouble;
using detail::YNode;

namespace {

// "camN" -> N, or -1 for any other key.
int cameraIndexOfKey(const std::string& key) {
  if (key.size() < 4 || key.compare(0, 3, "cam") != 0) return -1;
  int n = 0;
  for (std::size_t i = 3; i < key.size(); ++i) {
    if (key[i] < '0' || key[i] > '9' || (i == 3 && key[i] == '0' && key.size() > 4)) return -1;
    n = n * 10 + (key[i] - '0');
    if (n > 100000) return -1;
  }
  return n;
}

}  // namespace

std::string formatKalibrCamchain(const std::vector<CamchainCamera>& cameras) {
  std::string s;
  s += "# Kalibr camera chain written by fgcal. T_cn_cnm1 maps points of camera n-1 into camera n\n";
  s += "# (p_cn = T_cn_cnm1 * p_cnm1); metres. fgcal_camera names the camera in fgcal's rig.yaml.\n";
  for (std::size_t n = 0; n < cameras.size(); ++n) {
    const CamchainCamera& c = cameras[n];
    s += "cam" + std::to_string(n) + ":\n";
    if (n > 0) {
      const SE3 T_cn_cnm1 = c.T_cam0_cam.inverse() * cameras[n - 1].T_cam0_cam;
      s += "  T_cn_cnm1:" + detail::formatMatrixBlock(T_cn_cnm1.matrix(), 2) + "\n";
    }
    s += "  camera_model: " + detail::yamlScalar(c.camera_model) + "\n";
    s += "  intrinsics: " +
         detail::formatList(Eigen::Vector4d(c.intrinsics[0], c.intrinsics[1], c.intrinsics[2], c.intrinsics[3])) +
         "  # fu, fv, pu, pv\n";
    s += "  distortion_model: " + detail::yamlScalar(c.distortion_model) + "\n";
    s += "  distortion_coeffs: " + detail::formatList(c.distortion_coeffs) + "\n";
    s += "  resolution: [" + std::to_string(c.resolution[0]) + ", " + std::to_string(c.resolution[1]) + "]\n";
    if (!c.rostopic.empty()) s += "  rostopic: " + detail::yamlQuoted(c.rostopic) + "\n";
    s += "  fgcal_camera: " + detail::yamlQuoted(c.name) + "\n";
  }
  return s;
}

bool looksLikeKalibrCamchain(const std::string& text) {
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap() || root.size() == 0) return false;
    for (auto it = root.begin(); it != root.end(); ++it)
      if (!it->first.IsScalar() || cameraIndexOfKey(it->first.Scalar()) < 0) return false;
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

std::vector<CamchainCamera> parseKalibrCamchain(const std::string& text, const std::string& file) {
  const YNode root = detail::parseYaml(text, file);
  root.requireMap("a Kalibr camera chain: a mapping with keys cam0, cam1, ...");
  std::map<int, YNode> by_index;
  for (auto it = root.node.begin(); it != root.node.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : "";
    const YNode n{it->second, file, key};
    const int idx = cameraIndexOfKey(key);
    if (idx < 0) n.fail("expected only camera keys cam0, cam1, ... at the top level of a camchain, got '" + key + "'");
    by_index.emplace(idx, n);
  }
  if (by_index.empty()) root.fail("expected at least cam0, got an empty mapping");
  std::vector<CamchainCamera> out;
  for (int i = 0; i < static_cast<int>(by_index.size()); ++i) {
    const auto it = by_index.find(i);
    if (it == by_index.end())
      throw InputError(file, "cam" + std::to_string(i),
                       "missing; expected consecutive cameras cam0 .. cam" + std::to_string(by_index.size() - 1));
    const YNode& n = it->second;
    n.requireMap("a camera: camera_model, intrinsics, distortion_model, distortion_coeffs, resolution, ...");
    CamchainCamera c;
    c.name = "cam" + std::to_string(i);
    const YNode name = n.maybe("fgcal_camera");
    if (name.node.IsDefined()) c.name = name.string();
    c.camera_model = n.at("camera_model", "Kalibr's camera model, e.g. pinhole").string();
    const YNode in = n.at("intrinsics", "[fu, fv, pu, pv]");
    const std::size_t nin = in.listSize("[fu, fv, pu, pv]");
    if (c.camera_model == "pinhole" && nin != 4) in.fail("expected 4 numbers [fu, fv, pu, pv] for pinhole, got " + std::to_string(nin));
    if (nin >= 4)
      for (std::size_t k = 0; k < 4; ++k) c.intrinsics[k] = in[nin - 4 + k].number();
    c.distortion_model = n.at("distortion_model", "radtan, equidistant, fov or none").string();
    c.distortion_coeffs = n.at("distortion_coeffs", "the distortion coefficients").numbers();
    const YNode res = n.at("resolution", "[width, height]");
    if (res.listSize("[width, height]") != 2) res.fail("expected 2 integers [width, height]");
    c.resolution = {res[0].integer(1), res[1].integer(1)};
    const YNode topic = n.maybe("rostopic");
    if (topic.node.IsDefined()) c.rostopic = topic.string();
    if (i > 0) {
      const SE3 T_cn_cnm1 =
          n.at("T_cn_cnm1", "the 4x4 transform mapping points of cam" + std::to_string(i - 1) + " into cam" +
                                std::to_string(i))
              .transform();
      c.T_cam0_cam = out.back().T_cam0_cam * T_cn_cnm1.inverse();
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<CamchainCamera> loadKalibrCamchain(const std::string& path) {
  return parseKalibrCamchain(readTextFile(path, "Kalibr camchain"), path);
}

RelativeEvaluation evaluateCamchain(const std::vector<CamchainCamera>& cameras, const GroundTruth& truth,
                                    const std::string& camchain_path) {
  RelativeEvaluation ev;
  std::vector<const CamchainCamera*> matched;
  for (const CamchainCamera& c : cameras) {
    if (truth.T_base_cam.count(c.name))
      matched.push_back(&c);
    else
      ev.unmatched.push_back(c.name);
  }
  if (matched.size() < 2) {
    std::vector<std::string> in_truth;
    for (const auto& [name, T] : truth.T_base_cam) in_truth.push_back(name);
    std::vector<std::string> in_chain;
    for (const auto& c : cameras) in_chain.push_back(c.name);
    throw InputError(camchain_path, "",
                     "a camchain holds only relative poses: expected at least two of its cameras (" +
                         detail::joinNames(in_chain) + ") in the ground truth (" + detail::joinNames(in_truth) +
                         "), matched by fgcal_camera or else by the key camN");
  }
  for (std::size_t a = 0; a < matched.size(); ++a)
    for (std::size_t b = a + 1; b < matched.size(); ++b) {
      const SE3 est = matched[a]->T_cam0_cam.inverse() * matched[b]->T_cam0_cam;
      const SE3 tru = truth.T_base_cam.at(matched[a]->name).inverse() * truth.T_base_cam.at(matched[b]->name);
      ev.pairs.emplace_back("T_" + matched[a]->name + "_" + matched[b]->name,
                            poseError(est, Mat6::Constant(std::nan("")), tru));
    }
  return ev;
}

std::string formatRelativeEvaluationTable(const RelativeEvaluation& ev) {
  std::string s;
  int width = 13;  // "relative pose"; pair names are never cut
  for (const auto& p : ev.pairs) width = std::max(width, static_cast<int>(p.first.size()));
  char line[160];
  std::snprintf(line, sizeof(line), " %8s %8s %8s %9s %9s %9s %9s %9s\n", "x mm", "y mm", "z mm", "roll deg",
                "pitch deg", "yaw deg", "|t| mm", "angle deg");
  s += "relative pose" + std::string(static_cast<std::size_t>(width - 13), ' ') + line;
  for (const auto& [name, e] : ev.pairs) {
    std::snprintf(line, sizeof(line), " %8.3f %8.3f %8.3f %9.4f %9.4f %9.4f %9.3f %9.4f\n", e.x_mm, e.y_mm, e.z_mm,
                  e.roll_deg, e.pitch_deg, e.yaw_deg, e.translation_mm, e.rotation_deg);
    s += name + std::string(static_cast<std::size_t>(width) - name.size(), ' ') + line;
  }
  s += "A Kalibr camchain has no base frame: only the relative poses T_a_b between its cameras are evaluated "
       "(errors in camera a's frame), not the cameras' poses in the base, and without covariance there is no NEES.\n";
  s += "mount: not scored (a Kalibr camchain holds no board mount)\n";
  if (!ev.unmatched.empty())
    s += "Cameras of the camchain without ground truth, not evaluated: " + detail::joinNames(ev.unmatched) + "\n";
  return s;
}

}  // namespace fgcal::apps
