// --urdf-out, --kalibr-out and --tf-out of `fgcal calibrate` (see robot_outputs.hpp).
#include "fgcal/apps/robot_outputs.hpp"

#include <cstdio>
#include <filesystem>
#include <map>

#include "fgcal/apps/camchain.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/tf_launch.hpp"
#include "io/text_format.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

namespace {

void checkOutputPath(const std::string& path, const std::string& option) {
  std::error_code ec;
  const fs::path folder = fs::absolute(path, ec).parent_path();
  if (!fs::is_directory(folder, ec))
    throw InputError(path, option, "the output folder " + folder.string() + " does not exist; create it first");
  if (fs::is_directory(path, ec)) throw InputError(path, option, "expected an output file path, got a folder");
}

std::string sameFile(const std::string& path) {
  std::error_code ec;
  return fs::absolute(path, ec).lexically_normal().string();
}

}  // namespace

RobotOutputPlan planRobotOutputs(const RobotOutputOptions& options, const RigConfig& rig, const std::string& rig_path,
                                 const std::vector<std::string>& other_outputs) {
  RobotOutputPlan plan;
  plan.options = options;
  plan.base_link = rig.robot.base_link;
  plan.cameras = rig.cameras;
  std::map<std::string, std::string> used;  // normalized path -> what uses it ("--tf-out a.launch")
  for (const auto& o : other_outputs)
    if (!o.empty()) used.emplace(sameFile(o), o);
  std::vector<std::pair<std::string, std::string>> outputs{{options.urdf_out, "--urdf-out"},
                                                         {options.kalibr_out, "--kalibr-out"}};
  for (const std::string& path : options.tf_outs) outputs.emplace_back(path, "--tf-out");
  for (const auto& [path, option] : outputs) {
    if (path.empty()) {
      if (option == "--tf-out") throw InputError(path, option, "expected a launch file path, got an empty one");
      continue;
    }
    checkOutputPath(path, option);
    if (option == "--tf-out" && !launchFlavorFor(path))
      throw InputError(path, option, std::string("expected a launch file ending in ") + kLaunchExtensions);
    const auto [it, fresh] = used.emplace(sameFile(path), option + " " + path);
    if (!fresh)
      throw InputError(path, option, "expected a file of its own, but " + it->second + " is written there too");
  }
  if (!options.urdf_out.empty()) {
    std::vector<UrdfCameraFrame> frames;
    for (const CameraConfig& c : rig.cameras)
      if (!c.frame.empty()) frames.push_back({c.name, c.frame, c.urdf_joint, cameraField(c.name)});
    if (frames.empty()) {
      const std::string field = cameraField(rig.cameras.front().name, "frame");
      throw InputError(rig_path, field,
                       "missing; --urdf-out expected at least one camera with a frame: field (the URDF link of its "
                       "optical frame), and none of the calibrated cameras has one. fgcal init writes a suggested "
                       "'# frame: LINK' line per camera: check the link and remove the '# ' (docs/formats.md, "
                       "\"Starting a rig.yaml\")" + rig.lineSuffix(cameraField(rig.cameras.front().name)));
    }
    if (sameFile(options.urdf_out) == sameFile(rig.robot.urdf))
      throw InputError(options.urdf_out, "--urdf-out",
                       "expected another file than the robot description it is made from (" + rig.robot.urdf +
                           "); write a copy and replace the original yourself");
    const std::string text = readTextFile(rig.robot.urdf, "URDF (robot description)");
    try {
      plan.urdf = planUrdfUpdate(text, rig.robot.urdf, rig.robot.base_link, frames, rig_path);
    } catch (const InputError& e) {
      if (e.file() != rig_path) throw;
      throw InputError(e.file(), e.location(), e.detail() + rig.lineSuffix(e.location()));
    }
  }
  if (!options.tf_outs.empty()) {
    if (const std::string p = frameIdProblem(rig.robot.base_link); !p.empty())
      throw InputError(rig_path, "robot.base_link", p + "; got '" + rig.robot.base_link + "'" +
                                                        rig.lineSuffix("robot.base_link"));
    for (const CameraConfig& c : rig.cameras)
      if (const std::string p = frameIdProblem(c.frame.empty() ? c.name : c.frame); !p.empty())
        throw InputError(rig_path, cameraField(c.name, "frame"),
                         p + "; got '" + (c.frame.empty() ? c.name : c.frame) + "'" +
                             rig.lineSuffix(cameraField(c.name, "frame")));
  }
  return plan;
}

RobotOutputFiles robotOutputFiles(const RobotOutputPlan& plan, const CalibrationOutput& out) {
  RobotOutputFiles res;
  std::map<std::string, SE3> T_base_cam;
  for (const CameraResult& c : out.cameras) T_base_cam[c.name] = c.T_base_cam;
  std::vector<const CameraConfig*> cams;  // calibrated cameras in rig order
  for (const CameraConfig& c : plan.cameras)
    if (T_base_cam.count(c.name)) cams.push_back(&c);

  if (!plan.options.urdf_out.empty()) {
    const UrdfUpdateResult u = applyUrdfUpdate(plan.urdf, T_base_cam);
    res.files.emplace_back(plan.options.urdf_out, u.text);
    std::string joints;
    for (const UrdfJointEdit& e : plan.urdf.edits) joints += (joints.empty() ? "" : ", ") + e.camera + " -> " + e.joint;
    char figures[160];
    std::snprintf(figures, sizeof(figures), "max %.1e m, %.1e rad (tolerance %.0e)", u.max_translation_error_m,
                  u.max_rotation_error_rad, kUrdfCheckTolerance);
    res.summary += "  URDF check: " + plan.options.urdf_out + " re-parsed, the chains " + plan.base_link +
                   " -> frame of " + std::to_string(u.cameras_checked) + " camera(s) equal the calibration: " +
                   figures + "; joints updated: " + joints + "\n";
  }
  if (!plan.options.kalibr_out.empty()) {
    std::vector<CamchainCamera> chain;
    for (const CameraConfig* c : cams) {
      CamchainCamera k;
      k.name = c->name;
      k.camera_model = c->camera_model;
      k.intrinsics = c->intrinsics;
      k.distortion_model = c->distortion_model;
      k.distortion_coeffs = c->distortion_coeffs;
      k.resolution = c->resolution;
      k.rostopic = c->topic;  // empty for a folder dataset: Kalibr then has no rostopic line
      k.T_cam0_cam = T_base_cam.at(cams.front()->name).inverse() * T_base_cam.at(c->name);
      chain.push_back(k);
    }
    res.files.emplace_back(plan.options.kalibr_out, formatKalibrCamchain(chain));
    res.summary += "  Kalibr camchain: " + plan.options.kalibr_out + " (" + std::to_string(chain.size()) +
                   " camera(s), cam0 = " + (chain.empty() ? std::string("-") : chain.front().name) + ")\n";
  }
  if (!plan.options.tf_outs.empty()) {
    std::vector<StaticTransform> tfs;
    for (const CameraConfig* c : cams)
      tfs.push_back({c->name, plan.base_link, c->frame.empty() ? c->name : c->frame, T_base_cam.at(c->name)});
    for (const std::string& path : plan.options.tf_outs) {
      const LaunchFlavor flavor = *launchFlavorFor(path);  // planRobotOutputs checked it
      res.files.emplace_back(path, formatStaticTfLaunch(tfs, flavor));
      res.summary += "  static transforms: " + path + " (" + launchFlavorName(flavor) + ", " +
                     std::to_string(tfs.size()) + " camera(s) in " + plan.base_link + ")\n";
    }
  }
  return res;
}

}  // namespace fgcal::apps
