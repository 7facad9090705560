// Is the per-image PnP covariance honest? Simulates datasets without encoder
// noise (so forward kinematics at the image stamp gives the true board pose),
// estimates each image's T_cam_marker by PnP, and compares the error against
// the truth with the reported covariance: NEES per image (chi-square(6) mean
// 6), the variance ratio per axis, and the mean error (a bias would not
// average out over images).
//
//   probe_pnp_nees [--seeds 5] [--frames 60] [--pixel-noise 0.5] [--sigma stated|residuals|larger]
//                  [--corners 1] [--synthetic M] [--dump FILE]
//
// Experimental diagnostics (off by default):
//   --corners 1       detected corners against the true projections: mean
//                     offset (u, v) and its pattern over image region, depth,
//                     board tilt and radius.
//   --synthetic M     replace the detected corners by the true projections
//                     plus N(0, pixel_noise^2) (same corner ids), M draws per
//                     image: PnP alone, without renderer or detector.
//   --dump FILE       one CSV line per image (seed, camera, stamp, draw, the
//                     error e = Log(T_true^-1 T_est), the reported covariance
//                     and the true rotation R_cam_marker, all row-major):
//                     for correlations between images, which the per-image
//                     NEES cannot show.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
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
using vision::Vec2;

int main(int argc, char** argv) {
  int seeds = 5, frames = 60;
  double pixel = 0.5;
  std::string sigma = "larger";
  int corners = 0, synthetic = 0;
  std::string dump_path;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--seeds") seeds = std::atoi(v.c_str());
    else if (k == "--frames") frames = std::atoi(v.c_str());
    else if (k == "--pixel-noise") pixel = std::atof(v.c_str());
    else if (k == "--sigma") sigma = v;
    else if (k == "--corners") corners = std::atoi(v.c_str());
    else if (k == "--synthetic") synthetic = std::atoi(v.c_str());
    else if (k == "--dump") dump_path = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  FILE* dump = nullptr;
  if (!dump_path.empty() && !(dump = std::fopen(dump_path.c_str(), "w"))) {
    std::fprintf(stderr, "cannot write %s: %s\n", dump_path.c_str(), std::strerror(errno));
    return 2;
  }
  vision::PnpOptions pnp;
  pnp.sigma_source = sigma == "stated"      ? vision::PnpOptions::SigmaSource::PixelSigma
                     : sigma == "residuals" ? vision::PnpOptions::SigmaSource::Residuals
                                            : vision::PnpOptions::SigmaSource::Larger;
  // Corner offsets (detected - true projection), px: sums over groups.
  struct Off {
    long n = 0;
    double su = 0, sv = 0, suu = 0, svv = 0;
    void add(const Vec2& d) { ++n; su += d.x(); sv += d.y(); suu += d.x() * d.x(); svv += d.y() * d.y(); }
  };
  struct CornerAcc {
    Off all, img_mean;  // img_mean: one sample per image (its mean offset)
    Off region[3][3], depth[4], tilt[4], radius[4];
    Off radial;  // x: offset along the radial direction, y: tangential
  };
  std::map<std::string, CornerAcc> cacc;
  double pnp_seconds = 0;
  long pnp_calls = 0;
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
        const auto q = apps::interpolate(ds.joints, im.stamp_ns, columns, nullptr);
        if (!q) continue;
        const SE3 T_true = truth.T_base_cam.at(cc.name).inverse() * chain.forward(*q) * *truth.T_link_marker;
        std::vector<Vec2> proj(det.corners.size());
        bool all_proj = true;
        for (size_t i = 0; i < det.corners.size(); ++i) {
          const auto p = model.project(T_true * det.object_points[i]);
          if (!p) all_proj = false;
          else proj[i] = *p;
        }
        if (corners && all_proj) {
          CornerAcc& ca = cacc[cc.name];
          const Vec3 centre = T_true * Vec3(0.5 * target.squares_x * target.square_size,
                                            0.5 * target.squares_y * target.square_size, 0.0);
          const Vec3 normal = T_true.rotation().col(2);
          const double tilt = std::acos(std::min(1.0, std::abs(normal.dot(centre.normalized())))) * 180.0 / M_PI;
          const int tb = tilt < 20 ? 0 : tilt < 40 ? 1 : tilt < 55 ? 2 : 3;
          const double z = centre.z();
          const int db = z < 0.6 ? 0 : z < 0.9 ? 1 : z < 1.3 ? 2 : 3;
          Vec2 m = Vec2::Zero();
          const double W = model.width(), H = model.height();
          const Vec2 pp(model.cx(), model.cy());
          for (size_t i = 0; i < det.corners.size(); ++i) {
            const Vec2 d = det.corners[i] - proj[i];
            m += d;
            ca.all.add(d);
            const int rx = std::clamp(static_cast<int>(3 * proj[i].x() / W), 0, 2);
            const int ry = std::clamp(static_cast<int>(3 * proj[i].y() / H), 0, 2);
            ca.region[ry][rx].add(d);
            ca.depth[db].add(d);
            ca.tilt[tb].add(d);
            const Vec2 rv = proj[i] - pp;
            const double rn = rv.norm() / (0.5 * std::hypot(W, H));
            ca.radius[std::clamp(static_cast<int>(4 * rn), 0, 3)].add(d);
            if (rv.norm() > 1.0) {
              const Vec2 ur = rv.normalized();
              ca.radial.add(Vec2(d.dot(ur), ur.x() * d.y() - ur.y() * d.x()));
            }
          }
          ca.img_mean.add(m / static_cast<double>(det.corners.size()));
        }
        const int draws = synthetic > 0 ? synthetic : 1;
        std::mt19937_64 rng(sim.seed * 1000003ull + static_cast<unsigned long long>(im.stamp_ns));
        std::normal_distribution<double> nd(0.0, 1.0);
        for (int draw = 0; draw < draws; ++draw) {
          vision::CharucoDetection d2 = det;
          if (synthetic > 0) {
            if (!all_proj) break;
            for (size_t i = 0; i < d2.corners.size(); ++i) d2.corners[i] = proj[i] + pixel * Vec2(nd(rng), nd(rng));
          }
          vision::PoseEstimate est;
          try {
            const auto t0 = std::chrono::steady_clock::now();
            est = vision::estimatePose(model, d2, pnp);
            pnp_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            ++pnp_calls;
          } catch (const std::exception&) {
            continue;
          }
          const Vec6 e = T_true.inverse().compose(est.T_cam_marker).log();  // T_est = T_true * exp(e)
          if (dump) {
            std::fprintf(dump, "%u,%s,%lld,%d", sim.seed, cc.name.c_str(), static_cast<long long>(im.stamp_ns), draw);
            for (int i = 0; i < 6; ++i) std::fprintf(dump, ",%.9g", e[i]);
            for (int i = 0; i < 36; ++i) std::fprintf(dump, ",%.9g", est.covariance(i / 6, i % 6));
            for (int i = 0; i < 9; ++i) std::fprintf(dump, ",%.9g", T_true.rotation()(i / 3, i % 3));
            std::fprintf(dump, "\n");
          }
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
    }
    std::fprintf(stderr, "seed %d done\n", s + 1);
  }
  fs::remove_all(dir);
  if (dump) std::fclose(dump);
  std::printf("PnP per-image NEES, %d seeds x %d frames, %.2f px, sigma %s%s\n", seeds, frames, pixel,
              sigma.c_str(), synthetic > 0 ? (", synthetic corners x" + std::to_string(synthetic)).c_str() : "");
  std::printf("estimatePose: %ld calls, %.3f ms per call\n", pnp_calls, pnp_calls ? 1e3 * pnp_seconds / pnp_calls : 0.0);
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
  auto show = [](const char* label, const Off& o) {
    if (o.n < 2) {
      std::printf("  %-22s n=%ld\n", label, o.n);
      return;
    }
    const double mu = o.su / o.n, mv = o.sv / o.n;
    const double vu = o.suu / o.n - mu * mu, vv = o.svv / o.n - mv * mv;
    std::printf("  %-22s n=%6ld  u %+.4f+-%.4f (sd %.3f)  v %+.4f+-%.4f (sd %.3f)\n", label, o.n, mu,
                std::sqrt(vu / o.n), std::sqrt(vu), mv, std::sqrt(vv / o.n), std::sqrt(vv));
  };
  for (auto& [name, ca] : cacc) {
    std::printf("%s: corner offset detected - true projection (px), mean +- standard error\n", name.c_str());
    show("all corners", ca.all);
    show("per-image means", ca.img_mean);
    show("radial(u)/tangential(v)", ca.radial);
    const char* rows[3] = {"top", "middle", "bottom"};
    const char* cols[3] = {"left", "centre", "right"};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) show((std::string("region ") + rows[r] + "-" + cols[c]).c_str(), ca.region[r][c]);
    const char* dl[4] = {"depth <0.6 m", "depth 0.6-0.9 m", "depth 0.9-1.3 m", "depth >1.3 m"};
    for (int i = 0; i < 4; ++i) show(dl[i], ca.depth[i]);
    const char* tl[4] = {"tilt <20 deg", "tilt 20-40 deg", "tilt 40-55 deg", "tilt >55 deg"};
    for (int i = 0; i < 4; ++i) show(tl[i], ca.tilt[i]);
    const char* rl[4] = {"radius <25%", "radius 25-50%", "radius 50-75%", "radius >75%"};
    for (int i = 0; i < 4; ++i) show(rl[i], ca.radius[i]);
  }
  return 0;
}
