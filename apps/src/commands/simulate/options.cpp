// The simulator's options: command-line texts parsed, every value checked
// before anything is written (each error names its option and what was
// expected).
#include "commands/simulate/options.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

#include "fgcal/apps/errors.hpp"

namespace fgcal::apps {

namespace {

[[noreturn]] void bad(const std::string& option, const std::string& detail) { throw InputError("", option, detail); }

// A whole text as a finite number (no "inf", "nan", trailing characters).
bool finiteNumber(const std::string& text, double* out) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno == ERANGE || end != text.c_str() + text.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

std::vector<std::string> splitCommas(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) items.push_back(item);
  if (!text.empty() && text.back() == ',') items.emplace_back();
  return items;
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void range(const char* name, double v, double hi, const char* unit) {
  if (!std::isfinite(v) || v < 0.0 || v > hi)
    bad(name, std::string("expected a value in [0, ") + fmt(hi) + "] " + unit + ", got " + fmt(v));
}

}  // namespace

std::map<std::string, double> parseNamedValues(const std::vector<std::string>& texts, const std::string& option) {
  std::map<std::string, double> out;
  for (const std::string& text : texts)
    for (const std::string& item : splitCommas(text)) {
      const auto eq = item.find('=');
      double v = 0.0;
      if (eq == std::string::npos || eq == 0 || !finiteNumber(item.substr(eq + 1), &v))
        bad(option, "expected NAME=NUMBER items separated by commas, got '" + item + "' in '" + text + "'");
      const std::string name = item.substr(0, eq);
      if (!out.emplace(name, v).second) bad(option, "'" + name + "' is given twice; expected each name once");
    }
  return out;
}

void parseBacklash(const std::vector<std::string>& texts, double* all_rad, std::map<std::string, double>* per_joint) {
  std::vector<std::string> named;
  bool have_all = false;
  *all_rad = 0.0;
  for (const std::string& text : texts)
    for (const std::string& item : splitCommas(text)) {
      if (item.find('=') != std::string::npos) {
        named.push_back(item);
        continue;
      }
      if (!finiteNumber(item, all_rad))
        bad("--backlash", "expected RAD (every movable joint of the marker chain) or JOINT=RAD items separated by "
                          "commas, got '" + item + "' in '" + text + "'");
      if (have_all) bad("--backlash", "RAD for every joint is given twice; expected it once, JOINT=RAD for others");
      have_all = true;
    }
  *per_joint = parseNamedValues(named, "--backlash");
}

std::vector<double> parseNumberList(const std::string& text, const std::string& option, std::size_t count,
                                    const std::string& form) {
  const std::vector<std::string> items = splitCommas(text);
  std::vector<double> out(items.size());
  bool ok = items.size() == count;
  for (std::size_t i = 0; ok && i < items.size(); ++i) ok = finiteNumber(items[i], &out[i]);
  if (!ok)
    bad(option, "expected " + std::to_string(count) + " numbers " + form + " separated by a comma, got '" + text +
                    "'");
  return out;
}

namespace sim {

void validateOptions(const SimulationOptions& o) {
  if (o.out_dir.empty()) bad("--out", "expected the dataset folder to write");
  if (o.cameras < 1 || o.cameras > 4)
    bad("--camera-count", "expected 1..4 (cam0 stereo left, cam1 RGB-D, cam2 stereo right, cam3 wide), got " +
                         std::to_string(o.cameras));
  if (o.frames < 1 || o.frames > 100'000)
    bad("--frames", "expected 1..100000 cam0 images (30 Hz), got " + std::to_string(o.frames));
  range("--pixel-noise", o.pixel_noise, 10.0, "px");
  range("--encoder-noise", o.encoder_noise, 0.5, "rad");
  range("--mount-error", o.mount_error_m, 0.5, "metres (MM of MM,DEG: at most 500 mm)");
  range("--mount-error", o.mount_error_rad, M_PI, "radians (DEG of MM,DEG: at most 180 deg)");
  // No command-line flag: the library's and Python's field (cam1 fires this long after cam0).
  range("cam1_delay_us", o.cam1_delay_us, 1000.0, "us");
  if (o.distortion != "radtan" && o.distortion != "equidistant" && o.distortion != "none")
    bad("--distortion", "expected radtan, equidistant or none, got '" + o.distortion + "'");
  // No command-line flags: the library's and Python's fields.
  if (o.supersampling < 1 || o.supersampling > 16)
    bad("supersampling", "expected 1..16 samples per pixel side, got " + std::to_string(o.supersampling));
  if (o.image_width < 0 || o.image_height < 0 || o.image_width > 8192 || o.image_height > 8192 ||
      (o.image_width == 0) != (o.image_height == 0))
    bad("image_width, image_height", "expected both width and height in 1..8192 (or both 0 for each camera's own), got " +
                            std::to_string(o.image_width) + "x" + std::to_string(o.image_height));
  if (o.base_link.empty()) bad("--base-link", "expected a link name");
  if (o.marker_link.empty()) bad("--marker-link", "expected a link name");
  range("--intrinsics-error", o.intrinsics_error_pct, 50.0, "percent (PCT of PCT,PX)");
  range("--intrinsics-error", o.intrinsics_error_px, 100.0, "pixels (PX of PCT,PX)");
  range("--leg-origin-error", o.leg_origin_error_m, 0.02, "metres (MM of MM,DEG: at most 20 mm)");
  range("--leg-origin-error", o.leg_origin_error_rad, 0.05, "radians (DEG of MM,DEG: at most 2.86 deg)");
  const double fov_max = o.distortion == "equidistant" ? 160.0 : 120.0;
  if (o.fov_deg != 0.0 && !(o.fov_deg >= 30.0 && o.fov_deg <= fov_max))
    bad("--fov-deg", "expected 0 (each camera's own) or a horizontal field of view in [30, " + fmt(fov_max) +
                         "] degrees with --distortion " + o.distortion + ", got " + fmt(o.fov_deg) +
                         (o.distortion == "equidistant" ? "" : " (wider: --distortion equidistant)"));
  // Camera names are known from the count alone: checked before the robot.
  const std::vector<std::string> names = simulatedCameraNames(o.cameras);
  for (const auto& [name, ms] : o.camera_delay_ms) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      bad("--camera-delay-ms", "no camera '" + name + "' in a simulation with --camera-count " +
                                   std::to_string(o.cameras) + "; expected one of " + list);
    }
    if (!std::isfinite(ms)) bad("--camera-delay-ms", "expected a finite number of milliseconds for " + name);
  }
  for (const auto& [joint, rad] : o.joint_offsets_rad)
    if (!std::isfinite(rad) || std::abs(rad) > 0.5)
      bad("--joint-offsets", "expected an offset in [-0.5, 0.5] rad (m for a prismatic joint) for '" + joint +
                                 "', got " + fmt(rad));
  range("--backlash", o.backlash_rad, 0.1, "rad (m for a prismatic joint) for every joint of the marker chain");
  for (const auto& [joint, rad] : o.joint_backlash_rad)
    if (!std::isfinite(rad) || rad < 0.0 || rad > 0.1)
      bad("--backlash", "expected a backlash in [0, 0.1] rad (m for a prismatic joint) for '" + joint + "', got " +
                            fmt(rad));
  range("--encoder-resolution", o.encoder_resolution_rad, 0.1, "rad (m for a prismatic joint), the encoder's step");
  for (const auto& [name, ms] : o.readout_ms) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      bad("--readout-ms", "no camera '" + name + "' in a simulation with --camera-count " + std::to_string(o.cameras) +
                              "; expected one of " + list);
    }
    const double period = framePeriodMs(name, o.cameras);
    if (!std::isfinite(ms) || ms < 0.0 || ms > period)
      bad("--readout-ms", name + "=" + fmt(ms) + ": expected a readout in [0, " + fmt(period) + "] ms (at most " +
                              name + "'s frame period; 0 = global shutter)");
  }
  if (!std::isfinite(o.exposure_ms) || o.exposure_ms < 0.0 || o.exposure_ms > 1000.0 / 30.0)
    bad("--exposure-ms", "expected a value in [0, " + fmt(1000.0 / 30.0) +
                             "] ms (at most the 30 Hz cameras' frame period), got " + fmt(o.exposure_ms));
}

