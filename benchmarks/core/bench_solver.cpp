// bench_solver: fgcal's Levenberg-Marquardt against Ceres Solver (when found
// at configure time) on the calibration-shaped graph, in one
// program, from the same start, with the same stopping rule.
//
// Every (solver, size, repetition) runs in its own forked child so that its
// peak RSS (getrusage ru_maxrss, monotone per process) is its own; the child
// builds the solver's problem from the shared, pre-generated measurements,
// solves, and sends its figures back through a pipe. Times are the best of
// --repeat runs. One CSV line per size goes to stdout, a summary to stderr.
//
//   bench_solver [--sizes small|medium|all|M:N,M:N...] [--repeat K] [--repeat-limit F] [--repeat-large K3]
//                [--repeat-small K2] [--small-limit F2]
//                [--threads T] [--solvers fgcal,fgcal_chol,snc,schur] [--fgcal-solver auto|cholesky|schur|streamed] [--timeout S] [--seed S]
//                [--tolerance T] [--max-iterations K] [--see P]
// Sizes with more than --repeat-limit factors (default 500000) run K3 times
// (default 1), sizes with fewer than --small-limit (default 15000) max(K, K2)
// times. On a VM that hands idle memory back to its host (free page
// reporting), the first run after a pause pays the host's first touch of
// every page (about 2 us per 4 kB here): a second run of the same solver
// right after it measures the solver, not the order of the runs.
// CHOLMOD is built with OpenMP on Debian: run with OMP_NUM_THREADS=1 (as
// benchmarks/run_solver_benchmark.sh does) for single-threaded figures.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "calibration_problem.hpp"
#include "ceres_problem.hpp"
#include "fgcal/core/optimizer.hpp"

namespace {

using namespace fgcal;
using namespace fgcal::bench;
using Clock = std::chrono::steady_clock;

constexpr int kMaxCameras = 64;

// What a child reports: plain data, written through a pipe.
struct CaseResult {
  int status = 0;  // 1 ok, 0 not run, -1 failed, -2 timed out / killed
  char message[200] = {};
  char termination[64] = {};
  char linear_solver[96] = {};
  bool converged = false;
  double seconds = NAN;  // wall time of the solve call
  int iterations = 0;
  int linear_solves = 0;
  double linearize_s = NAN, analyze_s = NAN, solve_s = NAN, other_s = NAN;
  double initial_cost = NAN, final_cost = NAN;
  double model_mb = NAN, peak_mb = NAN;  // RSS increase after building the problem / at the peak of build + solve
  int cameras = 0;
  double camera_params[7 * kMaxCameras] = {};
};

double rssMb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return NAN;
}
double maxRssMb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void setText(char* dst, std::size_t n, const std::string& s) {
  std::snprintf(dst, n, "%s", s.c_str());
}

