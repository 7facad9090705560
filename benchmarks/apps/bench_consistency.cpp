// Honesty of the reported uncertainty (issue #5): over many seeds, simulate a
// dataset, calibrate it (F2 and F1), evaluate against the truth, and compare
// the mean NEES of each camera with the 95 % band of chi-square(6) for that
// many samples. Also prints mean and spread of the per-axis errors.
//
//   bench_consistency [--seeds 50] [--frames 300] [--first-seed 1] [--pixel-noise 0.5]
//                     [--encoder-noise 0.002] [--mount-error-mm 3] [--mount-error-deg 1]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/simulator.hpp"

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

}  // namespace

int main(int argc, char** argv) {
  int seeds = 50, frames = 300;
  unsigned first = 1;
  double pixel = 0.5, encoder = 0.002, mount_mm = 3.0, mount_deg = 1.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const double v = std::atof(argv[i + 1]);
    if (k == "--seeds") seeds = static_cast<int>(v);
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
  for (int s = 0; s < seeds; ++s) {
    fs::remove_all(dir);
    fgcal::apps::SimulationOptions sim;
    sim.out_dir = (dir / "dataset").string();
    sim.frames = frames;
    sim.seed = first + static_cast<unsigned>(s);
    sim.pixel_noise = pixel;
    sim.encoder_noise = encoder;
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
      const auto r = fgcal::apps::runCalibrate(c, quiet);
      const auto ev = fgcal::apps::evaluate(r.output, truth);
      auto add = [&](const std::string& who, const fgcal::apps::PoseError& e) {
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
