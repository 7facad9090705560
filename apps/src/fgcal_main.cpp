// The fgcal command. CLI11 lives in this one translation unit only (it costs
// seconds of compile time per unit that includes it). Every command is a
// library call in fgcal::apps; this file parses options and maps exceptions
// to the exit codes of docs/ (0 ok, 1 data cannot support a calibration, 2 bad
// input or usage).
//
// Each subcommand has an Args struct (its library options plus what the
// command line spells differently), a function adding its options, and a
// function running it once parsed; command() ties the three together.
#include <cstdio>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "fgcal/apps/bag_info.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/camchain.hpp"
#include "fgcal/apps/demo.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/import.hpp"
#include "fgcal/apps/rig_init.hpp"
#include "fgcal/apps/simulator.hpp"
#include "pose_graph_demo.hpp"
#include "version.hpp"

namespace {

namespace apps = fgcal::apps;

/// A subcommand: its CLI11 node and how it runs once parsed (the exit code).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// The end of every --help: the exit codes and where the documentation is.
const char* const kHelpTrailer =
    "Exit codes: 0 success (verdict ok or check); 1 the data cannot support a calibration, or the\n"
    "            verdict is unusable (the message or the findings say why and name the input);\n"
    "            2 bad input or usage (the message names the file, field or option).\n"
    "Documentation: README.md, docs/formats.md (dataset folder, rig.yaml, bags) and\n"
    "docs/outputs.md (what calibrate writes, evaluate) in fgcal's source tree.";

/// The subcommand `name`: `add` adds its options into an Args that lives as
/// long as the command, `run` runs it; `example` is shown by its --help.
template <class Args>
Command command(CLI::App& app, const char* name, const char* description, const char* example,
                void (*add)(CLI::App*, Args&), int (*run)(Args&)) {
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(name, description);
  cmd->footer(std::string("Example:\n  ") + example + "\n\n" + kHelpTrailer);
  add(cmd, *args);
  return {cmd, [args, run] { return run(*args); }};
}

/// "a,b,,c" -> {a, b, c}.
std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

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
      throw apps::InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
    }
  }
  if (out.size() != 2) throw apps::InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
  return out;
}

// ---- calibrate ----------------------------------------------------------------

struct CalibrateArgs {
  apps::CalibrateOptions options;
  std::string cameras;     ///< --cameras, comma-separated
  bool no_report = false;  ///< --no-report
  std::string method;      ///< --method; empty: corners when --estimate has intrinsics, else pnp
  std::string estimate;    ///< --estimate, comma-separated
};

void addCalibrateOptions(CLI::App* cmd, CalibrateArgs& a) {
  apps::CalibrateOptions& o = a.options;
  cmd->add_option("input", o.dataset,
                  "dataset folder (rig.yaml, joints.csv, <camera>/<stamp_ns>.png), or a bag: ROS 1 .bag, ROS 2 bag "
                  "folder (.db3 or .mcap) or .mcap file")
      ->required();
  cmd->add_option("--rig", o.rig,
                  "rig.yaml (robot, board, cameras with their topics): required for a bag; for a folder, used "
                  "instead of its own rig.yaml");
  cmd->add_option("-o,--output", o.output, "result file; the URDF snippet goes beside it")->capture_default_str();
  cmd->add_option("--cameras", a.cameras, "comma-separated subset of the rig's cameras");
  cmd->add_flag("--single-camera", o.single_camera, "solve each camera alone (the paper's F1)");
  cmd->add_flag("--fix-mount", o.fix_mount, "hold the board mount at its rig.yaml value");
  cmd->add_option("--threads", o.threads, "detection threads (0: every core)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--pnp-covariance-scale", o.pnp_covariance_scale,
                  "multiplies every image's PnP covariance: detection errors of consecutive views are correlated "
                  "(>= 1; 1 treats the images as independent, as the paper does)")
      ->capture_default_str();
  CLI::Option* report = cmd->add_option(
      "--report", o.report_dir, "folder of the HTML report (default: <output stem>_report beside the output)");
  cmd->add_flag("--no-report", a.no_report, "do not write the HTML report")->excludes(report);
  cmd->add_option("--urdf-out", o.robot_outputs.urdf_out,
                  "write a copy of the robot's URDF with each camera's joint origin (rig.yaml frame:, "
                  "urdf_joint:) set to the calibration");
  cmd->add_option("--kalibr-out", o.robot_outputs.kalibr_out, "write the cameras as a Kalibr camchain.yaml");
  cmd->add_option("--tf-out", o.robot_outputs.tf_outs,
                  "write a static_transform_publisher launch file: FILE.launch.py (ROS 2 Python), FILE.launch.xml "
                  "(ROS 2 XML) or FILE.launch (ROS 1 XML); give it more than once for several forms")
      ->allow_extra_args(false);
  cmd->add_option("--method", a.method,
                  "pnp: one PnP pose factor per image, with its corner-jitter covariance (the paper's method; the "
                  "default); corners: one reprojection factor per detected corner through the camera model, "
                  "started from the pnp solution (default with --estimate intrinsics)");
  cmd->add_option("--estimate", a.estimate,
                  "also estimate, comma-separated:\n"
                  "time-offset: each camera's delay to the joint stamps (an image stamped t was exposed at t + offset)\n"
                  "joint-offsets: the marker chain's joint zero offsets (prior robot.joint_offset_sigma, 0.05 rad)\n"
                  "intrinsics: fx, fy, cx, cy and distortion (prior intrinsics_sigma; --method corners)\n"
                  "backlash: the marker chain's gear backlash, the true angle lagging the encoder by half of it "
                  "against the motion (prior robot.backlash_sigma, 0.01 rad)");
}

