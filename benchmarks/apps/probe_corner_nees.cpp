// Corner graph against the PnP graph on synthetic corners (no rendering, so
// the corner noise is exactly the stated Gaussian): mean camera errors and
// the mean NEES of each method over seeds, at a given pixel noise. A quick
// look between the rendered runs of bench_accuracy / bench_consistency,
// which include the detector's own errors.
//
//   probe_corner_nees [--seeds 20] [--instants 300] [--pixel-noise 0.5] [--distortion radtan]
//                     [--intrinsics-error PCT,PX] [--estimate-intrinsics] [--board 5x7]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "calibration/synthetic_corners.hpp"
#include "fgcal/apps/corner_calibration.hpp"

namespace {
struct Stats {
  double sum = 0, sq = 0;
  int n = 0;
  void add(double x) {
    sum += x;
    sq += x * x;
    ++n;
  }
  double mean() const { return n ? sum / n : NAN; }
  double sd() const { return n > 1 ? std::sqrt(std::max(0.0, (sq - sum * sum / n) / (n - 1))) : NAN; }
};
}  // namespace

int main(int argc, char** argv) {
  using namespace fgcal;
  using namespace fgcal::apps;
  synthetic::CornerProblemOptions opt;
  opt.instants = 300;
  int seeds = 20;
  bool estimate = false;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--estimate-intrinsics") {
      estimate = true;
      continue;
    }
    if (i + 1 >= argc) return 2;
    const std::string v = argv[++i];
    if (k == "--seeds") seeds = std::atoi(v.c_str());
    else if (k == "--instants") opt.instants = std::atoi(v.c_str());
    else if (k == "--pixel-noise") opt.pixel_sigma = std::atof(v.c_str());
    else if (k == "--distortion") opt.distortion = v;
    else if (k == "--intrinsics-error") std::sscanf(v.c_str(), "%lf,%lf", &opt.intrinsics_error_pct, &opt.intrinsics_error_px);
    else if (k == "--board") std::sscanf(v.c_str(), "%dx%d", &opt.squares_x, &opt.squares_y);
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  Stats t_pnp, r_pnp, n_pnp, t_cor, r_cor, n_cor;
  int pnp_failed = 0;
  for (int s = 1; s <= seeds; ++s) {
    opt.seed = static_cast<unsigned>(s);
    synthetic::CornerProblem d = synthetic::makeCornerProblem(opt);
    d.corners.estimate_intrinsics = estimate;
    CalibrationSolution pnp;
    bool pnp_ok = true;
    try {
      pnp = solveCalibration(d.problem);
    } catch (const std::exception& e) {
      ++pnp_failed;  // the corner graph then starts from the detections and the kinematics
      pnp_ok = false;
    }
    const CornerSolution cs = solveCornerCalibration(d.problem, d.corners, pnp);
    for (std::size_t c = 0; c < d.true_cameras.size(); ++c) {
      const auto add = [&](const CameraEstimate& e, Stats& t, Stats& r, Stats& n) {
        const Vec6 err = d.true_cameras[c].minus(e.T_base_cam);
        t.add(1e3 * (e.T_base_cam.translation() - d.true_cameras[c].translation()).norm());
        r.add(err.head<3>().norm() * 180.0 / M_PI);
        n.add(err.dot(e.covariance.ldlt().solve(err)));
      };
      if (pnp_ok) add(pnp.cameras[c], t_pnp, r_pnp, n_pnp);
      add(cs.solution.cameras[c], t_cor, r_cor, n_cor);
    }
  }
  std::printf("%d seeds x %d cameras, %d instants, %.2f px, %s, intrinsics error %.1f %% / %.1f px%s\n", seeds,
              opt.cameras, opt.instants, opt.pixel_sigma, opt.distortion.c_str(), opt.intrinsics_error_pct,
              opt.intrinsics_error_px, estimate ? ", estimated" : "");
  std::printf("| method | translation mm | rotation deg | mean NEES (6: honest) |\n|---|---|---|---|\n");
  std::printf("| pnp | %.3f (%.3f) | %.4f (%.4f) | %.2f | failed on %d seed(s) |\n", t_pnp.mean(), t_pnp.sd(),
              r_pnp.mean(), r_pnp.sd(), n_pnp.mean(), pnp_failed);
  std::printf("| corners | %.3f (%.3f) | %.4f (%.4f) | %.2f |\n", t_cor.mean(), t_cor.sd(), r_cor.mean(), r_cor.sd(),
              n_cor.mean());
  return 0;
}
