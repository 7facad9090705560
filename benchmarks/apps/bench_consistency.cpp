// Honesty of the reported uncertainty: over many seeds, simulate a
// dataset, calibrate it (F2 and F1), evaluate against the truth, and compare
// the mean NEES of each camera with the 95 % band of chi-square(6) for that
// many samples. Also prints mean and spread of the per-axis errors.
//
//   bench_consistency [--seeds 50] [--frames 300] [--first-seed 1] [--pixel-noise 0.5]
//                     [--encoder-noise 0.002] [--mount-error-mm 3] [--mount-error-deg 1]
//                     [--per-seed FILE] [--resample-encoders 1] [--cam1-delay-us 200]
//                     [--pnp-covariance-scale 1.3]
//
// Diagnostics (used by docs/studies/uncertainty.md):
//   --per-seed FILE   CSV: one line per seed and estimate (NEES, errors,
//                     images rejected); "I," lines, one per image, with the
//                     error of its factors at the truth, their covariance and
//                     rotations; "L," lines, one per F1 camera, with the
//                     weighted least-squares correction linearized at the
//                     truth (its NEES, and Newey-West sandwich NEES).
//   --resample-encoders 1
//                     simulate without encoder noise, draw white joint noise
//                     here (sigma --encoder-noise) and re-solve: the
//                     kinematic and PnP errors are then known apart ("R,"
//                     lines: NEES of the correction from all, kinematic and
//                     PnP errors, and what the model expects of the parts).
//   --cam1-delay-us U the simulated cam1 exposure after cam0's (default that of
//                     fgcal simulate, 200 us).
//   --pnp-covariance-scale F  what fgcal calibrate's option of that name sets
//                     (default the product's); 1 treats the images as independent.
// The file's comment lines list every column.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <exception>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/kinematics/robot_model.hpp"

