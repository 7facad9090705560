// End to end: `fgcal calibrate` on a dataset the size of the
// paper's (1312 instants, 2 cameras), at 640x480 and at 1280x720, with 1 and
// 2 threads; the split of the total time (loading, image decoding, detection,
// kinematics, graph building, optimizer, output) and the peak memory (VmHWM).
// Peak memory is also measured at twice the instants: it must not grow with
// the images beyond the detections themselves (images are decoded one at a
// time per thread and dropped).
//
//   bench_end_to_end [--frames 1312] [--resolutions 640x480,1280x720] [--threads 1,2]
//                    [--memory-frames 2624] [--seed 1] [--supersampling 1]
//
// The images are rendered with 1 sample per pixel (the simulator's default is
// 3 x 3) to keep the simulation of ~6,000 images affordable; calibrate's
// figures should depend little on it (the same blur and noise; only the
// anti-aliasing of the edges differs).
// Each calibration runs in a fresh child process (this program re-executed),
// so VmHWM is that run's own. The
// datasets are simulated into a temporary folder and deleted afterwards; the
// simulation time is printed but is not part of the figures.
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/simulator.hpp"

namespace {

namespace fs = std::filesystem;

long statusKb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(f, line))
    if (line.rfind(k, 0) == 0) return std::atol(line.c_str() + k.size());
  return -1;
}

double cpuSeconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Run {
  bool ok = false;
  int images = 0, used = 0;
  double total = 0, load = 0, decode = 0, detection = 0, kinematics = 0, solve = 0, optimizer = 0, output = 0;
  double cpu = 0;  // user + system seconds of the child
  double report = 0;  // the HTML report, written after total_seconds
  long rss_detect_kb = 0, rss_rest_kb = 0;  // largest sampled VmRSS during loading + detection, and after
  long hwm_kb = 0;
  std::string error;
};

