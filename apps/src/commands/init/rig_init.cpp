// fgcal init: a commented starter rig.yaml (see rig_init.hpp). The text is
// written here rather than by writeRigConfig because the comments are the
// point: each default says what it means and what to measure or change.
#include "fgcal/apps/rig_init.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <set>

#include "commands/init/rig_init_bag.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/intrinsics_import.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/urdf_update.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/charuco_target.hpp"
#include "io/text_format.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

using detail::formatDouble;
using detail::joinNames;
using detail::yamlScalar;

namespace {

constexpr const char* kBoardForm =
    "SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY in metres, e.g. 5x7:0.04:0.03:DICT_4X4_50";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool parseWholeInt(const std::string& s, int* out) {
  if (s.empty() || s.size() > 6 || !std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); }))
    return false;
  *out = std::stoi(s);
  return true;
}

bool parseNumber(const std::string& s, double* out) {
  try {
    std::size_t used = 0;
    *out = std::stod(s, &used);
    return used == s.size() && std::isfinite(*out);
  } catch (const std::exception&) {
    return false;
  }
}

// Valid rig.yaml camera names (rig_config.hpp): they also name image folders.
bool validCameraName(const std::string& s) {
  return !s.empty() && s[0] != '.' && std::all_of(s.begin(), s.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-' || c == '.';
  });
}

const char* fileKind(const std::string& text_of_file) {
  if (text_of_file.find("!!opencv-matrix") != std::string::npos) return "OpenCV calibration file";
  if (text_of_file.find("camera_matrix") != std::string::npos) return "ROS camera_info file";
  return "Kalibr camchain";
}

// The URDF link a camera named `name` most likely means, tried in this order:
// the name itself, then the optical-frame names ROS drivers and URDFs use.
std::string linkForCamera(const kinematics::RobotModel& model, const std::string& name, std::string* how) {
  const std::vector<std::string> suffixes = {"",        "_optical_frame", "_color_optical_frame", "_optical",
                                             "_frame",  "_link"};
  for (const auto& suffix : suffixes) {
    if (model.hasLink(name + suffix)) {
      *how = suffix.empty() ? "the URDF link named like the camera" : "the URDF link named '" + name + suffix + "'";
      return name + suffix;
    }
  }
  return "";
}

// The camera's body in the URDF, named like its frame_id or name without the
// optical suffix ("front_cam_optical_frame" -> "front_cam", "front_cam_link").
std::string cadLinkOf(const kinematics::RobotModel& model, const std::string& hint) {
  std::string stem = hint;
  for (const char* suffix : {"_color_optical_frame", "_optical_frame", "_optical", "_frame", "_link"}) {
    const std::string sfx(suffix);
    if (stem.size() > sfx.size() && stem.compare(stem.size() - sfx.size(), sfx.size(), sfx) == 0) {
      stem.erase(stem.size() - sfx.size());
      break;
    }
  }
  for (const std::string& name : {stem, stem + "_link", stem + "_frame", stem + "_camera"})
    if (!name.empty() && model.hasLink(name)) return name;
  return "";
}

// The link's pose in the base link with every movable joint at zero, or
// nothing when no chain reaches it (a floating joint between them).
std::optional<SE3> poseInBase(const kinematics::RobotModel& model, const std::string& base, const std::string& link) {
  try {
    const kinematics::KinematicChain chain = model.chain(base, link);
    return chain.forward(VecX::Zero(static_cast<Eigen::Index>(chain.jointNames().size())));
  } catch (const kinematics::KinematicsError&) {
    return std::nullopt;
  }
}

// The rotation of an optical frame in its camera body's frame (REP 103 /
// REP 105): z forward along the body's x, x right (the body's -y), y down
// (the body's -z).
bool hasOpticalRotation(const SE3& T_parent_child) {
  Mat3 R_opt;
  R_opt << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return (T_parent_child.rotation() - R_opt).cwiseAbs().maxCoeff() < 1e-3;
}

