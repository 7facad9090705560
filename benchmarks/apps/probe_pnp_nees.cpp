// Is the per-image PnP covariance honest? Simulates datasets without encoder
// noise (so forward kinematics at the image stamp gives the true board pose),
// estimates each image's T_cam_marker by PnP, and compares the error against
// the truth with the reported covariance: NEES per image (chi-square(6) mean
// 6), the variance ratio per axis, and the mean error (a bias would not
// average out over images).
//
//   probe_pnp_nees [--seeds 5] [--frames 60] [--pixel-noise 0.5] [--sigma stated|residuals|larger]
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"

using namespace fgcal;

int main(int argc, char** argv) {
  int seeds = 5, frames = 60;
  double pixel = 0.5;
  std::string sigma = "larger";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--seeds") seeds = std::atoi(v.c_str());
    else if (k == "--frames") frames = std::atoi(v.c_str());
    else if (k == "--pixel-noise") pixel = std::atof(v.c_str());
    else if (k == "--sigma") sigma = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  vision::PnpOptions pnp;
  pnp.sigma_source = sigma == "stated"      ? vision::PnpOptions::SigmaSource::PixelSigma
                     : sigma == "residuals" ? vision::PnpOptions::SigmaSource::Residuals
                                            : vision::PnpOptions::SigmaSource::Larger;
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("fgcal-pnp-nees-" + std::to_string(::getpid()));
  struct Acc {
    int n = 0;
    double nees = 0;
    Vec6 ratio = Vec6::Zero(), mean_cam = Vec6::Zero(), sq_cam = Vec6::Zero();
  };
  std::map<std::string, Acc> acc;
  for (int s = 0; s < seeds; ++s) {
    fs::remove_all(dir);
    apps::SimulationOptions sim;
    sim.out_dir = (dir / "dataset").string();
    sim.frames = frames;
    sim.seed = 1000u + static_cast<unsigned>(s);
    sim.pixel_noise = pixel;
    sim.encoder_noise = 0.0;
    apps::simulateDataset(sim);
    const auto truth = apps::loadGroundTruth((dir / "dataset" / "ground_truth.yaml").string());
    const apps::Dataset ds = apps::loadDataset(sim.out_dir);
    const auto robot = kinematics::RobotModel::fromFile(ds.rig.robot.urdf);
    const auto chain = robot.chain(ds.rig.robot.base_link, ds.rig.robot.marker_link);
    const auto columns = apps::columnIndices(ds.joints, chain.jointNames(), "joints.csv");
    const vision::CharucoTarget target{ds.rig.target.squares_x, ds.rig.target.squares_y, ds.rig.target.square_size,
                                       ds.rig.target.marker_size, ds.rig.target.dictionary};
    const vision::CharucoDetector detector(target);
    for (const auto& cc : ds.rig.cameras) {
      const auto model = vision::CameraModel::fromKalibr(
          cc.camera_model, cc.distortion_model, std::vector<double>(cc.intrinsics.begin(), cc.intrinsics.end()),
          cc.distortion_coeffs, {cc.resolution[0], cc.resolution[1]});
      pnp.pixel_sigma = cc.pixel_sigma;
      for (const auto& im : ds.images) {
        if (im.camera != cc.name) continue;
        const auto det = detector.detectFile(im.path);
        if (!det.ok()) continue;
        vision::PoseEstimate est;
        try {
          est = vision::estimatePose(model, det, pnp);
        } catch (const std::exception&) {
          continue;
        }
        const auto q = apps::interpolate(ds.joints, im.stamp_ns, columns, nullptr);
        if (!q) continue;
        const SE3 T_true = truth.T_base_cam.at(cc.name).inverse() * chain.forward(*q) * *truth.T_link_marker;
        const Vec6 e = T_true.inverse().compose(est.T_cam_marker).log();  // T_est = T_true * exp(e)
        Acc& a = acc[cc.name];
        ++a.n;
        a.nees += e.dot(est.covariance.ldlt().solve(e));
        a.ratio += e.cwiseAbs2().cwiseQuotient(est.covariance.diagonal());
        Vec6 ec;  // in camera axes
        ec << T_true.rotation() * e.head<3>(), T_true.rotation() * e.tail<3>();
        a.mean_cam += ec;
        a.sq_cam += ec.cwiseAbs2();
      }
    }
    std::fprintf(stderr, "seed %d done\n", s + 1);
  }
  fs::remove_all(dir);
  std::printf("PnP per-image NEES, %d seeds x %d frames, %.2f px, sigma %s\n", seeds, frames, pixel, sigma.c_str());
  for (auto& [name, a] : acc) {
    std::printf("%s: %d images, mean NEES %.2f (6 expected)\n  variance ratio wx wy wz vx vy vz:", name.c_str(), a.n,
                a.nees / a.n);
    for (int i = 0; i < 6; ++i) std::printf(" %.2f", a.ratio[i] / a.n);
    std::printf("\n  mean error in camera axes (mrad, mm) +- its standard error:");
    for (int i = 0; i < 6; ++i) {
      const double m = a.mean_cam[i] / a.n, var = a.sq_cam[i] / a.n - m * m;
      std::printf(" %.3f+-%.3f", 1e3 * m, 1e3 * std::sqrt(var / a.n));
    }
    std::printf("\n");
  }
  return 0;
}