int runCalibrateCommand(CalibrateArgs& a) {
  a.options.cameras = splitList(a.cameras);
  a.options.report = !a.no_report;
  a.options.estimate = apps::parseEstimateSet(a.estimate);
  // Intrinsics can only be estimated from the corners: without --method,
  // asking for them selects the corner method (an explicit --method pnp
  // with them is refused by runCalibrate, saying why).
  a.options.method = !a.method.empty()            ? apps::methodFromString(a.method)
                     : a.options.estimate.intrinsics ? apps::Method::Corners
                                                     : apps::Method::Pnp;
  const apps::CalibrateResult res = apps::runCalibrate(a.options, std::cerr);
  // An unusable result wrote no calibration output and says why (docs/outputs.md, quality).
  return res.output.quality.verdict == apps::Verdict::Unusable ? 1 : 0;
}

// ---- import -------------------------------------------------------------------

void addImportOptions(CLI::App* cmd, apps::ImportOptions& o) {
  cmd->add_option("bag", o.bag, "a ROS 1 .bag, a ROS 2 bag folder (.db3 or .mcap) or an .mcap file")->required();
  cmd->add_option("--rig", o.rig, "rig.yaml naming each camera's topic")->required();
  cmd->add_option("--out", o.out, "dataset folder to create (must not exist, or be empty)")->required();
}

int runImportCommand(apps::ImportOptions& o) {
  apps::runImport(o, std::cerr);
  return 0;
}

// ---- simulate -----------------------------------------------------------------

struct SimulateArgs {
  apps::SimulationOptions options;
  std::string mount_error;    ///< --mount-error MM,DEG
  std::string camera_frames;  ///< --camera-frames, comma-separated
  std::vector<std::string> camera_delays;  ///< --camera-delay-ms NAME=MS,...
  std::vector<std::string> joint_offsets;  ///< --joint-offsets JOINT=RAD,...
  std::string intrinsics_error;            ///< --intrinsics-error PCT,PX
  std::string leg_origin_error;            ///< --leg-origin-error MM,DEG
  std::vector<std::string> backlash;       ///< --backlash RAD and/or JOINT=RAD,...
  std::vector<std::string> readouts;       ///< --readout-ms NAME=MS,...
};