// Cameras from --camera-info NAME:FILE / FILE arguments.
std::vector<InitCamera> camerasFromFiles(const std::vector<std::string>& args, const kinematics::RobotModel& model) {
  std::vector<InitCamera> out;
  for (const std::string& arg : args) {
    std::string name, file = arg;
    const auto colon = arg.find(':');
    if (colon != std::string::npos && !fs::exists(arg)) {
      name = arg.substr(0, colon);
      file = arg.substr(colon + 1);
      if (!validCameraName(name) || file.empty())
        throw InputError(arg, "--camera-info",
                         "expected NAME:FILE (NAME of letters, digits, '_', '-', '.') or FILE, got '" + arg + "'");
    }
    const std::string text = readTextFile(file, "camera-info file");
    std::vector<CameraConfig> cams = parseIntrinsics(text, file, kInitPixelSigma, name.empty() ? "cam0" : name);
    if (!name.empty()) {
      const auto it = std::find_if(cams.begin(), cams.end(), [&](const CameraConfig& c) { return c.name == name; });
      if (it != cams.end()) {
        cams = {*it};
      } else if (cams.size() == 1) {
        cams[0].name = name;
      } else {
        std::vector<std::string> names;
        for (const auto& c : cams) names.push_back(c.name);
        throw InputError(file, "--camera-info " + arg,
                         "the file holds " + std::to_string(cams.size()) + " cameras (" + joinNames(names) +
                             ") and none is named '" + name + "'; give NAME as one of them, or FILE alone for all");
      }
    }
    for (auto& c : cams) {
      InitCamera ic;
      ic.camera = c;
      ic.source = file + " (" + fileKind(text) + ")";
      ic.intrinsics_file = file;
      std::string how;
      ic.frame = linkForCamera(model, c.name, &how);
      ic.frame_hint = c.name;
      ic.frame_note = ic.frame.empty() ? "no URDF link is named like camera '" + c.name + "' (or " + c.name +
                                             "_optical_frame)"
                                       : how;
      out.push_back(std::move(ic));
    }
  }
  return out;
}

// The links walked from base to tip with the joints between them.
void describeChain(const kinematics::RobotModel& model, const std::string& base, const std::string& tip,
                   InitPlan& plan) {
  const kinematics::KinematicChain chain = model.chain(base, tip);  // refuses floating/planar joints
  plan.chain_joints = chain.jointNames();
  std::map<std::string, std::size_t> joint_index;
  for (std::size_t i = 0; i < model.joints().size(); ++i) joint_index[model.joints()[i].name] = i;
  auto parentJoint = [&](const std::string& link) -> const kinematics::JointInfo* {
    const std::string& j = model.link(link).parent_joint;
    return j.empty() ? nullptr : &model.joints()[joint_index.at(j)];
  };
  std::vector<std::string> base_up{base};  // base and its ancestors
  for (auto* j = parentJoint(base); j; j = parentJoint(j->parent_link)) base_up.push_back(j->parent_link);
  std::vector<const kinematics::JointInfo*> down;  // tip up to the common ancestor
  std::string l = tip;
  while (std::find(base_up.begin(), base_up.end(), l) == base_up.end()) {
    const auto* j = parentJoint(l);
    down.push_back(j);
    l = j->parent_link;
  }
  plan.chain_lines.push_back(base);
  for (const std::string& up : base_up) {
    if (up == l) break;
    const auto* j = parentJoint(up);
    plan.chain_lines.push_back("  <- " + j->name + " (" + kinematics::toString(j->type) + ", walked upward) -- " +
                               j->parent_link);
  }
  for (auto it = down.rbegin(); it != down.rend(); ++it)
    plan.chain_lines.push_back("  -- " + (*it)->name + " (" + kinematics::toString((*it)->type) + ") --> " +
                               (*it)->child_link);
}

// A path as rig.yaml gives it: relative to the rig.yaml's folder when both sit under one top-level folder
// (a project tree moved as a whole keeps working), absolute otherwise.
std::string relativePathFor(const std::string& path, const std::string& output) {
  const fs::path abs = fs::absolute(path).lexically_normal();
  fs::path folder = fs::path(output).parent_path();
  if (folder.empty()) folder = ".";
  const fs::path abs_folder = fs::absolute(folder).lexically_normal();
  auto top = [](const fs::path& p) {
    auto it = p.begin();
    if (it != p.end()) ++it;  // the root "/"
    return it == p.end() ? fs::path() : *it;
  };
  if (top(abs) != top(abs_folder)) return abs.string();
  const fs::path rel = abs.lexically_relative(abs_folder);
  return rel.empty() ? abs.string() : rel.string();
}