namespace {

// Quantile of chi-square(k) by the Wilson-Hilferty approximation (ample for k >= 30).
double chi2Quantile(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

struct Stats {
  std::vector<double> v;
  double mean() const {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? NAN : s / v.size();
  }
  double sd() const {
    const double m = mean();
    double s = 0;
    for (double x : v) s += (x - m) * (x - m);
    return v.size() < 2 ? NAN : std::sqrt(s / (v.size() - 1));
  }
};

/// The kinematic covariance at the marker the calibration uses for `o` (the
/// encoder noise through the leg Jacobian), with or without the floors.
fgcal::Mat6 kinematicCovariance(const fgcal::apps::BoardObservation& o, const fgcal::SE3& T_link_marker,
                                const fgcal::apps::CalibrationProblemInput& pr, bool with_floors) {
  fgcal::Mat6 K = fgcal::KinematicFactor::markerCovariance(o.link_covariance, T_link_marker);
  if (with_floors) {
    K.diagonal().head<3>().array() += pr.kinematic_floor_rad * pr.kinematic_floor_rad;
    K.diagonal().tail<3>().array() += pr.kinematic_floor_m * pr.kinematic_floor_m;
  }
  return K;
}

/// The PnP covariance of `o` as the fiducial factor weighs it (times the scale).
fgcal::Mat6 pnpCovariance(const fgcal::apps::BoardObservation& o, const fgcal::apps::CalibrationProblemInput& pr) {
  return pr.fiducial_covariance_scale * o.covariance.matrix();
}

/// F1, one image, the board pose eliminated: e = Log((FK(q) M)^-1 T_base_cam
/// T_cam_marker) moves by J [d_cam; d_mount] (right perturbations).
Eigen::Matrix<double, 6, 12> imageJacobian(const fgcal::apps::BoardObservation& o) {
  Eigen::Matrix<double, 6, 12> J;
  J.leftCols<6>() = o.T_cam_marker.inverse().adjoint();
  J.rightCols<6>() = -fgcal::Mat6::Identity();
  return J;
}

/// The mount prior's information, [w v].
fgcal::Mat6 mountPriorInformation(const fgcal::apps::CalibrationProblemInput& pr) {
  fgcal::Vec6 sp;
  sp << pr.mount_sigma_rad, pr.mount_sigma_rad, pr.mount_sigma_rad, pr.mount_sigma_m, pr.mount_sigma_m,
      pr.mount_sigma_m;
  return sp.cwiseAbs2().cwiseInverse().asDiagonal();
}

using Mat12 = Eigen::Matrix<double, 12, 12>;
using fgcal::apps::BoardObservation;
using fgcal::apps::CalibrationProblemInput;

/// Calls f(i, o, K, J, W) for every image of camera c the solve used:
/// K the kinematic covariance at the true mount (with floors), J the image's
/// Jacobian, W = (K + scaled PnP covariance)^-1, as the calibration weighs it.
template <class F>
void forEachUsedImage(const CalibrationProblemInput& pr, const std::vector<char>& used, std::size_t c,
                      const fgcal::SE3& M, F f) {
  for (std::size_t i = 0; i < pr.observations.size(); ++i) {
    const BoardObservation& o = pr.observations[i];
    if (o.camera != static_cast<int>(c) || !used[i]) continue;
    const fgcal::Mat6 K = kinematicCovariance(o, M, pr, true);
    f(i, o, K, imageJacobian(o), fgcal::Mat6((K + pnpCovariance(o, pr)).inverse()));
  }
}

/// NEES of the camera part of d against the camera block of P.
double cameraNees(const Eigen::Matrix<double, 12, 1>& d, const Mat12& P) {
  const fgcal::Vec6 dc = d.head<6>();
  return dc.dot(P.topLeftCorner<6, 6>().ldlt().solve(dc));
}

/// "I," lines: every image's error at the truth (F2 run).
void writeImageLines(FILE* out, unsigned seed, const CalibrationProblemInput& pr, const fgcal::apps::GroundTruth& truth) {
  const fgcal::SE3& M = *truth.T_link_marker;
  for (const BoardObservation& o : pr.observations) {
    const std::string& cam = pr.camera_names[static_cast<std::size_t>(o.camera)];
    const fgcal::SE3 board_kin = o.T_base_link * M;
    const fgcal::Vec6 e = board_kin.between(truth.T_base_cam.at(cam) * o.T_cam_marker).log();
    // The image's own covariance (PnP unscaled): a per-image check, and what
    // cross_image_terms.py splits into independent and cross-image parts.
    const fgcal::Mat6 C = kinematicCovariance(o, M, pr, true) + o.covariance.matrix();
    const std::string image = cam + "/" + std::to_string(o.stamp_ns);  // the image's name in a dataset folder, less its extension
    std::fprintf(out, "I,%u,%s,%s,%.4f,%.4f,%.4f", seed, image.c_str(), cam.c_str(), e.dot(C.ldlt().solve(e)),
                 e.head<3>().norm() * 1e3, e.tail<3>().norm() * 1e3);
    for (int i = 0; i < 6; ++i) std::fprintf(out, ",%.9g", e[i]);
    for (int i = 0; i < 36; ++i) std::fprintf(out, ",%.9g", C(i / 6, i % 6));
    for (const fgcal::Mat3& R : {board_kin.rotation(), o.T_cam_marker.rotation(), M.rotation()})
      for (int i = 0; i < 9; ++i) std::fprintf(out, ",%.9g", R(i / 3, i % 3));
    std::fprintf(out, ",%lld\n", static_cast<long long>(o.stamp_ns));
  }
}

/// "L," lines, F1: the weighted least-squares correction of (camera, mount)
/// linearized at the truth, its NEES, its covariance against the reported one,
/// and Newey-West sandwich variants.
void writeLinearizedLines(FILE* out, unsigned seed, const CalibrationProblemInput& pr,
                          const fgcal::apps::CalibrateResult& r, const fgcal::apps::GroundTruth& truth) {
  const fgcal::SE3& M = *truth.T_link_marker;
  for (std::size_t c = 0; c < pr.camera_names.size(); ++c) {
    const std::string& cam = pr.camera_names[c];
    Mat12 I = Mat12::Zero();
    Eigen::Matrix<double, 12, 1> b = Eigen::Matrix<double, 12, 1>::Zero();
    std::vector<std::pair<std::int64_t, Eigen::Matrix<double, 12, 1>>> scores;
    forEachUsedImage(pr, r.solution.used, c, M, [&](std::size_t, const BoardObservation& o, const fgcal::Mat6&,
                                                   const Eigen::Matrix<double, 6, 12>& J, const fgcal::Mat6& W) {
      const fgcal::Vec6 e = (o.T_base_link * M).between(truth.T_base_cam.at(cam) * o.T_cam_marker).log();
      I += J.transpose() * W * J;
      b -= J.transpose() * W * e;  // minimize |e + J d|^2_W
      scores.emplace_back(o.stamp_ns, J.transpose() * W * e);
    });
    const fgcal::Mat6 prior_info = mountPriorInformation(pr);
    I.bottomRightCorner<6, 6>() += prior_info;
    b.tail<6>() -= prior_info * pr.mount_prior.between(M).log();
    const Mat12 P = I.inverse();
    const Eigen::Matrix<double, 12, 1> d = P * b;
    const auto reported = std::find_if(r.output.cameras.begin(), r.output.cameras.end(),
                                       [&](const auto& cr) { return cr.name == cam; });
    if (reported == r.output.cameras.end()) continue;  // not calibrated: no line
    const fgcal::Mat6& Pr = reported->covariance;
    std::fprintf(out, "L,%u,%s,%.4f,%.4f,%.4f", seed, cam.c_str(), cameraNees(d, P),
                 std::sqrt(P.topLeftCorner<6, 6>().trace() / Pr.trace()),
                 (P.topLeftCorner<6, 6>() - Pr).norm() / Pr.norm());
    // Sandwich covariance with a Bartlett-weighted (Newey-West) sum of the
    // scores' autocovariances, from the true errors, lags 0..L.
    std::sort(scores.begin(), scores.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (int L : {0, 5, 10, 20, 40}) {
      Mat12 Om = Mat12::Zero();
      for (std::size_t i = 0; i < scores.size(); ++i) {
        const auto& si = scores[i].second;
        Om += si * si.transpose();
        for (int l = 1; l <= L && i + static_cast<std::size_t>(l) < scores.size(); ++l) {
          const auto& sj = scores[i + static_cast<std::size_t>(l)].second;
          Om += (1.0 - l / (L + 1.0)) * (si * sj.transpose() + sj * si.transpose());
        }
      }
      Om.bottomRightCorner<6, 6>() += prior_info;
      const Mat12 Ps = P * Om * P;
      std::fprintf(out, ",%.4f,%.4f", cameraNees(d, Ps),
                   std::sqrt(Ps.topLeftCorner<6, 6>().trace() / P.topLeftCorner<6, 6>().trace()));
    }
    std::fprintf(out, "\n");
  }
}

/// "R," lines, F1 with resampled joints: the same correction from all image
/// errors, the kinematic errors alone and the PnP errors alone, and what the
/// model expects of the kinematic, PnP, floor and prior parts. b holds image
/// errors only (no prior residual), so "all" should match kinematic + PnP;
/// the floors and the prior weigh the solve but draw no error here.
void writeSplitLines(FILE* out, unsigned seed, const CalibrationProblemInput& noisy,
                     const CalibrationProblemInput& exact, const std::vector<char>& used,
                     const fgcal::apps::GroundTruth& truth) {
  const fgcal::SE3& M = *truth.T_link_marker;
  for (std::size_t c = 0; c < noisy.camera_names.size(); ++c) {
    const std::string& cam = noisy.camera_names[c];
    Mat12 I = Mat12::Zero(), Ok = Mat12::Zero(), Op = Mat12::Zero(), Of = Mat12::Zero(), Oprior = Mat12::Zero();
    Eigen::Matrix<double, 12, 3> b = Eigen::Matrix<double, 12, 3>::Zero();
    forEachUsedImage(noisy, used, c, M, [&](std::size_t i, const BoardObservation& o, const fgcal::Mat6& K,
                                            const Eigen::Matrix<double, 6, 12>& J, const fgcal::Mat6& W) {
      const fgcal::SE3 kin_noisy = o.T_base_link * M, kin_true = exact.observations[i].T_base_link * M;
      const fgcal::SE3 board_cam = truth.T_base_cam.at(cam) * o.T_cam_marker;
      Eigen::Matrix<double, 6, 3> e;
      e << kin_noisy.between(board_cam).log(), kin_noisy.between(kin_true).log(), kin_true.between(board_cam).log();
      const fgcal::Mat6 Kraw = kinematicCovariance(o, M, noisy, false);
      I += J.transpose() * W * J;
      b -= J.transpose() * W * e;
      Ok += J.transpose() * W * Kraw * W * J;
      Of += J.transpose() * W * (K - Kraw) * W * J;
      Op += J.transpose() * W * pnpCovariance(o, noisy) * W * J;
    });
    Oprior.bottomRightCorner<6, 6>() = mountPriorInformation(noisy);
    I += Oprior;
    const Mat12 P = I.inverse();
    const Eigen::Matrix<double, 12, 3> d = P * b;
    std::fprintf(out, "R,%u,%s", seed, cam.c_str());
    for (int k = 0; k < 3; ++k) std::fprintf(out, ",%.4f", cameraNees(d.col(k), P));
    const auto Pcc = P.topLeftCorner<6, 6>().ldlt();
    for (const Mat12* O : {&Ok, &Op, &Of, &Oprior})
      std::fprintf(out, ",%.4f", Pcc.solve(Mat12(P * *O * P).topLeftCorner<6, 6>()).trace());
    std::fprintf(out, "\n");
  }
}

/// The problem with its joints moved by white N(0, sigma^2) noise, forward
/// kinematics and covariances recomputed through the dataset's leg chain.
CalibrationProblemInput resampleJoints(const CalibrationProblemInput& exact, const std::string& dataset, double sigma,
                                       unsigned seed) {
  const auto ds = fgcal::apps::loadDataset(dataset);
  const auto robot = fgcal::kinematics::RobotModel::fromFile(ds.rig.robot.urdf);
  const auto chain = robot.chain(ds.rig.robot.base_link, ds.rig.robot.marker_link);
  std::mt19937_64 rng(seed * 7919ull);
  std::normal_distribution<double> nd(0.0, 1.0);
  CalibrationProblemInput noisy = exact;
  const fgcal::VecX sig = chain.sigmaVector(sigma);
  for (BoardObservation& o : noisy.observations) {
    for (int i = 0; i < o.joint_positions.size(); ++i) o.joint_positions[i] += sigma * nd(rng);
    fgcal::Mat6 link_covariance;
    o.T_base_link = chain.forwardWithCovariance(o.joint_positions, sig, &link_covariance);
    o.link_covariance = link_covariance;
  }
  return noisy;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  int seeds = 50, frames = 300;
  unsigned first = 1;
  double pixel = 0.5, encoder = 0.002, mount_mm = 3.0, mount_deg = 1.0;
  double cam1_delay_us = fgcal::apps::SimulationOptions{}.cam1_delay_us;
  double pnp_scale = fgcal::apps::kDefaultFiducialCovarianceScale;
  std::string per_seed_path;
  // Experiment: simulate without encoder noise, then draw white N(0, sigma^2)
  // joint noise per image here and re-solve (isolates the dataset's encoder
  // path from the estimator).
  bool resample = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const double v = std::atof(argv[i + 1]);
    if (k == "--per-seed") per_seed_path = argv[i + 1];
    else if (k == "--resample-encoders") resample = v != 0.0;
    else if (k == "--seeds") seeds = static_cast<int>(v);
    else if (k == "--frames") frames = static_cast<int>(v);
    else if (k == "--first-seed") first = static_cast<unsigned>(v);
    else if (k == "--pixel-noise") pixel = v;
    else if (k == "--encoder-noise") encoder = v;
    else if (k == "--mount-error-mm") mount_mm = v;
    else if (k == "--mount-error-deg") mount_deg = v;
    else if (k == "--cam1-delay-us") cam1_delay_us = v;
    else if (k == "--pnp-covariance-scale") pnp_scale = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("fgcal-consistency-" + std::to_string(::getpid()));
  std::map<std::string, std::map<std::string, Stats>> stats;  // method/camera -> quantity -> samples
  FILE* per_seed = nullptr;
  if (!per_seed_path.empty()) {
    per_seed = std::fopen(per_seed_path.c_str(), "w");
    if (!per_seed) {
      std::fprintf(stderr, "cannot write %s: %s\n", per_seed_path.c_str(), std::strerror(errno));
      return 2;
    }
    std::fprintf(per_seed, "seed,method,estimate,nees,translation_mm,rotation_deg,images_used,images_rejected\n");
    std::fprintf(per_seed,
                 "# images_used is -1 for the mount. Other lines, by their first field:\n"
                 "# I,seed,image,camera,nees,|e_w| mrad,|e_v| mm, e[6], C[36], R_base_marker[9], R_cam_marker[9],\n"
                 "#   R_link_marker[9], stamp_ns: per image (F2 run), e = Log((FK(q) M)^-1 T_base_cam T_cam_marker) at\n"
                 "#   the truth, C = kinematic (with floors) + PnP covariance (unscaled: the image's own); matrices\n"
                 "#   row-major. L and R lines weigh the PnP covariance times --pnp-covariance-scale, as the graph\n"
                 "#   does\n"
                 "# L,seed,camera,nees,sqrt(tr P / tr reported),|P - reported|/|reported|, then for lags 0,5,10,20,40:\n"
                 "#   nees against the Newey-West sandwich, sqrt(tr sandwich / tr P): F1 correction linearized at the truth\n"
                 "# R,seed,camera,nees all,nees kinematic,nees PnP,model kinematic,model PnP,model floors,model prior:\n"
                 "#   with --resample-encoders, the same correction split (image errors only; all = kinematic + PnP)\n");
  }
  for (int s = 0; s < seeds; ++s) {
    fs::remove_all(dir);
    fgcal::apps::SimulationOptions sim;
    sim.out_dir = (dir / "dataset").string();
    sim.frames = frames;
    sim.seed = first + static_cast<unsigned>(s);
    sim.pixel_noise = pixel;
    sim.encoder_noise = resample ? 0.0 : encoder;
    sim.mount_error_m = mount_mm * 1e-3;
    sim.mount_error_rad = mount_deg * M_PI / 180.0;
    sim.cam1_delay_us = cam1_delay_us;
    fgcal::apps::simulateDataset(sim);
    const auto truth = fgcal::apps::loadGroundTruth((dir / "dataset" / "ground_truth.yaml").string());
    const bool diagnose = per_seed && truth.T_link_marker;
    std::optional<CalibrationProblemInput> noisy;  // with --resample-encoders: one draw for F2 and F1
    for (const bool single : {false, true}) {
      fgcal::apps::CalibrateOptions c;
      c.dataset = sim.out_dir;
      c.single_camera = single;
      c.pnp_covariance_scale = pnp_scale;
      c.write_files = false;
      c.trace.problem = true;  // the detections, re-solved below under other settings
      std::ostringstream quiet;
      const auto r = fgcal::apps::runCalibrate(c, quiet);
      const CalibrationProblemInput& problem = *r.trace.problem;
      auto ev = fgcal::apps::evaluate(r.output, truth);
      std::optional<fgcal::apps::CalibrationSolution> resolved;
      if (resample) {
        if (!noisy) noisy = resampleJoints(problem, sim.out_dir, encoder, sim.seed);
        noisy->single_camera = single;
        if (diagnose && single) writeSplitLines(per_seed, sim.seed, *noisy, problem, r.solution.used, truth);
        resolved = fgcal::apps::solveCalibration(*noisy);
        for (const auto& ce : resolved->cameras)
          ev.cameras[ce.name] = fgcal::apps::poseError(ce.T_base_cam, ce.covariance, truth.T_base_cam.at(ce.name));
        if (ev.mount)
          ev.mount = fgcal::apps::poseError(resolved->T_link_marker, resolved->mount_covariance, *truth.T_link_marker);
      } else if (diagnose && single) {
        writeLinearizedLines(per_seed, sim.seed, problem, r, truth);
      }
      if (diagnose && !single) writeImageLines(per_seed, sim.seed, problem, truth);  // resampled: exact joints
      const fgcal::apps::CalibrationSolution& solved = resolved ? *resolved : r.solution;
      auto add = [&](const std::string& who, const fgcal::apps::PoseError& e) {
        if (per_seed) {
          int used = -1;
          for (const auto& ce : solved.cameras)
            if (ce.name == who) used = ce.observations_used;
          std::fprintf(per_seed, "%u,%s,%s,%.4f,%.4f,%.5f,%d,%zu\n", sim.seed, single ? "F1" : "F2", who.c_str(),
                       e.nees, e.translation_mm, e.rotation_deg, used, solved.rejected.size());
          std::fflush(per_seed);
        }
        auto& m = stats[std::string(single ? "F1 " : "F2 ") + who];
        m["x_mm"].v.push_back(e.x_mm);
        m["y_mm"].v.push_back(e.y_mm);
        m["z_mm"].v.push_back(e.z_mm);
        m["roll_deg"].v.push_back(e.roll_deg);
        m["pitch_deg"].v.push_back(e.pitch_deg);
        m["yaw_deg"].v.push_back(e.yaw_deg);
        m["nees"].v.push_back(e.nees);
      };
      for (const auto& [name, e] : ev.cameras) add(name, e);
      if (ev.mount && !std::isnan(ev.mount->nees)) add("mount", *ev.mount);
    }
    std::fprintf(stderr, "seed %u done (%d/%d)\n", sim.seed, s + 1, seeds);
  }
  fs::remove_all(dir);
  if (per_seed) std::fclose(per_seed);

  const double lo = chi2Quantile(6.0 * seeds, -1.959964) / seeds, hi = chi2Quantile(6.0 * seeds, 1.959964) / seeds;
  std::printf("%d seeds, %d frames, %.2f px, %.4f rad, mount error %.1f mm / %.1f deg\n", seeds, frames, pixel,
              encoder, mount_mm, mount_deg);
  std::printf("mean absolute error (std) per axis; NEES mean must lie in [%.2f, %.2f] (chi-square(6) 95 %% band)\n",
              lo, hi);
  std::printf("| estimate | x mm | y mm | z mm | roll deg | pitch deg | yaw deg | mean NEES | in band |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  int outside = 0;
  for (auto& [who, m] : stats) {
    std::printf("| %s ", who.c_str());
    for (const char* q : {"x_mm", "y_mm", "z_mm"}) std::printf("| %.3f (%.3f) ", m[q].mean(), m[q].sd());
    for (const char* q : {"roll_deg", "pitch_deg", "yaw_deg"}) std::printf("| %.4f (%.4f) ", m[q].mean(), m[q].sd());
    const double nees = m["nees"].mean();
    const bool in = nees >= lo && nees <= hi;
    outside += !in;
    std::printf("| %.2f | %s |\n", nees, in ? "yes" : "NO");
  }
  return outside == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // e.g. a simulation option out of range
    std::fprintf(stderr, "bench_consistency: %s\n", e.what());
    return 2;
  }
}