// Runs `body` in a forked child; kills it after `timeout` seconds.
CaseResult runForked(double timeout, const std::function<CaseResult()>& body) {
  int fd[2];
  if (pipe(fd) != 0) {
    CaseResult r;
    r.status = -1;
    setText(r.message, sizeof r.message, "pipe() failed");
    return r;
  }
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    alarm(static_cast<unsigned>(std::ceil(timeout)));
    CaseResult r;
    try {
      r = body();
    } catch (const std::exception& e) {
      r.status = -1;
      setText(r.message, sizeof r.message, std::string("exception: ") + e.what());
    }
    const char* p = reinterpret_cast<const char*>(&r);
    std::size_t left = sizeof r;
    while (left > 0) {
      const ssize_t w = write(fd[1], p, left);
      if (w <= 0) break;
      p += w;
      left -= static_cast<std::size_t>(w);
    }
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  CaseResult r;
  char* p = reinterpret_cast<char*>(&r);
  std::size_t got = 0;
  while (got < sizeof r) {
    const ssize_t n = read(fd[0], p + got, sizeof r - got);
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  close(fd[0]);
  int wstatus = 0;
  waitpid(pid, &wstatus, 0);
  if (got != sizeof r) {
    r = CaseResult{};
    r.status = -2;
    if (WIFSIGNALED(wstatus) && WTERMSIG(wstatus) == SIGALRM)
      setText(r.message, sizeof r.message, "timed out after " + std::to_string(static_cast<int>(timeout)) + " s");
    else
      setText(r.message, sizeof r.message, "child died (signal " + std::to_string(WIFSIGNALED(wstatus) ? WTERMSIG(wstatus) : 0) + ")");
  }
  return r;
}

struct Settings {
  std::vector<std::pair<int, int>> sizes;
  int repeat = 1;
  double repeat_limit = 500000;  // sizes with more factors run repeat_large times
  int repeat_large = 1;
  // Sizes with fewer factors run repeat_small times (if more than repeat):
  // a solve of a millisecond or less is decided by one interrupt in few runs.
  int repeat_small = 0;
  double small_limit = 15000;
  int threads = 1;
  std::set<std::string> solvers{"fgcal", "fgcal_chol", "snc", "schur"};
  double timeout = 600.0;
  std::uint64_t seed = 1;
  double see = 0.6;
  OptimizerOptions fgcal;
};

// ---- fgcal ----------------------------------------------------------------

CaseResult solveFgcal(const CalibrationProblem& p, const OptimizerOptions& options) {
  CaseResult r;
  const double rss0 = rssMb();
  FactorGraph graph;
  Values initial;
  buildFgcalProblem(p, graph, initial);
  r.model_mb = rssMb() - rss0;
  const auto t0 = Clock::now();
  const OptimizerResult res = optimize(graph, initial, options);
  r.seconds = since(t0);
  r.peak_mb = maxRssMb() - rss0;
  r.status = 1;
  r.converged = res.converged;
  setText(r.termination, sizeof r.termination, toString(res.termination));
  std::string ls = res.linear_solver;
  std::replace(ls.begin(), ls.end(), ',', ';');  // it goes into a CSV field
  setText(r.linear_solver, sizeof r.linear_solver, ls);
  setText(r.message, sizeof r.message, res.message);
  r.iterations = res.iterations;
  r.linearize_s = res.linearize_seconds;
  r.analyze_s = res.analyze_seconds;
  r.solve_s = res.solve_seconds;
  r.other_s = res.total_seconds - res.linearize_seconds - res.analyze_seconds - res.solve_seconds;
  r.initial_cost = res.initial_cost;
  r.final_cost = res.final_cost;
  r.cameras = std::min(p.cameras, kMaxCameras);
#ifdef FGCAL_HAVE_CERES
  for (int i = 0; i < r.cameras; ++i) poseToParams(res.values.at<SE3>(cameraKey(i)), r.camera_params + 7 * i);
#endif
  return r;
}

// ---- Ceres ----------------------------------------------------------------

#ifdef FGCAL_HAVE_CERES
CaseResult solveCeres(const CalibrationProblem& p, const Settings& s, bool schur) {
  CaseResult r;
  const double rss0 = rssMb();
  CeresCalibrationProblem cp;
  buildCeresProblem(p, cp);
  r.model_mb = rssMb() - rss0;

  const OptimizerOptions& f = s.fgcal;
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = schur ? ceres::SPARSE_SCHUR : ceres::SPARSE_NORMAL_CHOLESKY;
  o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  o.num_threads = s.threads;
  o.max_num_iterations = f.max_iterations;
  o.function_tolerance = f.relative_cost_tolerance;
  o.gradient_tolerance = f.gradient_tolerance;
  // fgcal: |step| < step_tolerance (absolute, tangent); Ceres: |dx| <= tol (|x| + tol) (ambient).
  const double x_norm = Eigen::Map<const VecX>(cp.params.data(), static_cast<Eigen::Index>(cp.params.size())).norm();
  o.parameter_tolerance = f.step_tolerance / std::max(1.0, x_norm);
  o.initial_trust_region_radius = 1.0 / f.initial_lambda;
  o.min_lm_diagonal = f.min_diagonal;
  o.max_lm_diagonal = f.max_diagonal;
  // fgcal accepts any step that lowers the cost and the model predicts lowering.
  o.min_relative_decrease = 1e-12;
  o.use_nonmonotonic_steps = false;
  o.minimizer_progress_to_stdout = false;
  o.logging_type = ceres::SILENT;
  if (schur) {
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (int j = 0; j < p.frames; ++j) ordering->AddElementToGroup(cp.board(j, p.cameras), 0);
    for (int i = 0; i < p.cameras; ++i) ordering->AddElementToGroup(cp.camera(i), 1);
    o.linear_solver_ordering = ordering;
  }
  std::string why;
  if (!o.IsValid(&why)) {
    r.status = -1;
    setText(r.message, sizeof r.message, "invalid Ceres options: " + why);
    return r;
  }
  ceres::Solver::Summary summary;
  const auto t0 = Clock::now();
  ceres::Solve(o, cp.problem.get(), &summary);
  r.seconds = since(t0);
  r.peak_mb = maxRssMb() - rss0;
  r.status = summary.IsSolutionUsable() ? 1 : -1;
  r.converged = summary.termination_type == ceres::CONVERGENCE;
  setText(r.termination, sizeof r.termination, ceres::TerminationTypeToString(summary.termination_type));
  setText(r.message, sizeof r.message, summary.message);
  r.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  r.linear_solves = summary.num_linear_solves;
  r.linearize_s = summary.jacobian_evaluation_time_in_seconds + summary.residual_evaluation_time_in_seconds;
  r.analyze_s = summary.preprocessor_time_in_seconds;
  r.solve_s = summary.linear_solver_time_in_seconds;
  r.other_s = summary.total_time_in_seconds - r.linearize_s - r.analyze_s - r.solve_s;
  r.initial_cost = summary.initial_cost;
  r.final_cost = summary.final_cost;
  r.cameras = std::min(p.cameras, kMaxCameras);
  std::copy(cp.params.begin(), cp.params.begin() + 7 * r.cameras, r.camera_params);
  return r;
}
#endif

// ---- driver ---------------------------------------------------------------

CaseResult bestOf(const Settings& s, int repeat, const std::function<CaseResult()>& body) {
  CaseResult best;
  for (int k = 0; k < repeat; ++k) {
    CaseResult r = runForked(s.timeout, body);
    if (r.status != 1) return r;  // a failure or a timeout is not retried
    if (best.status != 1 || r.seconds < best.seconds) {
      const double peak = std::isnan(best.peak_mb) ? r.peak_mb : std::max(best.peak_mb, r.peak_mb);
      best = r;
      best.peak_mb = peak;
    }
  }
  return best;
}

// Largest camera difference between two solutions: (mm, deg).
std::pair<double, double> cameraDifference(const CaseResult& a, const CaseResult& b) {
  double dt = 0.0, dr = 0.0;
#ifdef FGCAL_HAVE_CERES
  for (int i = 0; i < std::min(a.cameras, b.cameras); ++i) {
    const Vec6 d = paramsToPose(a.camera_params + 7 * i).minus(paramsToPose(b.camera_params + 7 * i));
    dr = std::max(dr, d.head<3>().norm() * 180.0 / M_PI);
    dt = std::max(dt, d.tail<3>().norm() * 1e3);
  }
#else
  (void)a;
  (void)b;
#endif
  return {dt, dr};
}

std::string num(double x, int precision = 4) {
  if (std::isnan(x)) return "";
  std::ostringstream s;
  s.precision(precision);
  s << x;
  return s.str();
}
std::string numFixed(double x, int decimals) {
  if (std::isnan(x)) return "";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << x;
  return s.str();
}

std::string librariesInUse() {
  std::ifstream maps("/proc/self/maps");
  std::set<std::string> libs;
  std::string line;
  while (std::getline(maps, line)) {
    const auto pos = line.find('/');
    if (pos == std::string::npos) continue;
    const std::string path = line.substr(pos);
    if (path.find("blas") != std::string::npos || path.find("lapack") != std::string::npos ||
        path.find("atlas") != std::string::npos || path.find("cholmod") != std::string::npos) {
      char real[4096];
      libs.insert(realpath(path.c_str(), real) ? std::string(real) : path);
    }
  }
  std::string out;
  for (const auto& l : libs) out += (out.empty() ? "" : ", ") + l;
  return out.empty() ? "(none mapped)" : out;
}

[[noreturn]] void usage(const std::string& error) {
  std::fprintf(stderr,
               "bench_solver: %s\nusage: bench_solver [--sizes small|medium|all|M:N,...] [--repeat K] "
               "[--repeat-limit F] [--repeat-large K3] [--repeat-small K2] [--small-limit F2] [--threads T] [--solvers fgcal,fgcal_chol,snc,schur] [--fgcal-solver auto|cholesky|schur|streamed] [--timeout S] [--seed S] [--tolerance T] "
               "[--max-iterations K] [--see P]\n",
               error.c_str());
  std::exit(2);
}

std::vector<std::pair<int, int>> parseSizes(const std::string& spec) {
  std::vector<std::pair<int, int>> out;
  const std::vector<int> cams{1, 2, 4, 8, 16};
  auto grid = [&](std::vector<int> frames) {
    for (int n : frames)
      for (int m : cams) out.emplace_back(m, n);
  };
  if (spec == "small") {
    grid({100, 1000});
  } else if (spec == "medium") {
    grid({100, 1000, 10000});
  } else if (spec == "all") {
    grid({100, 1000, 10000, 100000});
    out.emplace_back(2, 1000000);
  } else {
    std::stringstream ss(spec);
    std::string item;
    while (std::getline(ss, item, ',')) {
      const auto colon = item.find(':');
      if (colon == std::string::npos) usage("size '" + item + "' is not M:N");
      try {
        const int m = std::stoi(item.substr(0, colon));
        const int n = static_cast<int>(std::stod(item.substr(colon + 1)));
        if (m < 1 || m > kMaxCameras || n < 1) usage("size '" + item + "' out of range (1 <= M <= 64, N >= 1)");
        out.emplace_back(m, n);
      } catch (const std::logic_error&) {
        usage("size '" + item + "' is not M:N");
      }
    }
  }
  return out;
}

Settings parseArgs(int argc, char** argv) {
  Settings s;
  s.sizes = parseSizes("small");
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    // A count: a whole number >= 1, all of the argument (std::stoi would take "2x" as 2).
    auto count = [&]() {
      const std::string v = value();
      std::size_t end = 0;
      const int n = std::stoi(v, &end);
      if (end != v.size() || n < 1) usage(a + " takes a whole number >= 1, got '" + v + "'");
      return n;
    };
    try {
      if (a == "--sizes") s.sizes = parseSizes(value());
      else if (a == "--repeat") s.repeat = count();
      else if (a == "--repeat-limit") s.repeat_limit = std::stod(value());
      else if (a == "--repeat-large") s.repeat_large = count();
      else if (a == "--repeat-small") s.repeat_small = count();
      else if (a == "--small-limit") s.small_limit = std::stod(value());
      else if (a == "--fgcal-solver") {
        const std::string v = value();
        using LS = OptimizerOptions::LinearSolver;
        if (v == "auto") s.fgcal.linear_solver = LS::Auto;
        else if (v == "cholesky") s.fgcal.linear_solver = LS::SparseCholesky;
        else if (v == "schur") s.fgcal.linear_solver = LS::SchurComplement;
        else if (v == "streamed") s.fgcal.linear_solver = LS::StreamedSchurComplement;
        else usage("--fgcal-solver takes auto, cholesky, schur or streamed");
      } else if (a == "--threads") {
        s.threads = count();
        s.fgcal.threads = s.threads;
      }
      else if (a == "--timeout") s.timeout = std::stod(value());
      else if (a == "--seed") s.seed = std::stoull(value());
      else if (a == "--see") s.see = std::stod(value());
      else if (a == "--tolerance") s.fgcal.relative_cost_tolerance = std::stod(value());
      else if (a == "--max-iterations") s.fgcal.max_iterations = std::stoi(value());
      else if (a == "--solvers") {
        s.solvers.clear();
        std::stringstream ss(value());
        std::string item;
        while (std::getline(ss, item, ',')) {
          if (item != "fgcal" && item != "fgcal_chol" && item != "snc" && item != "schur")
            usage("unknown solver '" + item + "'");
          s.solvers.insert(item);
        }
      } else if (a == "-h" || a == "--help") usage("help");
      else usage("unknown option '" + a + "'");
    } catch (const std::logic_error&) {
      usage("bad value for " + a);
    }
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const Settings s = parseArgs(argc, argv);
#ifdef FGCAL_HAVE_CERES
  const bool have_ceres = true;
#else
  const bool have_ceres = false;
#endif
  [[maybe_unused]] const bool run_snc = have_ceres && s.solvers.count("snc");
  [[maybe_unused]] const bool run_schur = have_ceres && s.solvers.count("schur");
  const bool run_fgcal = s.solvers.count("fgcal") != 0;
  // fgcal_chol: fgcal forced onto CHOLMOD over the whole of H, to show what its Schur path buys.
  const bool run_fgcal_chol = s.solvers.count("fgcal_chol") != 0;
  OptimizerOptions chol_options = s.fgcal;
  chol_options.linear_solver = OptimizerOptions::LinearSolver::SparseCholesky;

  {
    // Map CHOLMOD and its BLAS in now so that the report names them.
    CalibrationProblem tiny = makeCalibrationProblem({1, 3, 1.0, 7});
    FactorGraph g;
    Values v;
    buildFgcalProblem(tiny, g, v);
    optimize(g, v);
  }
#ifdef FGCAL_HAVE_CERES
  const char* ceres_version = CERES_VERSION_STRING;
#else
  const char* ceres_version = "(not found at configure time: fgcal alone)";
#endif
  std::fprintf(stderr, "# bench_solver: fgcal LM (threads=%d) vs Ceres %s (num_threads=%d)\n", s.fgcal.threads,
               ceres_version, s.threads);
  std::fprintf(stderr, "# linear algebra mapped in this process: %s\n", librariesInUse().c_str());
  const char* omp = std::getenv("OMP_NUM_THREADS");
  std::fprintf(stderr, "# OMP_NUM_THREADS=%s (CHOLMOD's supernodal factorization uses OpenMP: set 1 for single-threaded figures)\n",
               omp ? omp : "(unset)");
  std::fprintf(stderr,
               "# stopping rule: relative cost decrease < %g, step < %g, max |g| < %g, <= %d iterations; "
               "initial lambda %g (Ceres: initial radius %g); best of %d run(s) (%d above %g factors, %d below %g), "
               "each in a forked child\n",
               s.fgcal.relative_cost_tolerance, s.fgcal.step_tolerance, s.fgcal.gradient_tolerance,
               s.fgcal.max_iterations, s.fgcal.initial_lambda, 1.0 / s.fgcal.initial_lambda, s.repeat, s.repeat_large,
               s.repeat_limit,
               std::max(s.repeat, s.repeat_small), s.small_limit);
#ifdef FGCAL_HAVE_CERES
  {
    const EvaluationMismatch m = compareWithFgcal(makeCalibrationProblem({4, 50, 0.6, s.seed}), 1000);
    std::fprintf(stderr, "# Ceres cost functions vs fgcal factors at the start: max rel. diff residual %.1e, Jacobian %.1e\n",
                 m.residual, m.jacobian);
  }
#endif

  std::printf(
      "cameras,frames,factors,fgcal_s,fgcal_iters,fgcal_s_per_iter,fgcal_linearize_s,fgcal_analyze_s,fgcal_solve_s,"
      "fgcal_other_s,fgcal_peak_mb,ceres_snc_s,ceres_snc_iters,ceres_snc_s_per_iter,ceres_snc_eval_s,"
      "ceres_snc_linear_s,ceres_snc_peak_mb,ceres_schur_s,ceres_schur_iters,ceres_schur_s_per_iter,"
      "ceres_schur_eval_s,ceres_schur_linear_s,ceres_schur_peak_mb,ratio_snc,ratio_schur,initial_cost,fgcal_cost,"
      "ceres_snc_cost,ceres_schur_cost,cost_rel_diff,camera_diff_mm,camera_diff_deg,fgcal_converged,"
      "ceres_snc_converged,ceres_schur_converged,gen_s,runs,fgcal_linear_solver,fgcal_chol_s,fgcal_chol_iters,"
      "fgcal_chol_linearize_s,fgcal_chol_solve_s,fgcal_chol_peak_mb,fgcal_chol_cost\n");
  std::fflush(stdout);

  for (const auto& [m, n] : s.sizes) {
    const auto tg = Clock::now();
    const CalibrationProblem p = makeCalibrationProblem({m, n, s.see, s.seed});
    const double gen_s = since(tg);
    std::fprintf(stderr, "\n## M=%d cameras, N=%d board poses: %zu factors, %d variables (generated in %.1f s)\n", m,
                 n, p.numFactors(), m + n, gen_s);
    const double nf = static_cast<double>(p.numFactors());
    const int repeat =
        nf > s.repeat_limit ? s.repeat_large : nf < s.small_limit ? std::max(s.repeat, s.repeat_small) : s.repeat;

    CaseResult fg, fgc, snc, schur;
    if (run_fgcal) fg = bestOf(s, repeat, [&] { return solveFgcal(p, s.fgcal); });
    if (run_fgcal_chol) fgc = bestOf(s, repeat, [&] { return solveFgcal(p, chol_options); });
#ifdef FGCAL_HAVE_CERES
    if (run_snc) snc = bestOf(s, repeat, [&] { return solveCeres(p, s, false); });
    if (run_schur) schur = bestOf(s, repeat, [&] { return solveCeres(p, s, true); });
#endif
    auto describe = [&](const char* name, const CaseResult& r) {
      if (r.status == 0) return;
      if (r.status != 1) {
        std::fprintf(stderr, "  %-12s FAILED: %s\n", name, r.message);
        return;
      }
      std::fprintf(stderr,
                   "  %-12s %8.3f s  %3d it  %.4f s/it  eval/linearize %.3f  analyze/preproc %.3f  "
                   "factor+solve %.3f  other %.3f  peak +%.0f MB (model %.0f MB)  cost %.10g -> %.10g  [%s]\n",
                   name, r.seconds, r.iterations, r.seconds / std::max(1, r.iterations), r.linearize_s,
                   r.analyze_s, r.solve_s, r.other_s, r.peak_mb, r.model_mb, r.initial_cost, r.final_cost,
                   r.termination);
    };
    describe("fgcal", fg);
    if (fg.status == 1) std::fprintf(stderr, "  %-12s linear solver: %s\n", "", fg.linear_solver);
    describe("fgcal chol", fgc);
    describe("ceres SNC", snc);
    describe("ceres SCHUR", schur);

    auto ok = [](const CaseResult& r) { return r.status == 1; };
    auto ratio = [&](const CaseResult& c) { return ok(fg) && ok(c) ? c.seconds / fg.seconds : NAN; };
    double rel = NAN;
    for (const CaseResult* c : {&snc, &schur, &fgc})
      if (ok(fg) && ok(*c)) {
        const double d = std::abs(c->final_cost - fg.final_cost) / std::max(fg.final_cost, 1e-300);
        rel = std::isnan(rel) ? d : std::max(rel, d);
      }
    std::pair<double, double> cam{NAN, NAN};
    if (ok(fg) && ok(snc)) cam = cameraDifference(fg, snc);
    if (ok(fg) && ok(schur)) {
      const auto c2 = cameraDifference(fg, schur);
      cam = {std::isnan(cam.first) ? c2.first : std::max(cam.first, c2.first),
             std::isnan(cam.second) ? c2.second : std::max(cam.second, c2.second)};
    }
    if (ok(fg))
      std::fprintf(stderr, "  ratio Ceres/fgcal: SNC %s  SCHUR %s   final cost rel. diff %s   camera diff %s mm %s deg\n",
                   num(ratio(snc), 3).c_str(), num(ratio(schur), 3).c_str(), num(rel, 2).c_str(),
                   num(cam.first, 2).c_str(), num(cam.second, 2).c_str());

    auto sec = [&](const CaseResult& r, double x) { return ok(r) ? num(x, 4) : std::string(); };
    auto it = [&](const CaseResult& r) { return ok(r) ? std::to_string(r.iterations) : std::string(); };
    auto per = [&](const CaseResult& r) { return ok(r) ? num(r.seconds / std::max(1, r.iterations), 4) : std::string(); };
    auto mb = [&](const CaseResult& r) { return ok(r) ? numFixed(r.peak_mb, 1) : std::string(); };
    auto cost = [&](const CaseResult& r) { return ok(r) ? num(r.final_cost, 12) : std::string(); };
    auto conv = [&](const CaseResult& r) {
      return r.status == 0 ? std::string() : r.status == 1 ? std::to_string(int(r.converged)) : std::string("fail");
    };
    std::ostringstream line;
    line << m << ',' << n << ',' << p.numFactors() << ',' << sec(fg, fg.seconds) << ',' << it(fg) << ',' << per(fg)
         << ',' << sec(fg, fg.linearize_s) << ',' << sec(fg, fg.analyze_s) << ',' << sec(fg, fg.solve_s) << ','
         << sec(fg, fg.other_s) << ',' << mb(fg) << ',' << sec(snc, snc.seconds) << ',' << it(snc) << ','
         << per(snc) << ',' << sec(snc, snc.linearize_s) << ',' << sec(snc, snc.solve_s) << ',' << mb(snc) << ','
         << sec(schur, schur.seconds) << ',' << it(schur) << ',' << per(schur) << ','
         << sec(schur, schur.linearize_s) << ',' << sec(schur, schur.solve_s) << ',' << mb(schur) << ','
         << num(ratio(snc), 4) << ',' << num(ratio(schur), 4) << ','
         << (ok(fg) ? num(fg.initial_cost, 12) : ok(snc) ? num(snc.initial_cost, 12) : std::string()) << ','
         << cost(fg) << ',' << cost(snc) << ',' << cost(schur) << ',' << num(rel, 3) << ',' << num(cam.first, 3)
         << ',' << num(cam.second, 3) << ',' << conv(fg) << ',' << conv(snc) << ',' << conv(schur) << ','
         << num(gen_s, 3) << ',' << repeat << ',' << (ok(fg) ? fg.linear_solver : "") << ','
         << sec(fgc, fgc.seconds) << ',' << it(fgc) << ',' << sec(fgc, fgc.linearize_s) << ','
         << sec(fgc, fgc.solve_s) << ',' << mb(fgc) << ',' << cost(fgc);
    std::printf("%s\n", line.str().c_str());
    std::fflush(stdout);
  }
  return 0;
}