std::string listOf(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + formatDouble(v[i]);
  return s + "]";
}

/// robot: the URDF, the chain, the mount placeholder and the noise defaults.
std::string robotLines(const InitOptions& o, const InitPlan& p) {
  std::string s;
  s += "robot:\n";
  s += "  urdf: " + detail::yamlQuoted(relativePathFor(o.urdf, o.output)) + "\n";
  s += "  base_link: " + yamlScalar(o.base_link) + "\n";
  s += "  marker_link: " + yamlScalar(o.marker_link) + "  # the link the board is fixed to\n";
  s += "  # Chain " + o.base_link + " -> " + o.marker_link + ", movable joints (joints.csv needs them): " +
       (p.chain_joints.empty() ? std::string("none") : joinNames(p.chain_joints)) + "\n";
  s += "  # CHECK: the board frame in marker_link (OpenCV's ChArUco frame: origin at the top-left\n";
  s += "  # corner of the printed board, x right, y down, z into the board), 4x4 row-major, metres.\n";
  s += "  # Identity is a placeholder: measure it (CAD or ruler); mount_sigma says how well you did.\n";
  s += "  T_link_marker:\n";
  s += "    - [1.0, 0.0, 0.0, 0.0]\n    - [0.0, 1.0, 0.0, 0.0]\n    - [0.0, 0.0, 1.0, 0.0]\n    - [0.0, 0.0, 0.0, 1.0]\n";
  s += "  # Prior std of that mount: metres, radians. The calibration estimates the mount; a\n";
  s += "  # CAD value deserves [0.001, 0.01], a hand measurement the default; [0, 0] holds it fixed.\n";
  s += "  mount_sigma: [" + formatDouble(kInitMountSigmaM) + ", " + formatDouble(kInitMountSigmaRad) + "]\n";
  s += "  encoder_sigma: " + formatDouble(kInitEncoderSigma) +
       "  # joint reading noise std, radians (metres for prismatic); or a map joint: sigma\n";
  s += "  # The URDF's tolerance: 1-sigma error per axis of each joint origin on the chain above,\n";
  s += "  # [metres, radians]. A camera pose in the base frame is measured through the leg, so its\n";
  s += "  # sigma includes this; relative poses between cameras do not. A CAD URDF is good to about\n";
  s += "  # this; a leg calibrated by its maker may deserve less. Remove the line to take the URDF as exact.\n";
  s += "  kinematic_sigma: [" + formatDouble(kInitKinematicSigmaM) + ", " + formatDouble(kInitKinematicSigmaRad) +
       "]\n";
  return s;
}

/// target: from --board.
std::string targetLines(const InitOptions& o, const InitPlan& p) {
  std::string s;
  s += "target:  # from --board " + o.board + "\n";
  s += "  type: charuco\n";
  s += "  squares_x: " + std::to_string(p.target.squares_x) + "\n";
  s += "  squares_y: " + std::to_string(p.target.squares_y) + "\n";
  s += "  square_size: " + formatDouble(p.target.square_size) + "  # metres: CHECK on the printed board\n";
  s += "  marker_size: " + formatDouble(p.target.marker_size) + "  # metres\n";
  s += "  dictionary: " + yamlScalar(p.target.dictionary) + "\n";
  return s;
}

