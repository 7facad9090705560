// Honesty of the reported uncertainty (issue #5): over many seeds, simulate a
// dataset, calibrate it (F2 and F1), evaluate against the truth, and compare
// the mean NEES of each camera with the 95 % band of chi-square(6) for that
// many samples. Also prints mean and spread of the per-axis errors.
//
//   bench_consistency [--seeds 50] [--frames 300] [--first-seed 1] [--pixel-noise 0.5]
//                     [--encoder-noise 0.002] [--mount-error-mm 3] [--mount-error-deg 1]
//                     [--per-seed FILE] [--resample-encoders 1]
//
// Diagnostics (issue #5; BENCHMARKS.md, "Where the excess comes from"):
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
// The file's comment lines list every column.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
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

}  // namespace

int main(int argc, char** argv) {
  int seeds = 50, frames = 300;
  unsigned first = 1;
  double pixel = 0.5, encoder = 0.002, mount_mm = 3.0, mount_deg = 1.0;
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
                 "#   the truth, C = kinematic (with floors) + PnP covariance; matrices row-major\n"
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
    fgcal::apps::simulateDataset(sim);
    const auto truth = fgcal::apps::loadGroundTruth((dir / "dataset" / "ground_truth.yaml").string());
    for (const bool single : {false, true}) {
      fgcal::apps::CalibrateOptions c;
      c.dataset = sim.out_dir;
      c.single_camera = single;
      c.write_files = false;
      std::ostringstream quiet;
      auto r = fgcal::apps::runCalibrate(c, quiet);
      auto ev = fgcal::apps::evaluate(r.output, truth);
      std::optional<fgcal::apps::CalibrationSolution> resolved;  // with --resample-encoders
      if (resample) {
        const auto ds = fgcal::apps::loadDataset(sim.out_dir);
        const auto robot = fgcal::kinematics::RobotModel::fromFile(ds.rig.robot.urdf);
        const auto chain = robot.chain(ds.rig.robot.base_link, ds.rig.robot.marker_link);
        std::mt19937_64 rng(sim.seed * 7919ull);  // the same joint noise for F1 and F2
        std::normal_distribution<double> nd(0.0, 1.0);
        auto prob = r.problem;
        const fgcal::VecX sig = chain.sigmaVector(encoder);
        for (auto& o : prob.observations) {
          fgcal::VecX q = o.joint_positions;
          for (int i = 0; i < q.size(); ++i) q[i] += encoder * nd(rng);
          o.T_base_link = chain.forwardWithCovariance(q, sig, &o.link_covariance);
          o.joint_positions = q;
        }
        prob.single_camera = single;
        if (per_seed && single && truth.T_link_marker) {
          // Linearized at the truth, F1: the weighted least-squares correction
          // of (camera, mount) from the kinematic errors alone, the PnP errors
          // alone, and both (the sampled joint noise is known here). b holds
          // image errors only (no mount prior residual), so the NEES of "all"
          // should be model kinematic + model PnP; the floors and the prior
          // weigh the solve but draw no error here.
          const fgcal::SE3& M = *truth.T_link_marker;
          for (std::size_t c = 0; c < prob.camera_names.size(); ++c) {
            const std::string& cam = prob.camera_names[c];
            Eigen::Matrix<double, 12, 12> I = Eigen::Matrix<double, 12, 12>::Zero();
            Eigen::Matrix<double, 12, 3> b = Eigen::Matrix<double, 12, 3>::Zero();
            // What the model expects of each part: Cov(d) = P (sum J^T W C W J) P.
            Eigen::Matrix<double, 12, 12> Ok = Eigen::Matrix<double, 12, 12>::Zero(), Op = Ok, Of = Ok;
            for (std::size_t i = 0; i < prob.observations.size(); ++i) {
              const auto& o = prob.observations[i];
              if (o.camera != static_cast<int>(c) || !r.solution.used[i]) continue;
              const fgcal::SE3 kin_noisy = o.T_base_link * M, kin_true = r.problem.observations[i].T_base_link * M;
              const fgcal::SE3 board_cam = truth.T_base_cam.at(cam) * o.T_cam_marker;
              Eigen::Matrix<double, 6, 3> e;
              e.col(0) = kin_noisy.between(board_cam).log();
              e.col(1) = kin_noisy.between(kin_true).log();
              e.col(2) = kin_true.between(board_cam).log();
              const fgcal::Mat6 K = kinematicCovariance(o, M, prob, true);
              const fgcal::Mat6 Kraw = kinematicCovariance(o, M, prob, false);
              const Eigen::Matrix<double, 6, 12> J = imageJacobian(o);
              const fgcal::Mat6 W = (K + o.covariance).inverse();
              I += J.transpose() * W * J;
              b -= J.transpose() * W * e;
              Ok += J.transpose() * W * Kraw * W * J;
              Of += J.transpose() * W * (K - Kraw) * W * J;
              Op += J.transpose() * W * o.covariance * W * J;
            }
            Eigen::Matrix<double, 12, 12> Oprior = Eigen::Matrix<double, 12, 12>::Zero();
            Oprior.bottomRightCorner<6, 6>() = mountPriorInformation(prob);
            I += Oprior;
            const Eigen::Matrix<double, 12, 12> P = I.inverse();
            const Eigen::Matrix<double, 12, 3> d = P * b;
            std::fprintf(per_seed, "R,%u,%s", sim.seed, cam.c_str());
            for (int k = 0; k < 3; ++k) {
              const fgcal::Vec6 dc = d.col(k).head<6>();
              std::fprintf(per_seed, ",%.4f", dc.dot(P.topLeftCorner<6, 6>().ldlt().solve(dc)));
            }
            const auto Pcc = P.topLeftCorner<6, 6>().ldlt();
            for (const Eigen::Matrix<double, 12, 12>* O : {&Ok, &Op, &Of, &Oprior}) {
              const Eigen::Matrix<double, 12, 12> C = P * *O * P;
              std::fprintf(per_seed, ",%.4f", Pcc.solve(C.topLeftCorner<6, 6>()).trace());
            }
            std::fprintf(per_seed, "\n");
          }
        }
        resolved = fgcal::apps::solveCalibration(prob);
        const auto& sol = *resolved;
        for (const auto& ce : sol.cameras) ev.cameras[ce.name] = fgcal::apps::poseError(ce.T_base_cam, ce.covariance, truth.T_base_cam.at(ce.name));
        if (ev.mount) ev.mount = fgcal::apps::poseError(sol.T_link_marker, sol.mount_covariance, *truth.T_link_marker);
      }
      // F1, linearized at the truth: the weighted least-squares correction of
      // (camera, mount) from the images used, and its NEES against that
      // system's own covariance; beside the reported covariance.
      if (per_seed && single && truth.T_link_marker && !resample) {  // with --resample-encoders: the R lines
        const auto& pr = r.problem;
        for (std::size_t c = 0; c < pr.camera_names.size(); ++c) {
          const std::string& cam = pr.camera_names[c];
          Eigen::Matrix<double, 12, 12> I = Eigen::Matrix<double, 12, 12>::Zero();
          Eigen::Matrix<double, 12, 1> b = Eigen::Matrix<double, 12, 1>::Zero();
          std::vector<std::pair<std::int64_t, Eigen::Matrix<double, 12, 1>>> scores;
          for (std::size_t i = 0; i < pr.observations.size(); ++i) {
            const auto& o = pr.observations[i];
            if (o.camera != static_cast<int>(c) || !r.solution.used[i]) continue;
            const fgcal::SE3 board_kin = o.T_base_link * *truth.T_link_marker;
            const fgcal::Vec6 e = board_kin.between(truth.T_base_cam.at(cam) * o.T_cam_marker).log();
            const fgcal::Mat6 K = kinematicCovariance(o, *truth.T_link_marker, pr, true);
            const Eigen::Matrix<double, 6, 12> J = imageJacobian(o);
            const fgcal::Mat6 W = (K + o.covariance).inverse();
            I += J.transpose() * W * J;
            b -= J.transpose() * W * e;  // minimize |e + J d|^2_W
            scores.emplace_back(o.stamp_ns, J.transpose() * W * e);
          }
          const fgcal::Mat6 prior_info = mountPriorInformation(pr);
          const fgcal::Vec6 ep = pr.mount_prior.between(*truth.T_link_marker).log();
          I.bottomRightCorner<6, 6>() += prior_info;
          b.tail<6>() -= prior_info * ep;
          const Eigen::Matrix<double, 12, 12> P = I.inverse();
          const Eigen::Matrix<double, 12, 1> d = P * b;
          const fgcal::Vec6 dc = d.head<6>();
          const double lin_nees = dc.dot(P.topLeftCorner<6, 6>().ldlt().solve(dc));
          fgcal::Mat6 reported = fgcal::Mat6::Identity();
          for (const auto& cr : r.output.cameras)
            if (cr.name == cam) reported = cr.covariance;
          std::fprintf(per_seed, "L,%u,%s,%.4f,%.4f,%.4f", sim.seed, cam.c_str(), lin_nees,
                       std::sqrt(P.topLeftCorner<6, 6>().trace() / reported.trace()),
                       (P.topLeftCorner<6, 6>() - reported).norm() / reported.norm());
          // Sandwich covariance with a Bartlett-weighted (Newey-West) sum of
          // the scores' autocovariances, from the true errors, lags 0..L.
          std::sort(scores.begin(), scores.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
          for (int L : {0, 5, 10, 20, 40}) {
            Eigen::Matrix<double, 12, 12> Om = Eigen::Matrix<double, 12, 12>::Zero();
            for (std::size_t i = 0; i < scores.size(); ++i)
              for (int l = 0; l <= L && i + static_cast<std::size_t>(l) < scores.size(); ++l) {
                const double w = 1.0 - l / (L + 1.0);
                const auto& si = scores[i].second;
                const auto& sj = scores[i + static_cast<std::size_t>(l)].second;
                Om += l == 0 ? Eigen::Matrix<double, 12, 12>(si * si.transpose())
                             : Eigen::Matrix<double, 12, 12>(w * (si * sj.transpose() + sj * si.transpose()));
              }
            Om.bottomRightCorner<6, 6>() += prior_info;
            const Eigen::Matrix<double, 12, 12> Ps = P * Om * P;
            std::fprintf(per_seed, ",%.4f,%.4f", dc.dot(Ps.topLeftCorner<6, 6>().ldlt().solve(dc)),
                         std::sqrt(Ps.topLeftCorner<6, 6>().trace() / P.topLeftCorner<6, 6>().trace()));
          }
          std::fprintf(per_seed, "\n");
        }
      }
      if (per_seed && !single && truth.T_link_marker) {  // with --resample-encoders: the noise-free joints
        const auto& pr = r.problem;
        for (const auto& o : pr.observations) {
          const std::string& cam = pr.camera_names[static_cast<std::size_t>(o.camera)];
          const fgcal::SE3 board_kin = o.T_base_link * *truth.T_link_marker;
          const fgcal::SE3 board_pnp = truth.T_base_cam.at(cam) * o.T_cam_marker;
          const fgcal::Vec6 e = board_kin.between(board_pnp).log();
          const fgcal::Mat6 K = kinematicCovariance(o, *truth.T_link_marker, pr, true);
          const double n = e.dot((K + o.covariance).ldlt().solve(e));
          std::fprintf(per_seed, "I,%u,%s,%s,%.4f,%.4f,%.4f", sim.seed, o.image.c_str(), cam.c_str(), n,
                       e.head<3>().norm() * 1e3, e.tail<3>().norm() * 1e3);
          const fgcal::Mat6 C = K + o.covariance;
          for (int i = 0; i < 6; ++i) std::fprintf(per_seed, ",%.9g", e[i]);
          for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) std::fprintf(per_seed, ",%.9g", C(i, j));
          const fgcal::Mat3 Rbm = board_kin.rotation(), Rcm = o.T_cam_marker.rotation();
          const fgcal::Mat3 Rlm = truth.T_link_marker->rotation();
          for (const fgcal::Mat3* R : {&Rbm, &Rcm, &Rlm})
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) std::fprintf(per_seed, ",%.9g", (*R)(i, j));
          std::fprintf(per_seed, ",%lld\n", static_cast<long long>(o.stamp_ns));
        }
      }
      auto add = [&](const std::string& who, const fgcal::apps::PoseError& e) {
        if (per_seed) {
          const fgcal::apps::CalibrationSolution& solved = resolved ? *resolved : r.solution;
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