void addSimulateOptions(CLI::App* cmd, SimulateArgs& a) {
  apps::SimulationOptions& o = a.options;
  cmd->add_option("--out", o.out_dir, "dataset folder to create")->required();
  cmd->add_option("--urdf", o.urdf_path, "robot description (default: fgcal's HyQ-like robot)");
  cmd->add_option("--base-link", o.base_link, "base link")->capture_default_str();
  cmd->add_option("--marker-link", o.marker_link, "link the board is fixed to")->capture_default_str();
  cmd->add_option("--cameras", o.cameras, "number of cameras (1-4)")->capture_default_str();
  cmd->add_option("--frames", o.frames, "image instants of the fastest camera")->capture_default_str();
  cmd->add_option("--seed", o.seed, "random seed")->capture_default_str();
  cmd->add_option("--pixel-noise", o.pixel_noise, "corner noise std, px")->capture_default_str();
  cmd->add_option("--encoder-noise", o.encoder_noise, "joint reading noise std, rad")->capture_default_str();
  cmd->add_option("--mount-error", a.mount_error, "error of the rig.yaml mount prior: MM,DEG");
  cmd->add_option("--distortion", o.distortion, "radtan | equidistant | none")->capture_default_str();
  cmd->add_flag("--overwrite", o.overwrite, "replace an earlier simulation in --out");
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
  apps::SimulationOptions& o = a.options;
  if (!a.mount_error.empty()) {
    const auto v = parsePair(a.mount_error, "--mount-error");
    o.mount_error_m = v[0] * 1e-3;
    o.mount_error_rad = v[1] * M_PI / 180.0;
  }
  o.camera_frames = splitList(a.camera_frames);
  o.camera_delay_ms = apps::parseNamedValues(a.camera_delays, "--camera-delay-ms");
  o.joint_offsets_rad = apps::parseNamedValues(a.joint_offsets, "--joint-offsets");
  if (!a.intrinsics_error.empty()) {
    const auto v = apps::parseNumberList(a.intrinsics_error, "--intrinsics-error", 2, "PCT,PX");
    o.intrinsics_error_pct = v[0];
    o.intrinsics_error_px = v[1];
  }
  if (!a.leg_origin_error.empty()) {
    const auto v = parsePair(a.leg_origin_error, "--leg-origin-error");
    o.leg_origin_error_m = v[0] * 1e-3;
    o.leg_origin_error_rad = v[1] * M_PI / 180.0;
  }
  apps::parseBacklash(a.backlash, &o.backlash_rad, &o.joint_backlash_rad);
  o.readout_ms = apps::parseNamedValues(a.readouts, "--readout-ms");
  const auto s = apps::simulateDataset(o);
  std::cerr << "fgcal simulate: wrote " << s.images_written << " images, " << s.instants << " instants to "
            << o.out_dir << "\n";
  return 0;
}

// ---- evaluate -----------------------------------------------------------------

struct EvaluateArgs {
  std::string calibration;   ///< calibration.yaml or a Kalibr camchain.yaml
  std::string ground_truth;  ///< ground_truth.yaml
};

void addEvaluateOptions(CLI::App* cmd, EvaluateArgs& a) {
  cmd->add_option("calibration", a.calibration, "calibration.yaml, or a Kalibr camchain.yaml (relative poses only)")
      ->required();
  cmd->add_option("ground_truth", a.ground_truth, "ground_truth.yaml")->required();
}

int runEvaluateCommand(EvaluateArgs& a) {
  if (apps::looksLikeKalibrCamchain(apps::readTextFile(a.calibration, "calibration result"))) {
    const auto rel = apps::evaluateCamchain(apps::loadKalibrCamchain(a.calibration),
                                            apps::loadGroundTruth(a.ground_truth), a.calibration);
    std::cout << apps::formatRelativeEvaluationTable(rel);
    return 0;
  }
  const auto ev = apps::evaluateFiles(a.calibration, a.ground_truth);
  std::cout << apps::formatEvaluationTable(ev);
  return 0;
}

// ---- demo, pose-graph-demo ----------------------------------------------------

void addDemoOptions(CLI::App* cmd, apps::DemoOptions& o) {
  cmd->add_option("--frames", o.frames, "image instants")->capture_default_str()->check(CLI::Range(10, 100000));
  cmd->add_option("--seed", o.seed, "random seed")->capture_default_str();
  cmd->add_option("--keep", o.keep_dir, "keep the dataset and results in this folder");
}

int runDemoCommand(apps::DemoOptions& o) { return apps::runDemo(o, std::cout); }

void addPoseGraphDemoOptions(CLI::App* cmd, apps::PoseGraphDemoOptions& o) {
  cmd->add_option("--poses", o.poses, "number of poses")->check(CLI::Range(2, 10000000));
  cmd->add_option("--seed", o.seed, "random seed");
}

int runPoseGraphDemoCommand(apps::PoseGraphDemoOptions& o) { return apps::runPoseGraphDemo(o); }

// ---- bag-info -----------------------------------------------------------------

struct BagInfoArgs {
  std::string bag;
  bool stamps = false;  ///< --stamps: read every header stamp
};

void addBagInfoOptions(CLI::App* cmd, BagInfoArgs& a) {
  cmd->add_option("bag", a.bag, "a ROS 1 .bag, a ROS 2 bag folder or .db3, or an .mcap file")->required();
  cmd->add_flag("--stamps", a.stamps,
                "also read header.stamp of every JointState, Image, CompressedImage and CameraInfo message "
                "(reads those topics whole)");
}