/// A camera's `frame:`, or why it is left out with the URDF's optical frames.
std::string frameLines(const InitCamera& ic) {
  std::string s;
  if (ic.frame.empty()) {
    s += "    # CHECK frame: left out: " + ic.frame_note + ".\n";
    s += "    # calibrate --urdf-out needs the URDF link of this camera's optical frame (z forward,\n";
    s += "    # x right, y down).\n";
    if (ic.frame_candidates.empty()) {
      s += "    # The URDF has no link named *optical* or turned like an optical frame: add one to the\n";
      s += "    # URDF, or calibrate without --urdf-out.\n";
    } else {
      const std::size_t shown = std::min<std::size_t>(ic.frame_candidates.size(), 6);
      s += "    # Optical frames of the URDF (" + ic.frame_candidates_note + "):\n    #   " +
           joinNames({ic.frame_candidates.begin(), ic.frame_candidates.begin() + static_cast<std::ptrdiff_t>(shown)}) +
           (shown < ic.frame_candidates.size() ? ", ... (" + std::to_string(ic.frame_candidates.size()) + " in all)" : "") +
           "\n";
    }
    if (!ic.suggested_frame.empty()) {
      s += "    # Before --urdf-out, remove the '# ' in front of frame: below, once the link is checked\n";
      s += "    # to be this camera's (or put the right link there):\n";
      s += "    # frame: " + yamlScalar(ic.suggested_frame) + "\n";
    }
  } else {
    s += "    frame: " + yamlScalar(ic.frame) + "  # " + ic.frame_note +
         "; CHECK it is the optical frame (z forward, x right, y down)\n";
  }
  return s;
}

/// A camera's model and intrinsics: the values, or intrinsics_file with
/// the values it holds as comments.
std::string intrinsicsLines(const InitOptions& o, const InitCamera& ic) {
  const CameraConfig& c = ic.camera;
  std::string s;
  s += "    camera_model: " + yamlScalar(c.camera_model) + "\n";
  // With intrinsics_file the group is read from the file at load time and
  // must not be repeated here (rig_config.hpp); the values are shown as
  // comments so the file still says what the camera is.
  const std::string group = ic.intrinsics_file.empty() ? "    " : "    #   ";
  if (ic.intrinsics_file.empty() && !ic.camera_info_topic.empty())
    s += "    # The numbers below are the topic's first camera_info; remove them (distortion_model to\n"
         "    # resolution) to take the camera_info of the bag being calibrated instead.\n";
  if (!ic.intrinsics_file.empty()) {
    s += "    intrinsics_file: " + detail::yamlQuoted(relativePathFor(ic.intrinsics_file, o.output)) +
         "  # intrinsics, distortion and resolution, read when rig.yaml is loaded\n";
    s += "    # which holds (to keep the values in this file instead, uncomment these and remove intrinsics_file):\n";
  }
  s += group + "distortion_model: " + yamlScalar(c.distortion_model) +
       "  # radtan [k1, k2, p1, p2] | equidistant [k1..k4] | none []\n";
  s += group + "intrinsics: [" + formatDouble(c.intrinsics[0]) + ", " + formatDouble(c.intrinsics[1]) + ", " +
       formatDouble(c.intrinsics[2]) + ", " + formatDouble(c.intrinsics[3]) + "]  # fx, fy, cx, cy (pixels)\n";
  s += group + "distortion_coeffs: " + listOf(c.distortion_coeffs) + "\n";
  s += group + "resolution: [" + std::to_string(c.resolution[0]) + ", " + std::to_string(c.resolution[1]) + "]\n";
  return s;
}

/// One camera's entry of `cameras:`.
std::string cameraLines(const InitOptions& o, const InitCamera& ic) {
  const CameraConfig& c = ic.camera;
  std::string s;
  s += "  - name: " + yamlScalar(c.name) + "  # intrinsics from " + ic.source + "\n";
  if (!ic.topic_note.empty()) s += "    # " + ic.topic_note + "\n";
  if (!ic.topic.empty()) s += "    topic: " + yamlScalar(ic.topic) + "\n";
  if (!ic.camera_info_topic.empty()) s += "    camera_info_topic: " + yamlScalar(ic.camera_info_topic) + "\n";
  s += frameLines(ic);
  if (!ic.urdf_joint.empty())
    s += "    # urdf_joint: " + yamlScalar(ic.urdf_joint) + "  # the joint --urdf-out updates for this frame by default;\n"
         "    # set it to update another joint of this camera's own branch.\n";
  else if (!ic.urdf_joint_note.empty())
    s += "    # CHECK before --urdf-out: " + ic.urdf_joint_note +
         ". Set each camera's urdf_joint: to a joint of its own branch.\n";
  s += intrinsicsLines(o, ic);
  s += "    pixel_sigma: " + formatDouble(c.pixel_sigma) + "  # corner noise std, pixels\n";
  return s;
}