/// The child: runs calibrate and writes one line of figures to stdout. It is
/// a fresh process (exec), so its memory figures are its own, not the
/// simulator's pages of the parent.
int childMain(const std::string& dataset, const std::string& output, int threads) {
  std::ostringstream msg;
  // VmRSS every 10 ms, to tell the detection phase's peak from the solver's.
  std::atomic<bool> stop{false};
  std::vector<std::pair<double, long>> samples;
  const auto t0 = std::chrono::steady_clock::now();
  std::thread sampler([&] {
    while (!stop) {
      samples.emplace_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                           statusKb("VmRSS"));
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  try {
    fgcal::apps::CalibrateOptions c;
    c.dataset = dataset;
    c.output = output;
    c.threads = threads;
    std::ostringstream quiet;
    const auto r = fgcal::apps::runCalibrate(c, quiet);
    int used = 0, images = 0;
    for (const auto& cam : r.output.cameras) {
      used += cam.images_used;
      images += cam.images_used;
      for (const auto& [reason, n] : cam.images_skipped) images += n;
    }
    const fgcal::apps::CalibrateTimings& t = r.timings;
    stop = true;
    sampler.join();
    long rss_detect = 0, rss_rest = 0;
    for (const auto& [at, kb] : samples) {
      long& peak = at <= t.load + t.detection ? rss_detect : rss_rest;
      peak = std::max(peak, kb);
    }
    msg << "ok " << images << " " << used << " " << t.total << " " << t.load << " " << t.decode << " "
        << t.detection << " " << t.kinematics << " " << t.solve << " " << t.optimizer << " " << t.output << " "
        << statusKb("VmHWM") << " " << cpuSeconds() << " " << rss_detect << " " << rss_rest << " " << t.report
        << "\n";
  } catch (const std::exception& e) {
    msg << "error " << e.what() << "\n";
  }
  stop = true;
  if (sampler.joinable()) sampler.join();
  const std::string s = msg.str();
  std::fwrite(s.data(), 1, s.size(), stdout);
  return 0;
}

/// runCalibrate in a child process (this program re-executed with --child);
/// its figures come back through a pipe.
Run calibrateInChild(const std::string& dataset, const std::string& output, int threads) {
  int fd[2];
  if (::pipe(fd) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fd[0]);
    ::dup2(fd[1], STDOUT_FILENO);
    const std::string t = std::to_string(threads);
    ::execl("/proc/self/exe", "bench_end_to_end", "--child", dataset.c_str(), output.c_str(), t.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(fd[1]);
  std::string text;
  char buf[512];
  ssize_t n;
  while ((n = ::read(fd[0], buf, sizeof buf)) > 0) text.append(buf, static_cast<std::size_t>(n));
  ::close(fd[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  Run r;
  std::istringstream in(text);
  std::string tag;
  in >> tag;
  if (tag == "ok") {
    in >> r.images >> r.used >> r.total >> r.load >> r.decode >> r.detection >> r.kinematics >> r.solve >>
        r.optimizer >> r.output >> r.hwm_kb >> r.cpu >> r.rss_detect_kb >> r.rss_rest_kb >> r.report;
    r.ok = true;
  } else {
    std::getline(in, r.error);
  }
  return r;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

std::string shell(const std::string& cmd) {
  std::string out;
  if (FILE* f = ::popen(cmd.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, f)) out += buf;
    ::pclose(f);
  }
  while (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "--child") return childMain(argv[2], argv[3], std::atoi(argv[4]));
  int frames = 1312, memory_frames = 2624, supersampling = 1;
  unsigned seed = 1;
  std::string resolutions = "640x480,1280x720", threads_arg = "1,2";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--frames") frames = std::atoi(v.c_str());
    else if (k == "--memory-frames") memory_frames = std::atoi(v.c_str());
    else if (k == "--seed") seed = static_cast<unsigned>(std::atoi(v.c_str()));
    else if (k == "--supersampling") supersampling = std::atoi(v.c_str());
    else if (k == "--resolutions") resolutions = v;
    else if (k == "--threads") threads_arg = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  const fs::path tmp = fs::temp_directory_path() / ("fgcal-e2e-" + std::to_string(::getpid()));
  struct utsname un {};
  ::uname(&un);
  std::printf("Machine: %s, %ld cores, load average at start %s. Date: %s.\n", un.nodename,
              ::sysconf(_SC_NPROCESSORS_ONLN), shell("cut -d' ' -f1-3 /proc/loadavg").c_str(),
              shell("date -u +%Y-%m-%dT%H:%MZ").c_str());
  std::printf("Decode is summed over the detection threads; detect = detection wall time minus decode/threads "
              "minus kinematics; CPU s = user + system time of the calibrate process (its wall time on an idle machine with one thread); graph = solve minus optimizer (graph building, initialization, gating, marginals); "
              "report = the HTML report that fgcal calibrate writes by default, after its total (total s excludes it, non-detection %% and images/s include it); non-detection = load + kinematics + graph + optimizer + output + report.\n\n");
  std::printf("| image | instants | images | threads | total s | load | decode | detect | kinematics | graph | "
              "optimizer | output | report | non-detection %% | images/s | CPU s | peak MB | RSS MB detection | RSS MB solve, output, report |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  bool all_ok = true;
  struct MemPoint {
    std::string res;
    int frames, images;
    long hwm_kb;
  };
  std::vector<MemPoint> mem;
  for (const std::string& res : split(resolutions)) {
    int w = 0, h = 0;
    if (std::sscanf(res.c_str(), "%dx%d", &w, &h) != 2) {
      std::fprintf(stderr, "bad resolution %s\n", res.c_str());
      return 2;
    }
    std::vector<int> sizes{frames};
    if (memory_frames > 0 && res == split(resolutions).front()) sizes.push_back(memory_frames);
    for (const int n : sizes) {
      fs::remove_all(tmp);
      fgcal::apps::SimulationOptions sim;
      sim.out_dir = (tmp / "dataset").string();
      sim.frames = n;
      sim.seed = seed;
      sim.image_width = w;
      sim.image_height = h;
      sim.supersampling = supersampling;
      const auto s = fgcal::apps::simulateDataset(sim);
      std::fprintf(stderr, "simulated %d instants at %s: %d images in %.0f s\n", n, res.c_str(), s.images_written,
                   s.seconds);
      const std::vector<std::string> thread_list = n == frames ? split(threads_arg) : std::vector<std::string>{"1"};
      for (const std::string& t : thread_list) {
        const int threads = std::atoi(t.c_str());
        const Run r = calibrateInChild(sim.out_dir, (tmp / "calibration.yaml").string(), threads);
        if (!r.ok) {
          std::fprintf(stderr, "calibrate failed: %s\n", r.error.c_str());
          all_ok = false;
          continue;
        }
        const double detect = r.detection - r.decode / threads - r.kinematics;
        const double graph = r.solve - r.optimizer;
        const double rest = r.load + r.kinematics + r.solve + r.output + r.report;
        const double all = r.total + r.report;
        std::printf("| %s | %d | %d | %d | %.2f | %.3f | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.2f | %.1f | %.0f | %.1f | %.0f | %.0f | %.0f |\n",
                    res.c_str(), n, r.images, threads, r.total, r.load, r.decode, detect, r.kinematics, graph,
                    r.optimizer, r.output, r.report, 100.0 * rest / all, r.images / all, r.cpu, r.hwm_kb / 1024.0, r.rss_detect_kb / 1024.0, r.rss_rest_kb / 1024.0);
        std::fflush(stdout);
        if (threads == 1) mem.push_back({res, n, r.images, r.hwm_kb});
      }
    }
  }
  fs::remove_all(tmp);
  if (mem.size() >= 2 && mem[0].res == mem[1].res) {
    const double d_kb = static_cast<double>(mem[1].hwm_kb - mem[0].hwm_kb);
    const int d_img = mem[1].images - mem[0].images;
    std::printf("\nPeak memory, 1 thread, %s: %.0f MB at %d images, %.0f MB at %d images: %.2f KB per extra image "
                "(a decoded %s grayscale image is %.0f KB).\n",
                mem[0].res.c_str(), mem[0].hwm_kb / 1024.0, mem[0].images, mem[1].hwm_kb / 1024.0, mem[1].images,
                d_kb / d_img, mem[0].res.c_str(), [&] {
                  int w = 0, h = 0;
                  std::sscanf(mem[0].res.c_str(), "%dx%d", &w, &h);
                  return w * h / 1024.0;
                }());
  }
  return all_ok ? 0 : 1;
}