double framePeriodMs(const std::string& camera, int cameras) {
  return (camera == "xtion_rgb" && cameras > 1 ? 2.0 : 1.0) * 1000.0 / 30.0;
}

void checkJointOffsets(const SimulationOptions& o, const kinematics::KinematicChain& chain) {
  auto check = [&](const std::map<std::string, double>& values, const char* option) {
    for (const auto& [joint, rad] : values) {
      (void)rad;
      if (chain.indexOf(joint) >= 0) continue;
      std::string list;
      for (const auto& n : chain.jointNames()) list += (list.empty() ? "" : ", ") + n;
      bad(option, "no movable joint '" + joint + "' on the chain '" + o.base_link + "' -> '" + o.marker_link +
                      "'; expected one of " + list);
    }
  };
  check(o.joint_offsets_rad, "--joint-offsets");
  check(o.joint_backlash_rad, "--backlash");
}

void checkCameraDelays(const SimulationOptions& o, const std::vector<std::string>& names,
                       const std::vector<std::vector<int64_t>>& stamps_ns, int64_t first_joint_ns,
                       int64_t last_joint_ns) {
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (stamps_ns[c].empty()) continue;
    const auto it = o.camera_delay_ms.find(names[c]);
    const auto readout = o.readout_ms.find(names[c]);
    const double delay = it != o.camera_delay_ms.end() ? it->second : 0.0;
    // A rolling shutter's last row and the exposure end later than the stamp.
    const double span = (readout != o.readout_ms.end() ? readout->second : 0.0) + o.exposure_ms;
    const double before_ms = (stamps_ns[c].front() - first_joint_ns) * 1e-6;
    const double after_ms = (last_joint_ns - stamps_ns[c].back()) * 1e-6 - span;
    if (delay >= -before_ms && delay <= after_ms) continue;
    const std::string spanned = span > 0.0 ? " to stamp + " + fmt(delay + span) + " ms (readout and exposure)" : "";
    const std::string option = it != o.camera_delay_ms.end() ? "--camera-delay-ms"
                               : readout != o.readout_ms.end() && readout->second > 0.0 ? "--readout-ms"
                                                                                         : "--exposure-ms";
    const std::string expected =
        it != o.camera_delay_ms.end()
            ? "a delay in [" + fmt(-before_ms) + ", " + fmt(after_ms) + "] ms"
            : "a readout plus exposure of at most " + fmt(after_ms + span) + " ms";
    const std::string who = names[c] + (it != o.camera_delay_ms.end() ? "=" + fmt(delay) : "");
    bad(option, who + ": the board would be rendered at stamp + " + fmt(delay) + " ms" + spanned +
                    ", outside joints.csv; expected " + expected + " (the joint log's margin around " + names[c] +
                    "'s images)");
  }
}

}  // namespace sim

}  // namespace fgcal::apps