std::string renderRig(const InitOptions& o, const InitPlan& p) {
  std::string s;
  s += "# fgcal rig description, written by `fgcal init` as a starting point: check every\n";
  s += "# value marked CHECK before calibrating (docs/formats.md). Paths are\n";
  s += "# relative to this file's folder.\n";
  if (!p.joint_states_topic.empty() || !p.joint_states_note.empty()) {
    if (!p.joint_states_note.empty()) s += "# " + p.joint_states_note + "\n";
    if (!p.joint_states_topic.empty())
      s += "joint_states_topic: " + yamlScalar(p.joint_states_topic) + "  # sensor_msgs/JointState in the bag\n";
  }
  s += robotLines(o, p);
  s += targetLines(o, p);
  s += "cameras:\n";
  for (const InitCamera& ic : p.cameras) s += cameraLines(o, ic);
  s += "# Images closer in time than this share one board pose (several cameras at one instant).\n";
  s += "sync_tolerance_ms: " + formatDouble(kDefaultSyncToleranceMs) + "\n";
  return s;
}

}  // namespace

TargetConfig parseBoardSpec(const std::string& spec) {
  auto bad = [&](const std::string& why) -> InputError {
    return InputError("", "--board", "expected " + std::string(kBoardForm) + "; got '" + spec + "' (" + why + ")");
  };
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t pos; (pos = spec.find(':', start)) != std::string::npos; start = pos + 1)
    parts.push_back(spec.substr(start, pos - start));
  parts.push_back(spec.substr(start));
  if (parts.size() != 4) throw bad(std::to_string(parts.size()) + " ':'-separated parts instead of 4");
  TargetConfig t;
  const auto x = parts[0].find_first_of("xX");
  if (x == std::string::npos || !parseWholeInt(parts[0].substr(0, x), &t.squares_x) ||
      !parseWholeInt(parts[0].substr(x + 1), &t.squares_y))
    throw bad("squares '" + parts[0] + "' are not two whole numbers joined by 'x'");
  if (!parseNumber(parts[1], &t.square_size)) throw bad("square size '" + parts[1] + "' is not a number");
  if (!parseNumber(parts[2], &t.marker_size)) throw bad("marker size '" + parts[2] + "' is not a number");
  t.dictionary = parts[3];
  vision::CharucoTarget v;
  v.squares_x = t.squares_x;
  v.squares_y = t.squares_y;
  v.square_size = t.square_size;
  v.marker_size = t.marker_size;
  v.dictionary = t.dictionary;
  try {
    v.validate();
  } catch (const std::exception& e) {
    throw bad(e.what());
  }
  return t;
}

std::vector<std::string> nearestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t count) {
  return closestNames(name, candidates, count);
}

std::vector<OpticalFrameCandidate> opticalFrameCandidates(const kinematics::RobotModel& model,
                                                          const std::string& base_link,
                                                          const std::string& camera_hint) {
  const std::string cad = cadLinkOf(model, camera_hint);
  const std::optional<SE3> cad_pose = cad.empty() ? std::nullopt : poseInBase(model, base_link, cad);
  std::vector<OpticalFrameCandidate> out;
  for (const kinematics::LinkInfo& l : model.links()) {
    if (l.parent_joint.empty() || l.name == base_link) continue;
    OpticalFrameCandidate c;
    c.link = l.name;
    c.named_optical = lower(l.name).find("optical") != std::string::npos;
    c.optical_rotation = hasOpticalRotation(model.joint(l.parent_joint).T_parent_joint);
    if (!c.named_optical && !c.optical_rotation) continue;
    if (cad_pose) {
      const std::optional<SE3> pose = poseInBase(model, base_link, l.name);
      if (!pose) continue;
      c.distance_m = (pose->translation() - cad_pose->translation()).norm();
    }
    out.push_back(std::move(c));
  }
  auto kind = [](const OpticalFrameCandidate& c) { return c.named_optical && c.optical_rotation ? 0 : c.named_optical ? 1 : 2; };
  std::stable_sort(out.begin(), out.end(), [&](const OpticalFrameCandidate& a, const OpticalFrameCandidate& b) {
    // Within a millimetre the kind decides: a camera body's optical frame and its
    // other frames often share one origin.
    if (cad_pose && std::abs(a.distance_m - b.distance_m) > 1e-3) return a.distance_m < b.distance_m;
    return kind(a) < kind(b);
  });
  return out;
}