int runBagInfoCommand(BagInfoArgs& a) {
  std::cout << apps::formatBagInfo(apps::summarizeBag(a.bag, a.stamps));
  return 0;
}

// ---- init: a commented starter rig.yaml (apps/rig_init.hpp) -------------------

void addInitOptions(CLI::App* cmd, apps::InitOptions& o) {
  cmd->add_option("--urdf", o.urdf, "robot description")->required();
  cmd->add_option("--base-link", o.base_link, "base link")->required();
  cmd->add_option("--marker-link", o.marker_link, "link the board is fixed to")->required();
  cmd->add_option("--board", o.board,
                  "SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY, e.g. 5x7:0.04:0.03:DICT_4X4_50 (metres)")
      ->required();
  CLI::Option* bag =
      cmd->add_option("--bag", o.bag, "ROS 1 .bag, ROS 2 bag folder or .mcap: cameras from its CameraInfo topics");
  cmd->add_option("--camera-info", o.camera_infos,
                  "NAME:FILE or FILE: intrinsics in ROS camera_info, Kalibr camchain or OpenCV format")
      ->excludes(bag);
  cmd->add_option("-o,--output", o.output, "rig.yaml to write (its folder must exist)")->required();
  cmd->add_flag("--force", o.overwrite, "replace an existing output file");
}

int runInitCommand(apps::InitOptions& o) {
  apps::runInit(o, std::cout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // The name is given, not taken from argv[0], so that --help says "fgcal",
  // not the path the program was started from.
  CLI::App app{"fgcal: multi-camera extrinsic calibration of legged robots on a factor graph", "fgcal"};
  app.require_subcommand(1);
  app.footer(std::string("Examples:\n"
                         "  fgcal simulate --out ds && fgcal calibrate ds -o out/calibration.yaml\n"
                         "  fgcal evaluate out/calibration.yaml ds/ground_truth.yaml\n"
                         "  fgcal COMMAND --help   (each command's options and an example)\n\n") +
             kHelpTrailer);
  // fgcal --version: project version and git commit (version.hpp).
  app.set_version_flag("--version", apps::versionText(), "Print the version (and git commit) and exit");
  const std::vector<Command> commands = {
      command(app, "calibrate", "Calibrate the cameras from a dataset folder (docs/formats.md) or a robot bag",
              "fgcal calibrate run.mcap --rig rig.yaml -o out/calibration.yaml --tf-out out/cameras.launch.xml",
              addCalibrateOptions, runCalibrateCommand),
      command(app, "import", "Write a robot bag out as a dataset folder (images, joints.csv, rig.yaml)",
              "fgcal import run.bag --rig rig.yaml --out dataset", addImportOptions, runImportCommand),
      command(app, "simulate", "Write a synthetic dataset with ground truth",
              "fgcal simulate --out ds --cameras 2 --frames 60 --seed 3", addSimulateOptions, runSimulateCommand),
      command(app, "evaluate",
              "Compare a calibration with ground truth (Table I, NEES; time offsets, joint offsets and intrinsics "
              "when estimated, in sigmas)",
              "fgcal evaluate out/calibration.yaml ds/ground_truth.yaml   (the result first, then the truth)",
              addEvaluateOptions, runEvaluateCommand),
      command(app, "demo", "Simulate, calibrate with F1 and F2, evaluate: the whole product",
              "fgcal demo --frames 60 --keep demo_out", addDemoOptions, runDemoCommand),
      command(app, "pose-graph-demo", "The core engine alone on a noisy SE(3) pose graph",
              "fgcal pose-graph-demo --poses 1000 --seed 1", addPoseGraphDemoOptions, runPoseGraphDemoCommand),
      command(app, "bag-info", "List a ROS 1 / ROS 2 bag's topics, types, counts and rates (no ROS needed)",
              "fgcal bag-info run.mcap --stamps", addBagInfoOptions, runBagInfoCommand),
      command(app, "init", "Write a starter rig.yaml from a URDF, the board and camera_info",
              "fgcal init --urdf robot.urdf --base-link base --marker-link LF_FOOT "
              "--board 5x7:0.04:0.03:DICT_4X4_50 --bag run.mcap -o rig.yaml",
              addInitOptions, runInitCommand)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // help and version print and return 0
    return rc == 0 ? 0 : 2;
  }
  try {
    for (const Command& c : commands)
      if (*c.app) return c.run();
  } catch (const std::exception& e) {
    std::cerr << "fgcal: error: " << e.what() << "\n";
    return apps::exitCodeFor(e);
  }
  return 2;
}
