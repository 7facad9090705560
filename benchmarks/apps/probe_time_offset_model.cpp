// Does a time-offset factor need the exact board motion, or is a first-order
// one (the board at the instant moved along its body velocity, L Exp(V delta))
// enough? On the simulator's leg motions (joints without encoder noise, so the
// joint log's trajectory is the truth) and a 15 ms delay, this measures the
// first-order model's error at the board's outer corners (mm) and the bias it
// would put into the estimated delay: the least-squares shift of delta that
// best absorbs that error, sum g.e / sum g.g with g the corners' velocity.
// The target is 0.3 ms.
//
//   probe_time_offset_model [--seeds 5] [--frames 300] [--delay-ms 15]
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "fgcal/apps/joint_trajectory.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"

namespace fs = std::filesystem;
using namespace fgcal;

int main(int argc, char** argv) {
  int seeds = 5, frames = 300;
  double delay = 0.015;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--seeds") seeds = std::atoi(argv[i + 1]);
    else if (k == "--frames") frames = std::atoi(argv[i + 1]);
    else if (k == "--delay-ms") delay = std::atof(argv[i + 1]) * 1e-3;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  const fs::path dir = fs::temp_directory_path() / ("fgcal-probe-delay-" + std::to_string(::getpid()));
  std::printf("seed | instants | first-order error RMS mm | max mm | delta bias ms | board speed RMS mm/s\n");
  std::printf("---|---|---|---|---|---\n");
  for (int s = 1; s <= seeds; ++s) {
    fs::remove_all(dir);
    apps::SimulationOptions sim;
    sim.out_dir = dir.string();
    sim.frames = frames;
    sim.seed = static_cast<unsigned>(s);
    sim.encoder_noise = 0.0;
    sim.render_images = false;
    apps::simulateDataset(sim);
    const apps::RigConfig rig = apps::loadRigConfig((dir / "rig.yaml").string());
    const apps::JointLog log = apps::loadJointsCsv((dir / "joints.csv").string());
    const apps::GroundTruth truth = apps::loadGroundTruth((dir / "ground_truth.yaml").string());
    const auto robot = kinematics::RobotModel::fromFile(rig.robot.urdf);
    const auto chain = robot.chain(rig.robot.base_link, rig.robot.marker_link);
    const auto columns = apps::columnIndices(log, chain.jointNames(), "joints.csv");
    const apps::JointLogTrajectory traj(log, columns, "joints.csv");
    const SE3 M = *truth.T_link_marker;
    const double w = rig.target.squares_x * rig.target.square_size, h = rig.target.squares_y * rig.target.square_size;
    const std::vector<Vec3> corners{Vec3(0, 0, 0), Vec3(w, 0, 0), Vec3(0, h, 0), Vec3(w, h, 0)};
    double ee = 0, emax = 0, ge = 0, gg = 0, speed = 0;
    long n = 0;
    VecX q, qd, qb;
    kinematics::KinematicChain::Jacobian J;
    for (double t = 0.1; t + delay + 0.1 < traj.duration(); t += 1.0 / 30) {
      traj.evaluate(t, &q, &qd);
      const SE3 L = chain.forward(q, M, &J);
      Vec6 V = J * qd;  // the board's body velocity at t
      const SE3 first_order = L * SE3::exp(V * delay);
      traj.evaluate(t + delay, &qb, &qd);
      const SE3 exact = chain.forward(qb, M, &J);
      V = J * qd;  // at the exposure: the corners' velocity there
      for (const Vec3& p : corners) {
        const Vec3 e = exact * p - first_order * p;
        const Vec3 g = exact.rotation() * (V.head<3>().cross(p) + V.tail<3>());
        ee += e.squaredNorm();
        emax = std::max(emax, e.norm());
        ge += g.dot(e);
        gg += g.squaredNorm();
        speed += g.squaredNorm();
        ++n;
      }
    }
    std::printf("%d | %ld | %.4f | %.4f | %.4f | %.1f\n", s, n / 4, std::sqrt(ee / n) * 1e3, emax * 1e3,
                ge / gg * 1e3, std::sqrt(speed / n) * 1e3);
  }
  fs::remove_all(dir);
  return 0;
}
