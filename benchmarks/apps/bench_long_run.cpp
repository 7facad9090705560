// bench_long_run: `fgcal calibrate` on a 20 000-image dataset
// completes with flat memory.
//
//   bench_long_run [--images N] [--distinct K] [--width W --height H] [--keep DIR] [--threads T]
//
// 1. Simulates K distinct instants (default 200) of the default 2-camera rig at
//    a small resolution (default 320x240), then repeats that recording until it
//    holds N images (default 20 000): each repetition hard-links the image files
//    under stamps shifted by the recording's length, and appends the joint
//    samples shifted the same way, so the dataset costs the disk of K instants.
// 2. Runs the real fgcal executable on it (calibrate, every core) and samples
//    /proc/<pid>/status (VmRSS, VmHWM) every 0.2 s, reading the progress lines
//    "detected k/N images" from its stderr.
// 3. Prints RSS over time and at 25/50/75/100 % of the images, the peak, the
//    time split; exits 1 when memory grows with the images beyond what their
//    detections take: RSS(100 %) - RSS(50 %) must stay below
//    N/2 x 16 KB + 64 MB (a FrameResult with its corners is ~2-3 KB; one kept
//    320x240 image alone is 77 KB).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fgcal/apps/simulator.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

long statusKb(pid_t pid, const char* key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  const std::size_t n = std::strlen(key);
  while (std::getline(in, line))
    if (line.compare(0, n, key) == 0) return std::atol(line.c_str() + n + 1);
  return -1;
}

struct Sample {
  double t;
  long rss_kb, hwm_kb;
  long detected;
};

}  // namespace

