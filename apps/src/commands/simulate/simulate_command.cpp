// `fgcal simulate`: options, their parsing into SimulationOptions and the run (simulateDataset, simulator.hpp).
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/simulator.hpp"

namespace fgcal::apps::commands {

namespace {

std::vector<double> parsePair(const std::string& text, const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
    }
  }
  if (out.size() != 2) throw InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
  return out;
}

struct SimulateArgs {
  SimulationOptions options;
  std::string mount_error;                 ///< --mount-error MM,DEG
  std::string camera_frames;               ///< --camera-frames, comma-separated
  std::vector<std::string> camera_delays;  ///< --camera-delay-ms NAME=MS,...
  std::vector<std::string> joint_offsets;  ///< --joint-offsets JOINT=RAD,...
  std::string intrinsics_error;            ///< --intrinsics-error PCT,PX
  std::string leg_origin_error;            ///< --leg-origin-error MM,DEG
  std::vector<std::string> backlash;       ///< --backlash RAD and/or JOINT=RAD,...
  std::vector<std::string> readouts;       ///< --readout-ms NAME=MS,...
};

void addSimulateOptions(CLI::App* cmd, SimulateArgs& a) {
  SimulationOptions& o = a.options;
  cmd->add_option("-o,--out", o.out_dir, "dataset folder to create")->required();
  cmd->add_option("--urdf", o.urdf_path, "robot description (default: fgcal's HyQ-like robot)");
  cmd->add_option("--base-link", o.base_link, "base link")->capture_default_str();
  cmd->add_option("--marker-link", o.marker_link, "link the board is fixed to")->capture_default_str();
  cmd->add_option("--camera-count,--cameras", o.cameras, "number of cameras (1-4; --cameras: the old spelling)")
      ->capture_default_str();
  cmd->add_option("--frames", o.frames, "image instants of the fastest camera")->capture_default_str();
  cmd->add_option("--seed", o.seed, "random seed")->capture_default_str();
  cmd->add_option("--pixel-noise", o.pixel_noise, "corner noise std, px")->capture_default_str();
  cmd->add_option("--encoder-noise", o.encoder_noise, "joint reading noise std, rad")->capture_default_str();
  cmd->add_option("--mount-error", a.mount_error, "error of the rig.yaml mount prior: MM,DEG");
  cmd->add_option("--distortion", o.distortion, "radtan | equidistant | none")->capture_default_str();
  cmd->add_flag("--force,--overwrite", o.overwrite,
                "replace an earlier simulation in --out (--overwrite: the old spelling)");
  cmd->add_option("--camera-frames", a.camera_frames,
                  "comma-separated URDF links, one per camera: each camera sits at its link (moved a few mm/deg) "
                  "and rig.yaml gets frame: fields");
  cmd->add_option("--camera-delay-ms", a.camera_delays,
                  "NAME=MS[,NAME=MS...]: camera NAME's images show the board at their stamp + MS (its true time "
                  "offset; ground_truth.yaml time_offset_ms)");
  cmd->add_option("--joint-offsets", a.joint_offsets,
                  "JOINT=RAD[,JOINT=RAD...]: joints.csv holds the true angle - RAD for these joints of the marker "
                  "chain (ground_truth.yaml joint_offsets)");
  cmd->add_option("--intrinsics-error", a.intrinsics_error,
                  "PCT,PX: rig.yaml's fx, fy off by PCT % and cx, cy by PX pixels (signs from the seed); images use "
                  "the true ones (ground_truth.yaml intrinsics)");
  cmd->add_option("--leg-origin-error", a.leg_origin_error,
                  "MM,DEG: the real leg differs from its URDF: every joint origin of the marker chain is off by a "
                  "normal error with this std per axis (rig.yaml robot.kinematic_sigma, ground_truth.yaml "
                  "kinematic_origins)");
  cmd->add_option("--backlash", a.backlash,
                  "RAD and/or JOINT=RAD[,...]: gear backlash of every movable joint of the marker chain (RAD) or of "
                  "JOINT; joints.csv holds the motor side, the images the joint, b/2 behind a steady motion "
                  "(ground_truth.yaml backlash)");
  cmd->add_option("--encoder-resolution", o.encoder_resolution_rad,
                  "RAD: every joints.csv reading is rounded to a multiple of this encoder step, after the noise "
                  "(ground_truth.yaml encoder_resolution_rad)");
  cmd->add_option("--readout-ms", a.readouts,
                  "NAME=MS[,NAME=MS...]: camera NAME has a rolling shutter: row v of an image stamped t starts "
                  "exposing at t + v / (rows - 1) * MS (ground_truth.yaml readout_ms; not in rig.yaml)");
  cmd->add_option("--exposure-ms", o.exposure_ms,
                  "MS: every camera's rows integrate the moving board over MS from their start (motion blur; "
                  "ground_truth.yaml exposure_ms)");
  cmd->add_option("--fov-deg", o.fov_deg,
                  "horizontal field of view of every camera, degrees (0: each camera's own; up to 160 with "
                  "--distortion equidistant, a fisheye)");
}

int runSimulateCommand(SimulateArgs& a) {
  SimulationOptions& o = a.options;
  if (!a.mount_error.empty()) {
    const auto v = parsePair(a.mount_error, "--mount-error");
    o.mount_error_m = v[0] * 1e-3;
    o.mount_error_rad = v[1] * M_PI / 180.0;
  }
  o.camera_frames = splitList(a.camera_frames);
  o.camera_delay_ms = parseNamedValues(a.camera_delays, "--camera-delay-ms");
  o.joint_offsets_rad = parseNamedValues(a.joint_offsets, "--joint-offsets");
  if (!a.intrinsics_error.empty()) {
    const auto v = parseNumberList(a.intrinsics_error, "--intrinsics-error", 2, "PCT,PX");
    o.intrinsics_error_pct = v[0];
    o.intrinsics_error_px = v[1];
  }
  if (!a.leg_origin_error.empty()) {
    const auto v = parsePair(a.leg_origin_error, "--leg-origin-error");
    o.leg_origin_error_m = v[0] * 1e-3;
    o.leg_origin_error_rad = v[1] * M_PI / 180.0;
  }
  parseBacklash(a.backlash, &o.backlash_rad, &o.joint_backlash_rad);
  o.readout_ms = parseNamedValues(a.readouts, "--readout-ms");
  const auto s = simulateDataset(o);
  std::cerr << "fgcal simulate: wrote " << s.images_written << " images, " << s.instants << " instants to " << o.out_dir
            << "\n";
  return 0;
}

}  // namespace

Command addSimulateCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "simulate", "Write a synthetic dataset with ground truth",
                             "fgcal simulate --out ds --cameras 2 --frames 60 --seed 3");
  auto a = std::make_shared<SimulateArgs>();
  addSimulateOptions(cmd, *a);
  return {cmd, [a] { return runSimulateCommand(*a); }};
}

}  // namespace fgcal::apps::commands