namespace {

// For each camera without a frame, the best candidate that --urdf-out could
// update together with the frames already chosen (its own link, and a
// default joint on no other camera's chain); then the joint --urdf-out would
// update for each camera, or why a hand edit is needed before --urdf-out.
void suggestFrames(const InitOptions& o, const kinematics::RobotModel& model, InitPlan& plan) {
  const std::string urdf_text = readTextFile(o.urdf, "URDF");
  auto entry = [](const InitCamera& ic, const std::string& frame) {
    return UrdfCameraFrame{ic.camera.name, frame, "", cameraField(ic.camera.name)};
  };
  auto chosen = [](const InitCamera& ic) -> const std::string& { return ic.frame.empty() ? ic.suggested_frame : ic.frame; };
  auto updatable = [&](const std::vector<UrdfCameraFrame>& frames) {
    try {
      planUrdfUpdate(urdf_text, o.urdf, o.base_link, frames, o.output);
      return true;
    } catch (const std::exception&) {
      return false;
    }
  };
  for (InitCamera& ic : plan.cameras) {
    if (!ic.frame.empty()) continue;
    const auto candidates = opticalFrameCandidates(model, o.base_link, ic.frame_hint);
    for (const auto& c : candidates) ic.frame_candidates.push_back(c.link);
    const std::string cad = cadLinkOf(model, ic.frame_hint);
    ic.frame_candidates_note = !candidates.empty() && candidates.front().distance_m >= 0.0
                                   ? "nearest the camera's CAD link '" + cad + "' first"
                                   : "named *optical* and turned like one first, then named, then turned";
    for (const auto& c : candidates) {
      std::vector<UrdfCameraFrame> frames{entry(ic, c.link)};
      bool taken = false;
      for (const InitCamera& other : plan.cameras) {
        if (&other == &ic || chosen(other).empty()) continue;
        taken = taken || chosen(other) == c.link;
        frames.push_back(entry(other, chosen(other)));
      }
      if (!taken && updatable(frames)) {
        ic.suggested_frame = c.link;
        break;
      }
    }
  }
  std::vector<UrdfCameraFrame> all;
  for (const InitCamera& ic : plan.cameras)
    if (!chosen(ic).empty()) all.push_back(entry(ic, chosen(ic)));
  if (all.empty()) return;
  try {
    const UrdfUpdatePlan up = planUrdfUpdate(urdf_text, o.urdf, o.base_link, all, o.output);
    for (const UrdfJointEdit& e : up.edits)
      for (InitCamera& ic : plan.cameras)
        if (ic.camera.name == e.camera) ic.urdf_joint = e.joint;
  } catch (const InputError& e) {
    const std::string why = e.detail();
    for (InitCamera& ic : plan.cameras)
      if (!ic.frame.empty() || !ic.suggested_frame.empty())
        ic.urdf_joint_note = "calibrate --urdf-out cannot update these frames as they are: " + why;
  } catch (const std::exception& e) {
    for (InitCamera& ic : plan.cameras) ic.urdf_joint_note = std::string("calibrate --urdf-out cannot use this URDF: ") + e.what();
  }
}

}  // namespace

