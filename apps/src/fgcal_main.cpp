// The fgcal command. CLI11 lives in this one translation unit only (it costs
// seconds of compile time per unit that includes it). Every command is a
// library call in fgcal::apps; this file parses options and maps exceptions
// to DESIGN.md's exit codes (0 ok, 1 data cannot support a calibration, 2 bad
// input or usage).
#include <cstdio>
#include <exception>
#include <iostream>

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
      throw fgcal::apps::InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
    }
  }
  if (out.size() != 2) throw fgcal::apps::InputError("", option, "expected two numbers MM,DEG, got '" + text + "'");
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fgcal: multi-camera extrinsic calibration of legged robots on a factor graph"};
  app.require_subcommand(1);
  // fgcal --version: project version and git commit (version.hpp).
  app.set_version_flag("--version", fgcal::apps::versionText(), "Print the version (and git commit) and exit");

  fgcal::apps::CalibrateOptions cal;
  std::string cameras_csv;
  CLI::App* cal_cmd =
      app.add_subcommand("calibrate", "Calibrate the cameras from a dataset folder (docs/formats.md) or a robot bag");
  cal_cmd
      ->add_option("input", cal.dataset,
                   "dataset folder (rig.yaml, joints.csv, <camera>/<stamp_ns>.png), or a bag: ROS 1 .bag, ROS 2 bag "
                   "folder (.db3 or .mcap) or .mcap file")
      ->required();
  cal_cmd->add_option("--rig", cal.rig,
                      "rig.yaml (robot, board, cameras with their topics): required for a bag; for a folder, used "
                      "instead of its own rig.yaml");
  cal_cmd->add_option("-o,--output", cal.output, "result file; the URDF snippet goes beside it")
      ->capture_default_str();
  cal_cmd->add_option("--cameras", cameras_csv, "comma-separated subset of the rig's cameras");
  cal_cmd->add_flag("--single-camera", cal.single_camera, "solve each camera alone (the paper's F1)");
  cal_cmd->add_flag("--fix-mount", cal.fix_mount, "hold the board mount at its rig.yaml value");
  cal_cmd->add_option("--threads", cal.threads, "detection threads (0: every core)")->check(CLI::NonNegativeNumber);
  cal_cmd
      ->add_option("--pnp-covariance-scale", cal.pnp_covariance_scale,
                   "multiplies every image's PnP covariance: detection errors of consecutive views are correlated "
                   "(>= 1; 1 treats the images as independent, as the paper does)")
      ->capture_default_str();
  bool no_report = false;
  CLI::Option* report_opt = cal_cmd->add_option(
      "--report", cal.report_dir, "folder of the HTML report (default: <output stem>_report beside the output)");
  cal_cmd->add_flag("--no-report", no_report, "do not write the HTML report")->excludes(report_opt);
  cal_cmd->add_option("--urdf-out", cal.robot_outputs.urdf_out,
                      "write a copy of the robot's URDF with each camera's joint origin (rig.yaml frame:, "
                      "urdf_joint:) set to the calibration");
  cal_cmd->add_option("--kalibr-out", cal.robot_outputs.kalibr_out, "write the cameras as a Kalibr camchain.yaml");
  cal_cmd->add_option("--tf-out", cal.robot_outputs.tf_out,
                      "write static_transform_publisher launch files: ROS 2 Python, or ROS 1 XML for a .launch path");

  fgcal::apps::ImportOptions imp;
  CLI::App* imp_cmd = app.add_subcommand("import", "Write a robot bag out as a dataset folder (images, joints.csv, rig.yaml)");
  imp_cmd->add_option("bag", imp.bag, "a ROS 1 .bag, a ROS 2 bag folder (.db3 or .mcap) or an .mcap file")->required();
  imp_cmd->add_option("--rig", imp.rig, "rig.yaml naming each camera's topic")->required();
  imp_cmd->add_option("--out", imp.out, "dataset folder to create (must not exist, or be empty)")->required();

  fgcal::apps::SimulationOptions sim;
  std::string mount_error;
  CLI::App* sim_cmd = app.add_subcommand("simulate", "Write a synthetic dataset with ground truth");
  sim_cmd->add_option("--out", sim.out_dir, "dataset folder to create")->required();
  sim_cmd->add_option("--urdf", sim.urdf_path, "robot description (default: fgcal's HyQ-like robot)");
  sim_cmd->add_option("--base-link", sim.base_link, "base link")->capture_default_str();
  sim_cmd->add_option("--marker-link", sim.marker_link, "link the board is fixed to")->capture_default_str();
  sim_cmd->add_option("--cameras", sim.cameras, "number of cameras (1-4)")->capture_default_str();
  sim_cmd->add_option("--frames", sim.frames, "image instants of the fastest camera")->capture_default_str();
  sim_cmd->add_option("--seed", sim.seed, "random seed")->capture_default_str();
  sim_cmd->add_option("--pixel-noise", sim.pixel_noise, "corner noise std, px")->capture_default_str();
  sim_cmd->add_option("--encoder-noise", sim.encoder_noise, "joint reading noise std, rad")->capture_default_str();
  sim_cmd->add_option("--mount-error", mount_error, "error of the rig.yaml mount prior: MM,DEG");
  sim_cmd->add_option("--distortion", sim.distortion, "radtan | equidistant | none")->capture_default_str();
  sim_cmd->add_flag("--overwrite", sim.overwrite, "replace an earlier simulation in --out");
  std::string camera_frames_csv;
  sim_cmd->add_option("--camera-frames", camera_frames_csv,
                      "comma-separated URDF links, one per camera: each camera sits at its link (moved a few mm/deg) "
                      "and rig.yaml gets frame: fields");
  std::vector<std::string> camera_delays, joint_offsets;
  std::string intrinsics_error;
  sim_cmd->add_option("--camera-delay-ms", camera_delays,
                      "NAME=MS[,NAME=MS...]: camera NAME's images show the board at their stamp + MS (its true time "
                      "offset; ground_truth.yaml time_offset_ms)");
  sim_cmd->add_option("--joint-offsets", joint_offsets,
                      "JOINT=RAD[,JOINT=RAD...]: joints.csv holds the true angle - RAD for these joints of the marker "
                      "chain (ground_truth.yaml joint_offsets)");
  sim_cmd->add_option("--intrinsics-error", intrinsics_error,
                      "PCT,PX: rig.yaml's fx, fy off by PCT % and cx, cy by PX pixels (signs from the seed); images "
                      "use the true ones (ground_truth.yaml intrinsics)");
  sim_cmd->add_option("--fov-deg", sim.fov_deg,
                      "horizontal field of view of every camera, degrees (0: each camera's own; up to 160 with "
                      "--distortion equidistant, a fisheye)");

  std::string result_path, truth_path;
  CLI::App* eval_cmd = app.add_subcommand(
      "evaluate", "Compare a calibration with ground truth (Table I, NEES; time offsets, joint offsets and intrinsics "
                  "when estimated, in sigmas)");
  eval_cmd->add_option("calibration", result_path, "calibration.yaml, or a Kalibr camchain.yaml (relative poses only)")
      ->required();
  eval_cmd->add_option("ground_truth", truth_path, "ground_truth.yaml")->required();

  fgcal::apps::DemoOptions demo;
  CLI::App* demo_cmd = app.add_subcommand("demo", "Simulate, calibrate with F1 and F2, evaluate: the whole product");
  demo_cmd->add_option("--frames", demo.frames, "image instants")->capture_default_str()->check(CLI::Range(10, 100000));
  demo_cmd->add_option("--seed", demo.seed, "random seed")->capture_default_str();
  demo_cmd->add_option("--keep", demo.keep_dir, "keep the dataset and results in this folder");

  fgcal::apps::PoseGraphDemoOptions pg;
  CLI::App* pg_cmd = app.add_subcommand("pose-graph-demo", "The core engine alone on a noisy SE(3) pose graph");
  pg_cmd->add_option("--poses", pg.poses, "number of poses")->check(CLI::Range(2, 10000000));
  pg_cmd->add_option("--seed", pg.seed, "random seed");

  std::string bag_path;
  bool bag_stamps = false;
  CLI::App* bag_info_cmd =
      app.add_subcommand("bag-info", "List a ROS 1 / ROS 2 bag's topics, types, counts and rates (no ROS needed)");
  bag_info_cmd->add_option("bag", bag_path, "a ROS 1 .bag, a ROS 2 bag folder or .db3, or an .mcap file")->required();
  bag_info_cmd->add_flag("--stamps", bag_stamps,
                         "also read header.stamp of every JointState, Image, CompressedImage and CameraInfo message "
                         "(reads those topics whole)");
  // fgcal init: a commented starter rig.yaml (apps/rig_init.hpp).
  fgcal::apps::InitOptions init;
  CLI::App* init_cmd = app.add_subcommand("init", "Write a starter rig.yaml from a URDF, the board and camera_info");
  init_cmd->add_option("--urdf", init.urdf, "robot description")->required();
  init_cmd->add_option("--base-link", init.base_link, "base link")->required();
  init_cmd->add_option("--marker-link", init.marker_link, "link the board is fixed to")->required();
  init_cmd->add_option("--board", init.board, "SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY, e.g. "
                                              "5x7:0.04:0.03:DICT_4X4_50 (metres)")->required();
  CLI::Option* init_bag = init_cmd->add_option(
      "--bag", init.bag, "ROS 1 .bag, ROS 2 bag folder or .mcap: cameras from its CameraInfo topics");
  init_cmd
      ->add_option("--camera-info", init.camera_infos,
                   "NAME:FILE or FILE: intrinsics in ROS camera_info, Kalibr camchain or OpenCV format")
      ->excludes(init_bag);
  init_cmd->add_option("-o,--output", init.output, "rig.yaml to write (its folder must exist)")->required();
  init_cmd->add_flag("--force", init.overwrite, "replace an existing output file");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // help and version print and return 0
    return rc == 0 ? 0 : 2;
  }

  try {
    if (*cal_cmd) {
      std::stringstream ss(cameras_csv);
      std::string name;
      while (std::getline(ss, name, ','))
        if (!name.empty()) cal.cameras.push_back(name);
      cal.report = !no_report;
      fgcal::apps::runCalibrate(cal, std::cerr);
      return 0;
    }
    if (*imp_cmd) {
      fgcal::apps::runImport(imp, std::cerr);
      return 0;
    }
    if (*sim_cmd) {
      if (!mount_error.empty()) {
        const auto v = parsePair(mount_error, "--mount-error");
        sim.mount_error_m = v[0] * 1e-3;
        sim.mount_error_rad = v[1] * M_PI / 180.0;
      }
      std::stringstream frames_ss(camera_frames_csv);
      for (std::string link; std::getline(frames_ss, link, ',');)
        if (!link.empty()) sim.camera_frames.push_back(link);
      sim.camera_delay_ms = fgcal::apps::parseNamedValues(camera_delays, "--camera-delay-ms");
      sim.joint_offsets_rad = fgcal::apps::parseNamedValues(joint_offsets, "--joint-offsets");
      if (!intrinsics_error.empty()) {
        const auto v = fgcal::apps::parseNumberList(intrinsics_error, "--intrinsics-error", 2, "PCT,PX");
        sim.intrinsics_error_pct = v[0];
        sim.intrinsics_error_px = v[1];
      }
      const auto s = fgcal::apps::simulateDataset(sim);
      std::cerr << "fgcal simulate: wrote " << s.images_written << " images, " << s.instants << " instants to "
                << sim.out_dir << "\n";
      return 0;
    }
    if (*eval_cmd) {
      if (fgcal::apps::looksLikeKalibrCamchain(fgcal::apps::readTextFile(result_path, "calibration result"))) {
        const auto rel = fgcal::apps::evaluateCamchain(fgcal::apps::loadKalibrCamchain(result_path),
                                                       fgcal::apps::loadGroundTruth(truth_path), result_path);
        std::cout << fgcal::apps::formatRelativeEvaluationTable(rel);
        return 0;
      }
      const auto ev = fgcal::apps::evaluateFiles(result_path, truth_path);
      std::cout << fgcal::apps::formatEvaluationTable(ev);
      return 0;
    }
    if (*bag_info_cmd) {
      std::cout << fgcal::apps::formatBagInfo(fgcal::apps::summarizeBag(bag_path, bag_stamps));
      return 0;
    }
    if (*init_cmd) {
      fgcal::apps::runInit(init, std::cout);
      return 0;
    }
    if (*demo_cmd) return fgcal::apps::runDemo(demo, std::cout);
    if (*pg_cmd) return fgcal::apps::runPoseGraphDemo(pg);
  } catch (const std::exception& e) {
    std::cerr << "fgcal: error: " << e.what() << "\n";
    return fgcal::apps::exitCodeFor(e);
  }
  return 2;
}
