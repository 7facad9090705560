// rig.yaml reader, validator and writer (see rig_config.hpp).
#include "fgcal/apps/rig_config.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/intrinsics_import.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/urdf_update.hpp"
#include "io/text_format.hpp"
#include "io/yaml_read.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

using detail::YNode;

int RigConfig::cameraIndex(const std::string& name) const {
  for (std::size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string RigConfig::lineSuffix(const std::string& field) const {
  for (std::string f = field; !f.empty();) {
    const auto it = field_lines.find(f);
    if (it != field_lines.end() && it->second > 0) return " (line " + std::to_string(it->second) + ")";
    const auto cut = f.find_last_of(".[");
    if (cut == std::string::npos || cut == 0) break;
    f = f.substr(0, cut);
  }
  return "";
}

InputError rigFieldError(const RigConfig& rig, const std::string& field, const std::string& detail) {
  return InputError(rig.source, field, detail + rig.lineSuffix(field));
}

std::string cameraField(const std::string& camera, const std::string& field) {
  return "cameras[" + camera + "]" + (field.empty() ? "" : "." + field);
}

std::string closestNote(const std::string& name, const std::vector<std::string>& candidates, const std::string& what,
                        std::size_t count) {
  if (candidates.empty()) return "";
  return "; closest " + what + ": " + detail::joinNames(closestNames(name, candidates, count));
}

const std::vector<std::string>& supportedCameraModels() {
  static const std::vector<std::string> v{"pinhole"};
  return v;
}

const std::vector<std::string>& supportedDistortionModels() {
  static const std::vector<std::string> v{"radtan", "equidistant", "none"};
  return v;
}

std::vector<double> defaultDistortionSigma(const std::string& model) {
  if (model == "radtan") return {0.1, 0.1, 0.01, 0.01};
  if (model == "equidistant") return {0.1, 0.1, 0.1, 0.1};
  return {};
}

int distortionCoeffCount(const std::string& model) {
  if (model == "radtan" || model == "equidistant") return 4;
  if (model == "none") return 0;
  return -1;
}

namespace {

// A camera name is also a folder name inside the dataset: keep it to
// characters every file system and shell takes as they are.
bool isFolderSafe(const std::string& s) {
  if (s.empty() || s.size() > 128 || s[0] == '.' || s[0] == '-') return false;
  for (const char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

// rig.yaml paths are relative to its own folder.
std::string resolvePath(const std::string& given, const std::string& base_dir) {
  fs::path p(given);
  if (p.is_relative()) p = fs::path(base_dir.empty() ? "." : base_dir) / p;
  return fs::absolute(p).lexically_normal().string();
}

// A value for every joint, or per joint (a map joint -> value): `read`
// reads one value, `one` says what it is ("a number > 0"). Either form fills
// its output; the other is left as it was.
template <class T, class Read>
void readPerJoint(const YNode& n, const std::string& one, Read read, T* all, std::map<std::string, T>* per_joint) {
  const bool map = n.node.IsMap();
  if (map && n.node.size() == 0) n.fail("expected " + one + " or a non-empty map joint -> value, got an empty mapping");
  if (!map) {
    *all = read(n);
    return;
  }
  for (auto it = n.node.begin(); it != n.node.end(); ++it) {
    const std::string joint = it->first.IsScalar() ? it->first.Scalar() : "";
    const YNode v{it->second, n.file, n.childPath(joint)};
    if (joint.empty()) v.fail("expected joint names as keys");
    (*per_joint)[joint] = read(v);
  }
}

// A sigma for every joint (a number > 0) or per joint (a map joint -> sigma > 0).
void readSigmas(const YNode& es, double* all, std::map<std::string, double>* per_joint) {
  readPerJoint(es, "a number > 0", [](const YNode& v) {
    if (!v.node.IsScalar()) v.fail("expected a number > 0 or a map joint -> sigma, got " + v.found());
    return v.positive();
  }, all, per_joint);
}

// robot.kinematic_sigma: [metres, radians] (both > 0), or a map joint -> [metres, radians].
void readKinematicSigma(const YNode& ks, RobotConfig& r) {
  readPerJoint(ks, "[metres, radians]", [](const YNode& v) -> std::array<double, 2> {
    if (!v.node.IsSequence()) v.fail("expected [metres, radians] (both > 0) or a map joint -> [metres, radians], got " + v.found());
    if (v.node.size() != 2) v.fail("expected 2 numbers [metres, radians], got " + std::to_string(v.node.size()));
    return {v[0].positive(), v[1].positive()};
  }, &r.kinematic_sigma, &r.kinematic_sigmas);
}

RobotConfig readRobot(const YNode& root, const std::string& base_dir, std::vector<std::string>& warnings) {
  const YNode n = root.at("robot", "a mapping with keys urdf, base_link, marker_link, T_link_marker, mount_sigma, "
                                   "encoder_sigma");
  n.requireMap("a mapping with keys urdf, base_link, marker_link, T_link_marker, mount_sigma, encoder_sigma");
  n.warnUnknownKeys(
      {"urdf", "base_link", "marker_link", "T_link_marker", "mount_sigma", "encoder_sigma", "joint_offset_sigma",
       "kinematic_sigma", "backlash_sigma"},
      warnings);
  RobotConfig r;
  const std::string urdf = n.at("urdf", "the URDF file path, relative to the dataset folder").string();
  r.urdf = resolvePath(urdf, base_dir);
  r.base_link = n.at("base_link", "the URDF link the cameras are calibrated in (e.g. base_link)").string();
  r.marker_link = n.at("marker_link", "the URDF link the board is fixed to (e.g. lf_foot)").string();
  r.T_link_marker = n.at("T_link_marker", "the board pose in marker_link as a 4x4 matrix").transform();

  const YNode ms = n.at("mount_sigma", "[metres, radians], the prior std of T_link_marker ([0, 0] holds it fixed)");
  const std::size_t nms = ms.listSize("a list [metres, radians]");
  if (nms != 2) ms.fail("expected 2 numbers [metres, radians], got " + std::to_string(nms));
  r.mount_sigma_m = ms[0].nonNegative();
  r.mount_sigma_rad = ms[1].nonNegative();
  if ((r.mount_sigma_m == 0.0) != (r.mount_sigma_rad == 0.0))
    ms.fail("expected both sigmas > 0 (estimate the mount) or both 0 (hold it fixed), got [" +
            detail::formatDouble(r.mount_sigma_m) + ", " + detail::formatDouble(r.mount_sigma_rad) + "]");

  readSigmas(n.at("encoder_sigma", "the encoder noise std in radians (a number, or a map joint -> sigma)"),
             &r.encoder_sigma, &r.encoder_sigmas);
  // Optional: the prior of estimated joint zero offsets (--estimate joint-offsets).
  if (const YNode os = n.maybe("joint_offset_sigma"); os.node.IsDefined())
    readSigmas(os, &r.joint_offset_sigma, &r.joint_offset_sigmas);
  // Optional: the URDF's tolerance on the marker chain's joint origins.
  if (const YNode ks = n.maybe("kinematic_sigma"); ks.node.IsDefined()) readKinematicSigma(ks, r);
  // Optional: the prior of estimated gear backlash (--estimate backlash).
  if (const YNode bs = n.maybe("backlash_sigma"); bs.node.IsDefined())
    readSigmas(bs, &r.backlash_sigma, &r.backlash_sigmas);
  return r;
}

TargetConfig readTarget(const YNode& root, std::vector<std::string>& warnings) {
  const std::string keys = "type, squares_x, squares_y, square_size, marker_size, dictionary";
  const YNode n = root.at("target", "a mapping with keys " + keys);
  n.requireMap("a mapping with keys " + keys);
  n.warnUnknownKeys({"type", "squares_x", "squares_y", "square_size", "marker_size", "dictionary"}, warnings);
  TargetConfig t;
  const YNode type = n.at("type", "the board type: charuco");
  t.type = type.string();
  if (t.type != "charuco") type.fail("expected charuco (the only board type supported), got " + type.found());
  t.squares_x = n.at("squares_x", "the number of chessboard squares along x (>= 2)").integer(2);
  t.squares_y = n.at("squares_y", "the number of chessboard squares along y (>= 2)").integer(2);
  t.square_size = n.at("square_size", "the chessboard square side in metres").positive();
  const YNode ms = n.at("marker_size", "the ArUco marker side in metres");
  t.marker_size = ms.positive();
  if (!(t.marker_size < t.square_size))
    ms.fail("expected a marker smaller than its square (square_size " + detail::formatDouble(t.square_size) +
            " m), got " + ms.found());
  t.dictionary = n.at("dictionary", "an OpenCV predefined dictionary name such as DICT_4X4_50").string();
  return t;
}

// The intrinsics group read from rig.yaml itself (`intrinsics` given).
void readIntrinsicsGroup(const YNode& n, CameraConfig& c, std::vector<std::string>& warnings) {
  const YNode cm = n.at("camera_model", "one of: " + detail::joinNames(supportedCameraModels()));
  c.camera_model = cm.string();
  if (std::find(supportedCameraModels().begin(), supportedCameraModels().end(), c.camera_model) ==
          supportedCameraModels().end())
    cm.fail("expected one of: " + detail::joinNames(supportedCameraModels()) + "; got " + cm.found());

  const YNode dm = n.at("distortion_model", "one of: " + detail::joinNames(supportedDistortionModels()));
  c.distortion_model = dm.string();
  const int ncoeff = distortionCoeffCount(c.distortion_model);
  if (ncoeff < 0) dm.fail("expected one of: " + detail::joinNames(supportedDistortionModels()) + "; got " + dm.found());

  const YNode in = n.at("intrinsics", "[fx, fy, cx, cy] in pixels");
  const std::size_t nin = in.listSize("4 numbers [fx, fy, cx, cy] in pixels");
  if (nin != 4) in.fail("expected 4 numbers [fx, fy, cx, cy] in pixels, got " + std::to_string(nin));
  for (std::size_t i = 0; i < 4; ++i) c.intrinsics[i] = i < 2 ? in[i].positive() : in[i].number();

  const YNode dc = n.maybe("distortion_coeffs");
  if (!dc.node.IsDefined()) {
    if (ncoeff != 0)
      n.at("distortion_coeffs", std::to_string(ncoeff) + " numbers for distortion_model " + c.distortion_model);
  } else {
    const std::string expected =
        std::to_string(ncoeff) + " numbers for distortion_model " + c.distortion_model +
        (c.distortion_model == "radtan" ? " [k1, k2, p1, p2]"
                                        : c.distortion_model == "equidistant" ? " [k1, k2, k3, k4]" : " (an empty list [])");
    const std::size_t nd = dc.listSize(expected);
    if (nd != static_cast<std::size_t>(ncoeff)) dc.fail("expected " + expected + ", got " + std::to_string(nd));
    c.distortion_coeffs = dc.numbers();
  }

  const YNode res = n.at("resolution", "[width, height] in pixels");
  const std::size_t nres = res.listSize("2 integers [width, height] in pixels");
  if (nres != 2) res.fail("expected 2 integers [width, height] in pixels, got " + std::to_string(nres) + " values");
  c.resolution = {res[0].integer(1), res[1].integer(1)};

  if (c.intrinsics[2] < 0 || c.intrinsics[2] > c.resolution[0] || c.intrinsics[3] < 0 ||
      c.intrinsics[3] > c.resolution[1])
    warnings.push_back(in.file + ": " + in.path + ": principal point (" + detail::formatDouble(c.intrinsics[2]) +
                       ", " + detail::formatDouble(c.intrinsics[3]) + ") lies outside the " +
                       std::to_string(c.resolution[0]) + "x" + std::to_string(c.resolution[1]) +
                       " image; check the intrinsics' order [fx, fy, cx, cy]" + in.lineSuffix());
}

// When the intrinsics come from elsewhere (a file or the bag), rig.yaml must
// not hold half of the group: which values would win is not obvious, so say
// so rather than pick one. camera_model may stay (pinhole is the only one).
void refuseGroupFields(const YNode& n, const std::string& source) {
  for (const char* key : {"distortion_model", "distortion_coeffs", "resolution"}) {
    const YNode k = n.maybe(key);
    if (k.node.IsDefined())
      k.fail(std::string("given, but this camera has no 'intrinsics', so its intrinsics, distortion_model, "
                         "distortion_coeffs and resolution all come from ") +
             source + "; remove " + key + ", or give intrinsics too (then the whole group is read from rig.yaml)");
  }
  const YNode cm = n.maybe("camera_model");
  if (cm.node.IsDefined()) {
    const std::string model = cm.string();
    if (std::find(supportedCameraModels().begin(), supportedCameraModels().end(), model) ==
            supportedCameraModels().end())
      cm.fail("expected one of: " + detail::joinNames(supportedCameraModels()) + "; got " + cm.found());
  }
}

// Loads the intrinsics group from `intrinsics_file` (Kalibr camchain, ROS
// camera_info or OpenCV YAML): the camera named like this one, else the only
// one in the file.
void loadIntrinsicsFile(const YNode& f, const std::string& base_dir, CameraConfig& c) {
  const std::string path = resolvePath(f.string(), base_dir);
  std::vector<CameraConfig> found;
  try {
    // importIntrinsics wants a pixel_sigma to hand out; rig.yaml's own is kept.
    found = importIntrinsics(path, 1.0, c.name);
  } catch (const InputError& e) {
    f.fail(std::string("cannot load the intrinsics from it: ") + e.what());
  }
  const CameraConfig* pick = nullptr;
  for (const CameraConfig& k : found)
    if (k.name == c.name) pick = &k;
  if (pick == nullptr && found.size() == 1) pick = &found.front();
  if (pick == nullptr) {
    std::vector<std::string> names;
    for (const CameraConfig& k : found) names.push_back(k.name);
    f.fail(path + " holds " + std::to_string(found.size()) + " cameras (" + detail::joinNames(names) +
           ") and none is named '" + c.name + "'; expected a file with one camera, or one named like this camera");
  }
  c.intrinsics_file = path;
  c.camera_model = pick->camera_model;
  c.distortion_model = pick->distortion_model;
  c.intrinsics = pick->intrinsics;
  c.distortion_coeffs = pick->distortion_coeffs;
  c.resolution = pick->resolution;
}

// The prior of estimated intrinsics: intrinsics_sigma [fx, fy, cx, cy] and
// distortion_coeffs_sigma (one per coefficient of the model, checked here
// when the model is known; from a bag's camera_info, when it is read).
// Every sigma finite and > 0: a zero sigma would hold a value fixed while
// claiming to estimate it.
void readIntrinsicsPrior(const YNode& n, CameraConfig& c) {
  const YNode is = n.maybe("intrinsics_sigma");
  if (is.node.IsDefined()) {
    const std::size_t k = is.listSize("4 numbers [fx, fy, cx, cy] in pixels, each > 0");
    if (k != 4) is.fail("expected 4 numbers [fx, fy, cx, cy] in pixels, each > 0, got " + std::to_string(k));
    for (std::size_t i = 0; i < 4; ++i) c.intrinsics_sigma.push_back(is[i].positive());
  }
  const YNode ds = n.maybe("distortion_coeffs_sigma");
  if (ds.node.IsDefined()) {
    const std::string expected = c.intrinsics_from_bag
                                     ? std::string("one number > 0 per distortion coefficient")
                                     : std::to_string(distortionCoeffCount(c.distortion_model)) +
                                           " numbers > 0, one per coefficient of distortion_model " +
                                           c.distortion_model;
    const std::size_t k = ds.listSize(expected);
    if (!c.intrinsics_from_bag && k != static_cast<std::size_t>(distortionCoeffCount(c.distortion_model)))
      ds.fail("expected " + expected + ", got " + std::to_string(k));
    for (std::size_t i = 0; i < k; ++i) c.distortion_coeffs_sigma.push_back(ds[i].positive());
  }
}

std::string optionalTopic(const YNode& n, const std::string& key) {
  const YNode t = n.maybe(key);
  if (!t.node.IsDefined()) return "";
  const std::string s = t.string();
  if (std::any_of(s.begin(), s.end(), [](char ch) { return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r'; }))
    t.fail("expected a ROS topic name such as /cam0/image_raw (no spaces), got " + t.found());
  return s;
}

// `item`'s path is "cameras[#N]" (its position, 1 first) only until its name
// is read; every field after that is "cameras[NAME].field".
CameraConfig readCamera(const YNode& item, const std::string& base_dir, std::vector<std::string>& warnings) {
  const std::string keys =
      "name, topic, camera_info_topic, intrinsics_file, camera_model, distortion_model, intrinsics, "
      "distortion_coeffs, resolution, pixel_sigma, readout_ms, intrinsics_sigma, distortion_coeffs_sigma, "
      "T_base_cam_guess, frame, urdf_joint";
  item.requireMap("a mapping with keys " + keys);
  CameraConfig c;
  if (!item.node.Mark().is_null() && item.node.Mark().line >= 0) c.yaml_line = item.node.Mark().line + 1;
  const YNode name = item.at("name", "the camera name (also its image folder's name)");
  c.name = name.string();
  if (!isFolderSafe(c.name))
    name.fail("expected a name usable as a folder name (letters, digits, '_', '-', '.', not starting with '.' or "
              "'-'), got " + name.found());
  const YNode n{item.node, item.file, cameraField(c.name)};
  n.warnUnknownKeys({"name", "topic", "camera_info_topic", "intrinsics_file", "camera_model", "distortion_model",
                     "intrinsics", "distortion_coeffs", "resolution", "pixel_sigma", "readout_ms", "intrinsics_sigma",
                     "distortion_coeffs_sigma", "T_base_cam_guess", "frame", "urdf_joint"},
                    warnings);
  c.topic = optionalTopic(n, "topic");
  c.camera_info_topic = optionalTopic(n, "camera_info_topic");

  const YNode in = n.maybe("intrinsics");
  const YNode file = n.maybe("intrinsics_file");
  if (in.node.IsDefined()) {
    // docs/design.md, Contract names: intrinsics_file is "used when intrinsics is absent", so the
    // numbers in rig.yaml win; the file is not read, and a warning says so.
    if (file.node.IsDefined())
      warnings.push_back(file.file + ": " + file.path + ": ignored, because this camera also gives intrinsics" +
                         in.lineSuffix() + ", which take precedence; remove one of the two" + file.lineSuffix());
    readIntrinsicsGroup(n, c, warnings);
  } else if (file.node.IsDefined()) {
    refuseGroupFields(n, "intrinsics_file");
    loadIntrinsicsFile(file, base_dir, c);
  } else if (!c.camera_info_topic.empty()) {
    refuseGroupFields(n, "the bag's camera_info_topic " + c.camera_info_topic);
    c.intrinsics_from_bag = true;
    c.distortion_model = "none";
  } else {
    n.at("intrinsics",
         "[fx, fy, cx, cy] in pixels, or intrinsics_file (a Kalibr camchain, ROS camera_info or OpenCV YAML), or "
         "camera_info_topic (bag input only)");
  }

  c.pixel_sigma = n.at("pixel_sigma", "the corner noise std in pixels (> 0)").positive();
  if (const YNode ro = n.maybe("readout_ms"); ro.node.IsDefined()) c.readout_ms = ro.nonNegative();
  readIntrinsicsPrior(n, c);

  const YNode guess = n.maybe("T_base_cam_guess");
  if (guess.node.IsDefined()) c.T_base_cam_guess = guess.transform();

  // The camera in the robot description (checked against the URDF by --urdf-out).
  const YNode frame = n.maybe("frame");
  if (frame.node.IsDefined()) c.frame = frame.string();
  const YNode urdf_joint = n.maybe("urdf_joint");
  if (urdf_joint.node.IsDefined()) {
    c.urdf_joint = urdf_joint.string();
    if (c.frame.empty())
      urdf_joint.fail("expected a frame: field beside urdf_joint (the URDF link of the camera's optical frame), "
                      "got urdf_joint '" + c.urdf_joint + "' alone");
  }
  return c;
}

int lineOf(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  return m.is_null() || m.line < 0 ? 0 : m.line + 1;
}

// The line of every key, by the path messages give it, for the errors found
// after reading (rigFieldError).
void recordLines(const YNode& root, RigConfig& rig) {
  auto keysOf = [&](const YAML::Node& map, const std::string& prefix) {
    if (!map.IsMap()) return;
    for (auto it = map.begin(); it != map.end(); ++it)
      if (it->first.IsScalar()) rig.field_lines[prefix + it->first.Scalar()] = lineOf(it->first);
  };
  keysOf(root.node, "");
  for (const char* block : {"robot", "target"})
    if (root.node[block]) keysOf(root.node[block], std::string(block) + ".");
  const YAML::Node cams = root.node["cameras"];
  if (!cams.IsSequence()) return;
  for (std::size_t i = 0; i < cams.size() && i < rig.cameras.size(); ++i) {
    const std::string path = cameraField(rig.cameras[i].name);
    rig.field_lines[path] = rig.cameras[i].yaml_line;
    keysOf(cams[i], path + ".");
  }
}

}  // namespace

RigConfig parseRigConfig(const std::string& yaml_text, const std::string& source_name, const std::string& base_dir) {
  const YNode root = detail::parseYaml(yaml_text, source_name);
  root.requireMap("a mapping with keys robot, target, cameras, sync_tolerance_ms, joint_states_topic");
  RigConfig rig;
  rig.source = source_name;
  root.warnUnknownKeys({"robot", "target", "cameras", "sync_tolerance_ms", "joint_states_topic"}, rig.warnings);
  rig.robot = readRobot(root, base_dir, rig.warnings);
  rig.target = readTarget(root, rig.warnings);

  const YNode cams = root.at("cameras", "a list of cameras (name, camera_model, distortion_model, ...)");
  const std::size_t ncam = cams.listSize("a list of cameras");
  if (ncam == 0) cams.fail("expected at least one camera, got an empty list");
  for (std::size_t i = 0; i < ncam; ++i) {
    const YNode cn{cams[i].node, cams.file, "cameras[#" + std::to_string(i + 1) + "]"};
    CameraConfig c = readCamera(cn, base_dir, rig.warnings);
    const int prev = rig.cameraIndex(c.name);
    if (prev >= 0) {
      const int prev_line = rig.cameras[static_cast<std::size_t>(prev)].yaml_line;
      const YNode again{cn.node["name"], cn.file, cameraField(c.name, "name")};
      again.fail("expected unique camera names, got '" + c.name + "' again (the first is the camera" +
                 (prev_line > 0 ? " at line " + std::to_string(prev_line) : " #" + std::to_string(prev + 1)) + ")");
    }
    rig.cameras.push_back(std::move(c));
  }

  const YNode sync = root.maybe("sync_tolerance_ms");
  if (sync.node.IsDefined()) rig.sync_tolerance_ms = sync.nonNegative();
  if (root.has("joint_states_topic")) rig.joint_states_topic = optionalTopic(root, "joint_states_topic");
  recordLines(root, rig);
  return rig;
}

RigConfig loadRigConfig(const std::string& path) {
  const std::string text = readTextFile(path, "rig.yaml (the rig description)");
  const std::string dir = fs::path(path).parent_path().string();
  return parseRigConfig(text, path, dir.empty() ? "." : dir);
}

namespace {

using detail::formatDouble;
using detail::formatList;
using detail::yamlScalar;

/// `path` relative to the folder `relative_to` (as it is when that is empty
/// or no relative path exists).
std::string relativePath(const std::string& path, const std::string& relative_to) {
  if (relative_to.empty()) return path;
  const fs::path rel = fs::path(path).lexically_relative(fs::absolute(relative_to).lexically_normal());
  return rel.empty() ? path : rel.string();
}

std::string robotYaml(const RobotConfig& robot, const std::string& relative_to) {
  std::string s = "robot:\n";
  s += "  urdf: " + detail::yamlQuoted(relativePath(robot.urdf, relative_to)) + "\n";
  s += "  base_link: " + yamlScalar(robot.base_link) + "\n";
  s += "  marker_link: " + yamlScalar(robot.marker_link) + "\n";
  s += "  T_link_marker:  # board frame in marker_link, 4x4 row-major" +
       detail::formatMatrixBlock(robot.T_link_marker.matrix(), 4) + "\n";
  s += "  mount_sigma: [" + formatDouble(robot.mount_sigma_m) + ", " + formatDouble(robot.mount_sigma_rad) +
       "]  # metres, radians; [0, 0] holds the mount fixed\n";
  if (!robot.encoder_sigmas.empty()) {
    s += "  encoder_sigma:  # per joint\n";
    for (const auto& [joint, sigma] : robot.encoder_sigmas) s += "    " + yamlScalar(joint) + ": " + formatDouble(sigma) + "\n";
  } else {
    s += "  encoder_sigma: " + formatDouble(robot.encoder_sigma) + "  # radians (metres for prismatic joints)\n";
  }
  if (!robot.joint_offset_sigmas.empty()) {
    s += "  joint_offset_sigma:  # per joint, prior std of the joint zero offsets\n";
    for (const auto& [joint, sigma] : robot.joint_offset_sigmas)
      s += "    " + yamlScalar(joint) + ": " + formatDouble(sigma) + "\n";
  } else if (robot.joint_offset_sigma > 0.0) {
    s += "  joint_offset_sigma: " + formatDouble(robot.joint_offset_sigma) +
         "  # radians, prior std of the joint zero offsets (--estimate joint-offsets)\n";
  }
  if (!robot.kinematic_sigmas.empty()) {
    s += "  kinematic_sigma:  # per joint, [metres, radians]: the URDF's tolerance of the joint's origin\n";
    for (const auto& [joint, ms] : robot.kinematic_sigmas)
      s += "    " + yamlScalar(joint) + ": [" + formatDouble(ms[0]) + ", " + formatDouble(ms[1]) + "]\n";
  } else if (robot.hasKinematicSigma()) {
    s += "  kinematic_sigma: [" + formatDouble(robot.kinematic_sigma[0]) + ", " +
         formatDouble(robot.kinematic_sigma[1]) +
         "]  # [metres, radians]: the URDF's tolerance of each joint origin on the marker chain\n";
  }
  if (!robot.backlash_sigmas.empty()) {
    s += "  backlash_sigma:  # per joint, prior std of the gear backlash\n";
    for (const auto& [joint, sigma] : robot.backlash_sigmas)
      s += "    " + yamlScalar(joint) + ": " + formatDouble(sigma) + "\n";
  } else if (robot.backlash_sigma > 0.0) {
    s += "  backlash_sigma: " + formatDouble(robot.backlash_sigma) +
         "  # radians, prior std of the gear backlash (--estimate backlash)\n";
  }
  return s;
}

std::string targetYaml(const TargetConfig& target) {
  std::string s = "target:\n";
  s += "  type: " + yamlScalar(target.type) + "\n";
  s += "  squares_x: " + std::to_string(target.squares_x) + "\n";
  s += "  squares_y: " + std::to_string(target.squares_y) + "\n";
  s += "  square_size: " + formatDouble(target.square_size) + "  # metres\n";
  s += "  marker_size: " + formatDouble(target.marker_size) + "  # metres\n";
  s += "  dictionary: " + yamlScalar(target.dictionary) + "\n";
  return s;
}

/// Where a camera's intrinsics come from: the bag's camera_info, a file, or
/// the numbers themselves.
std::string intrinsicsYaml(const CameraConfig& c, const std::string& relative_to) {
  if (c.intrinsics_from_bag) {
    if (c.camera_info_topic.empty())
      throw std::invalid_argument("writeRigConfig: camera '" + c.name +
                                  "' has intrinsics_from_bag but no camera_info_topic to take them from");
    return "    # intrinsics, distortion and resolution: from camera_info_topic when the bag is read\n";
  }
  if (!c.intrinsics_file.empty())
    return "    intrinsics_file: " + detail::yamlQuoted(relativePath(c.intrinsics_file, relative_to)) +
           "  # intrinsics, distortion and resolution\n";
  std::string s = "    distortion_model: " + yamlScalar(c.distortion_model) + "\n";
  s += "    intrinsics: " +
       formatList(Eigen::Vector4d(c.intrinsics[0], c.intrinsics[1], c.intrinsics[2], c.intrinsics[3])) +
       "  # fx, fy, cx, cy (pixels)\n";
  s += "    distortion_coeffs: " + formatList(c.distortion_coeffs) + "\n";
  s += "    resolution: [" + std::to_string(c.resolution[0]) + ", " + std::to_string(c.resolution[1]) + "]\n";
  return s;
}

std::string cameraYaml(const CameraConfig& c, const std::string& relative_to) {
  std::string s = "  - name: " + yamlScalar(c.name) + "\n";
  if (!c.topic.empty()) s += "    topic: " + yamlScalar(c.topic) + "  # sensor_msgs Image or CompressedImage\n";
  if (!c.camera_info_topic.empty()) s += "    camera_info_topic: " + yamlScalar(c.camera_info_topic) + "\n";
  s += "    camera_model: " + yamlScalar(c.camera_model) + "\n";
  s += intrinsicsYaml(c, relative_to);
  s += "    pixel_sigma: " + formatDouble(c.pixel_sigma) + "  # pixels\n";
  if (c.readout_ms > 0.0)
    s += "    readout_ms: " + formatDouble(c.readout_ms) + "  # rolling shutter: first row's exposure start to the last's\n";
  if (!c.intrinsics_sigma.empty())
    s += "    intrinsics_sigma: " + formatList(c.intrinsics_sigma) + "  # prior std of estimated fx, fy, cx, cy (pixels)\n";
  if (!c.distortion_coeffs_sigma.empty())
    s += "    distortion_coeffs_sigma: " + formatList(c.distortion_coeffs_sigma) +
         "  # prior std of estimated coefficients\n";
  if (c.T_base_cam_guess) s += "    T_base_cam_guess:" + detail::formatMatrixBlock(c.T_base_cam_guess->matrix(), 6) + "\n";
  if (!c.frame.empty()) s += "    frame: " + yamlScalar(c.frame) + "  # URDF link of the optical frame\n";
  if (!c.urdf_joint.empty()) s += "    urdf_joint: " + yamlScalar(c.urdf_joint) + "  # joint --urdf-out updates\n";
  return s;
}

}  // namespace

std::string writeRigConfig(const RigConfig& rig, const std::string& relative_to) {
  std::string s = "# fgcal rig description (docs/formats.md); paths relative to this folder.\n";
  s += robotYaml(rig.robot, relative_to);
  s += targetYaml(rig.target);
  s += "cameras:\n";
  for (const CameraConfig& c : rig.cameras) s += cameraYaml(c, relative_to);
  s += "sync_tolerance_ms: " + formatDouble(rig.sync_tolerance_ms) + "  # images closer than this share one board pose\n";
  s += "joint_states_topic: " + yamlScalar(rig.joint_states_topic) + "  # sensor_msgs JointState, for bag input\n";
  return s;
}

}  // namespace fgcal::apps
