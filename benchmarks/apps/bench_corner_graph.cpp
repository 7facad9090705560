// The corner graph (`fgcal calibrate --method corners`) at the paper's size:
// 1312 instants, 2 cameras both seeing every instant, an 8 x 8 board (49
// corners per image): about 128,000 two-dimensional corner factors. The
// corners are synthetic (synthetic_corners.hpp: projected through the true
// camera models with 0.5 px noise; no images), the start is the PnP
// solution as in the pipeline. Times one thread: the process CPU time of
// solveCornerCalibration (what the machine's other users cannot inflate),
// and the phases (graph building, optimizer linearization and solve, gates,
// marginals) from steady clocks.
//
//   bench_corner_graph [--instants 1312] [--cameras 2] [--board 8x8] [--repeat 3] [--seed 1]
//                      [--distortion radtan|equidistant|none] [--intrinsics] [--threads 1]
//
// Prints one line per repeat and the best; exits 1 when the solution is off
// the truth by more than 2 mm / 0.1 deg (a benchmark of a wrong answer
// measures nothing).
#include <sys/resource.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>

#include "calibration/synthetic_corners.hpp"
#include "fgcal/apps/corner_calibration.hpp"

namespace {

double cpuSeconds() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace fgcal;
  using namespace fgcal::apps;
  synthetic::CornerProblemOptions opt;
  opt.instants = 1312;
  opt.squares_x = opt.squares_y = 8;
  opt.see_probability = 1.0;
  int repeat = 3, threads = 1;
  bool intrinsics = false;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--intrinsics") {
      intrinsics = true;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s needs a value\n", k.c_str());
      return 2;
    }
    const std::string v = argv[++i];
    if (k == "--instants") opt.instants = std::atoi(v.c_str());
    else if (k == "--cameras") opt.cameras = std::atoi(v.c_str());
    else if (k == "--repeat") repeat = std::atoi(v.c_str());
    else if (k == "--seed") opt.seed = static_cast<unsigned>(std::atoi(v.c_str()));
    else if (k == "--distortion") opt.distortion = v;
    else if (k == "--threads") threads = std::atoi(v.c_str());
    else if (k == "--board") {
      if (std::sscanf(v.c_str(), "%dx%d", &opt.squares_x, &opt.squares_y) != 2) {
        std::fprintf(stderr, "--board: expected SQUARES_XxSQUARES_Y, e.g. 8x8\n");
        return 2;
      }
    } else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  if (intrinsics) {
    opt.intrinsics_error_pct = 1.0;
    opt.intrinsics_error_px = 3.0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  synthetic::CornerProblem d = synthetic::makeCornerProblem(opt);
  d.corners.estimate_intrinsics = intrinsics;
  long corners = 0;
  for (const auto& im : d.corners.corners) corners += static_cast<long>(im.pixels.size());
  utsname un{};
  ::uname(&un);
  std::printf("# bench_corner_graph: %d instants, %d cameras, %dx%d board, %zu images, %ld corners (%.1f per image), "
              "%s, intrinsics %s, %d thread(s); generated in %.1f s\n",
              opt.instants, opt.cameras, opt.squares_x, opt.squares_y, d.problem.observations.size(), corners,
              static_cast<double>(corners) / static_cast<double>(d.problem.observations.size()),
              opt.distortion.c_str(), intrinsics ? "estimated (rig 1 % / 3 px off)" : "held", threads,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  std::printf("# machine %s, %ld cores, load %s\n", un.nodename, ::sysconf(_SC_NPROCESSORS_ONLN), [] {
    static char buf[64] = "?";
    if (FILE* f = std::fopen("/proc/loadavg", "r")) {
      if (!std::fgets(buf, sizeof buf, f)) buf[0] = 0;
      std::fclose(f);
    }
    for (char* c = buf; *c; ++c)
      if (*c == '\n') *c = 0;
    return buf;
  }());
  const double cpu_pnp0 = cpuSeconds();
  const CalibrationSolution pnp = solveCalibration(d.problem);
  std::printf("# PnP start (solveCalibration): %.3f s CPU\n", cpuSeconds() - cpu_pnp0);
  std::printf("| run | CPU s | wall s | solves | iterations | linearize s | linear solve s | build s | gates s | "
              "marginals s | factors | corners rejected |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  double best = 1e30;
  bool ok = true;
  for (int r = 0; r < repeat; ++r) {
    const double c0 = cpuSeconds();
    const auto w0 = std::chrono::steady_clock::now();
    const CornerSolution cs = solveCornerCalibration(d.problem, d.corners, pnp, threads);
    const double cpu = cpuSeconds() - c0;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    int iterations = 0;
    double lin = 0, solve = 0;
    std::string its;
    for (const auto& s : cs.solution.solves) {
      iterations += s.iterations;
      lin += s.linearize_seconds;
      solve += s.solve_seconds;
      its += (its.empty() ? "" : "+") + std::to_string(s.iterations);
    }
    std::printf("| %d | %.3f | %.3f | %zu | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %ld | %ld |\n", r + 1, cpu, wall,
                cs.solution.solves.size(), its.c_str(), lin, solve, cs.build_seconds, cs.gate_seconds,
                cs.marginals_seconds, cs.corners_used, cs.corners_rejected);
    best = std::min(best, cpu);
    if (r == 0) {
      std::printf("# linear solver: %s\n", cs.solution.solves.back().linear_solver.c_str());
      for (std::size_t c = 0; c < d.true_cameras.size(); ++c) {
        const Vec6 e = d.true_cameras[c].minus(cs.solution.cameras[c].T_base_cam);
        const double mm = 1e3 * (cs.solution.cameras[c].T_base_cam.translation() - d.true_cameras[c].translation()).norm();
        const double deg = e.head<3>().norm() * 180.0 / M_PI;
        std::printf("# camera %zu error %.3f mm %.4f deg\n", c, mm, deg);
        if (mm > 2.0 || deg > 0.1) ok = false;
      }
    }
  }
  std::printf("best CPU: %.3f s\n", best);
  if (!ok) {
    std::fprintf(stderr, "the corner graph's solution is off the truth: the timing is of a wrong answer\n");
    return 1;
  }
  return 0;
}