InitPlan planInit(const InitOptions& o) {
  if (o.output.empty()) throw InputError("", "-o", "expected the path of the rig.yaml to write");
  {
    fs::path folder = fs::path(o.output).parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
      throw InputError(o.output, "-o", "output folder " + folder.string() + " does not exist; create it first");
    if (fs::is_directory(o.output, ec)) throw InputError(o.output, "-o", "expected a file path, got a folder");
    if (!o.overwrite && fs::exists(o.output, ec))
      throw InputError(o.output, "-o", "the file exists; pass --force to replace it");
  }
  if (o.bag.empty() && o.camera_infos.empty())
    throw InputError("", "--bag / --camera-info", "expected a bag or at least one --camera-info NAME:FILE");
  if (!o.bag.empty() && !o.camera_infos.empty())
    throw InputError("", "--bag / --camera-info", "expected either a bag or --camera-info files, not both");

  InitPlan plan;
  plan.target = parseBoardSpec(o.board);
  const kinematics::RobotModel model = kinematics::RobotModel::fromFile(o.urdf);
  for (const auto& [link, option] : {std::pair{o.base_link, "--base-link"}, std::pair{o.marker_link, "--marker-link"}}) {
    if (!model.hasLink(link))
      throw InputError(o.urdf, option,
                       "'" + link + "' is not a link of robot '" + model.name() +
                           "'; closest links: " + joinNames(nearestNames(link, model.linkNames())));
  }
  describeChain(model, o.base_link, o.marker_link, plan);
  if (plan.chain_joints.empty())
    plan.warnings.push_back("no movable joint between " + o.base_link + " and " + o.marker_link +
                            ": the board cannot move relative to the base; is --marker-link the foot with the board?");

  if (!o.bag.empty()) {
    detail::BagCameras found = detail::camerasFromBag(o.bag, model);
    plan.cameras = std::move(found.cameras);
    plan.joint_states_topic = found.joint_states_topic;
    plan.joint_states_note = found.joint_states_note;
    for (auto& w : found.warnings) plan.warnings.push_back(std::move(w));
  } else {
    plan.cameras = camerasFromFiles(o.camera_infos, model);
  }
  std::set<std::string> names;
  for (const auto& c : plan.cameras)
    if (!names.insert(c.camera.name).second)
      throw InputError("", "--camera-info",
                       "two cameras are named '" + c.camera.name + "'; give distinct names with NAME:FILE");
  suggestFrames(o, model, plan);

  plan.rig_yaml = renderRig(o, plan);
  // The same reader `fgcal calibrate` uses, on the exact text, with relative
  // paths resolved against the output's folder: what is written loads back.
  fs::path folder = fs::path(o.output).parent_path();
  if (folder.empty()) folder = ".";
  const RigConfig loaded = parseRigConfig(plan.rig_yaml, o.output, folder.string());
  for (const auto& w : loaded.warnings) plan.warnings.push_back(w);
  return plan;
}

InitPlan runInit(const InitOptions& o, std::ostream& out) {
  InitPlan plan = planInit(o);
  writeFileAtomically(o.output, plan.rig_yaml);
  out << "fgcal init: chain " << o.base_link << " -> " << o.marker_link << " (check that this leg carries the board):\n";
  for (const auto& l : plan.chain_lines) out << "  " << l << "\n";
  out << "  movable joints: " << (plan.chain_joints.empty() ? std::string("none") : joinNames(plan.chain_joints))
      << "\n";
  bool edit_needed = false;
  for (const auto& ic : plan.cameras) {
    out << "camera " << ic.camera.name << ": " << ic.camera.distortion_model << ", " << ic.camera.resolution[0] << "x"
        << ic.camera.resolution[1] << ", frame " << (ic.frame.empty() ? "(not found: " + ic.frame_note + ")" : ic.frame);
    if (!ic.topic.empty()) out << ", topic " << ic.topic;
    out << "\n";
    if (ic.frame.empty() && !ic.suggested_frame.empty())
      out << "  suggested frame " << ic.suggested_frame << " (an optical frame of the URDF; others in rig.yaml)\n";
    if (ic.frame.empty() || !ic.urdf_joint_note.empty()) edit_needed = true;
  }
  if (edit_needed)
    out << "before calibrate --urdf-out: edit rig.yaml where it says CHECK frame / CHECK before --urdf-out "
           "(uncomment each camera's '# frame:' line once its link is checked)\n";
  for (const auto& w : plan.warnings) out << "warning: " << w << "\n";
  out << "wrote " << o.output << ": measure T_link_marker and check the values marked CHECK\n";
  return plan;
}

}  // namespace fgcal::apps