int main(int argc, char** argv) {
  long images = 20000;
  int distinct = 200, width = 320, height = 240, threads = 0;
  std::string keep;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "bench_long_run: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--images") images = std::stol(next());
    else if (a == "--distinct") distinct = std::stoi(next());
    else if (a == "--width") width = std::stoi(next());
    else if (a == "--height") height = std::stoi(next());
    else if (a == "--keep") keep = next();
    else if (a == "--threads") threads = std::stoi(next());
    else {
      std::cerr << "usage: bench_long_run [--images N] [--distinct K] [--width W --height H] [--keep DIR] [--threads T]\n";
      return 2;
    }
  }

  const fs::path root = keep.empty() ? fs::temp_directory_path() / ("fgcal_long_run_" + std::to_string(getpid()))
                                     : fs::path(keep);
  const fs::path base = root / "base", ds = root / "ds";
  fs::remove_all(root);
  fs::create_directories(root);
  const auto t0 = Clock::now();

  // ---- 1. K distinct instants, then repetitions --------------------------------
  fgcal::apps::SimulationOptions sim;
  sim.out_dir = base.string();
  sim.frames = distinct;
  sim.cameras = 2;
  sim.seed = 11;
  sim.supersampling = 1;
  sim.image_width = width;
  sim.image_height = height;
  const auto summary = fgcal::apps::simulateDataset(sim);
  const double t_sim = std::chrono::duration<double>(Clock::now() - t0).count();

  std::ifstream jin(base / "joints.csv");
  std::string header;
  std::getline(jin, header);
  std::vector<std::pair<int64_t, std::string>> rows;  // stamp, rest of the line
  for (std::string l; std::getline(jin, l);) {
    if (l.empty()) continue;
    const auto comma = l.find(',');
    rows.emplace_back(std::stoll(l.substr(0, comma)), l.substr(comma));
  }
  const int64_t period = rows.back().first - rows.front().first + 1000000;  // + 1 ms
  const long per_rep = summary.images_written;
  const long reps = (images + per_rep - 1) / per_rep;
  fs::create_directories(ds);
  fs::copy_file(base / "rig.yaml", ds / "rig.yaml");
  fs::copy_file(base / "robot.urdf", ds / "robot.urdf");
  {
    std::ofstream jout(ds / "joints.csv");
    jout << header << "\n";
    for (long r = 0; r < reps; ++r)
      for (const auto& [stamp, rest] : rows) jout << stamp + r * period << rest << "\n";
  }
  long linked = 0;
  for (const auto& cam : summary.cameras) {
    fs::create_directories(ds / cam);
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(base / cam)) files.push_back(e.path());
    for (long r = 0; r < reps; ++r)
      for (const auto& f : files) {
        const int64_t stamp = std::stoll(f.stem().string()) + r * period;
        fs::create_hard_link(f, ds / cam / (std::to_string(stamp) + f.extension().string()));
        ++linked;
      }
  }
  std::cout << "dataset: " << linked << " images (" << reps << " x " << per_rep << " distinct, " << width << "x"
            << height << "), " << reps * static_cast<long>(rows.size()) << " joint samples; simulated in " << t_sim
            << " s\n";

  // ---- 2. fgcal calibrate, sampled ------------------------------------------------
  int pipefd[2];
  if (pipe(pipefd) != 0) return 3;
  const std::string out = (root / "calibration.yaml").string();
  const std::string thr = std::to_string(threads);
  const auto t_cal = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(pipefd[1], STDERR_FILENO);
    close(pipefd[0]);
    close(pipefd[1]);
    execl(FGCAL_EXE, FGCAL_EXE, "calibrate", ds.c_str(), "-o", out.c_str(), "--threads", thr.c_str(), "--no-report",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  close(pipefd[1]);
  fcntl(pipefd[0], F_SETFL, O_NONBLOCK);
  std::vector<Sample> samples;
  std::string log, pending;
  long detected = 0;
  int status = 0;
  while (true) {
    char buf[4096];
    ssize_t n;
    while ((n = read(pipefd[0], buf, sizeof buf)) > 0) {
      log.append(buf, static_cast<std::size_t>(n));
      pending.append(buf, static_cast<std::size_t>(n));
      std::size_t nl;
      while ((nl = pending.find('\n')) != std::string::npos) {
        const std::string line = pending.substr(0, nl);
        pending.erase(0, nl + 1);
        const auto p = line.find("detected ");
        if (p != std::string::npos) detected = std::atol(line.c_str() + p + 9);
      }
    }
    const long rss = statusKb(pid, "VmRSS:"), hwm = statusKb(pid, "VmHWM:");
    if (rss > 0)
      samples.push_back({std::chrono::duration<double>(Clock::now() - t_cal).count(), rss, hwm, detected});
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  for (char buf[4096]; read(pipefd[0], buf, sizeof buf) > 0;) log += buf;
  const double t_total = std::chrono::duration<double>(Clock::now() - t_cal).count();
  const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);

  // ---- 3. Figures -------------------------------------------------------------------
  std::cout << "fgcal calibrate exit " << rc << " after " << t_total << " s\n";
  if (rc != 0) std::cout << log << "\n";
  const long total = linked;
  std::cout << "RSS over time (t s, images detected, VmRSS MB):\n";
  std::size_t step = std::max<std::size_t>(1, samples.size() / 40);
  for (std::size_t i = 0; i < samples.size(); i += step)
    std::printf("  %7.1f  %6ld  %7.1f\n", samples[i].t, samples[i].detected, samples[i].rss_kb / 1024.0);
  auto rssAt = [&](double frac) -> long {
    for (const auto& s : samples)
      if (s.detected >= static_cast<long>(frac * total)) return s.rss_kb;
    return samples.empty() ? -1 : samples.back().rss_kb;
  };
  const long r25 = rssAt(0.25), r50 = rssAt(0.5), r75 = rssAt(0.75), r100 = rssAt(1.0);
  const long peak = samples.empty() ? -1 : samples.back().hwm_kb;
  double t_detect = 0;
  for (const auto& s : samples)
    if (s.detected >= total) {
      t_detect = s.t;
      break;
    }
  std::printf("RSS at 25/50/75/100 %% of the images: %.1f / %.1f / %.1f / %.1f MB; peak (VmHWM) %.1f MB\n",
              r25 / 1024.0, r50 / 1024.0, r75 / 1024.0, r100 / 1024.0, peak / 1024.0);
  std::printf("time: detection done at %.1f s, total %.1f s (%ld images, %.2f ms/image)\n", t_detect, t_total, total,
              1e3 * t_total / static_cast<double>(total));
  const long allowed_kb = total / 2 * 16 + 64 * 1024;
  const bool flat = r100 - r50 <= allowed_kb;
  std::printf("memory growth 50 %% -> 100 %%: %.1f MB (allowed %.1f MB): %s\n", (r100 - r50) / 1024.0,
              allowed_kb / 1024.0, flat ? "flat" : "GROWS WITH THE IMAGES");
  if (keep.empty()) fs::remove_all(root);
  if (rc != 0) return 1;
  return flat ? 0 : 1;
}
