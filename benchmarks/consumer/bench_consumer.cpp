// Solves of the calibration-shaped graph (benchmarks/core's generator)
// through fgcal's installed package: what a project embedding the solver
// runs. Prints the wall time of optimize() (meaningful on a quiet machine
// only; with REPEAT > 1 the best of that many solves of the same graph from
// the same start in this process, the first one paying the process's first
// touch of its memory), its iterations and costs; profile it with
//   valgrind --tool=callgrind "--toggle-collect=fgcal::optimize(*" bench_consumer M N SEE
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <fgcal/core/factor_graph.hpp>
#include <fgcal/core/optimizer.hpp>
#include <fgcal/core/values.hpp>
#include <fgcal/factors/prior_factor.hpp>
#include <fgcal/factors/relative_pose_factor.hpp>

#include "calibration_problem.hpp"

namespace {

// The graph of fgcal::bench::buildFgcalProblem, built here, in this program's
// own translation unit and with its flags, as a project embedding fgcal
// builds its graph: whatever the factor headers make the compiler emit (the
// factors' inline code, their virtual tables) is emitted with those flags.
void buildGraph(const fgcal::bench::CalibrationProblem& p, fgcal::FactorGraph& graph, fgcal::Values& initial) {
  using fgcal::bench::boardKey;
  using fgcal::bench::cameraKey;
  graph.reserve(p.numFactors());
  for (int i = 0; i < p.cameras; ++i) initial.insert(cameraKey(i), p.initial_cameras[static_cast<std::size_t>(i)]);
  for (int j = 0; j < p.frames; ++j) initial.insert(boardKey(j), p.initial_boards[static_cast<std::size_t>(j)]);
  auto noise = [](const fgcal::Mat6& W) { return fgcal::NoiseModel::fromInformation(fgcal::MatX(W.transpose() * W)); };
  std::size_t o = 0;
  for (int j = 0; j < p.frames; ++j) {
    const fgcal::bench::PoseMeasurement& prior = p.board_priors[static_cast<std::size_t>(j)];
    graph.emplace<fgcal::PriorFactorSE3>(boardKey(j), prior.measured, noise(prior.sqrt_information));
    for (; o < p.observations.size() && p.observations[o].frame == j; ++o) {
      const fgcal::bench::Observation& ob = p.observations[o];
      graph.emplace<fgcal::RelativePoseFactor>(cameraKey(ob.camera), boardKey(j), ob.z.measured,
                                               noise(ob.z.sqrt_information));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 6 || (argc > 1 && std::string(argv[1]) == "--help")) {
    std::fprintf(stderr,
                 "usage: bench_consumer [CAMERAS [BOARDS [SEE_PROBABILITY [SEED [REPEAT]]]]]  (default 1 1000 1 1 1)\n");
    return 2;
  }
  fgcal::bench::CalibrationProblemOptions o;
  o.cameras = argc > 1 ? std::atoi(argv[1]) : 1;
  o.frames = argc > 2 ? std::atoi(argv[2]) : 1000;
  o.see_probability = argc > 3 ? std::atof(argv[3]) : 1.0;
  o.seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1;
  const int repeat = argc > 5 ? std::atoi(argv[5]) : 1;
  if (o.cameras < 1 || o.frames < 1 || repeat < 1) {
    std::fprintf(stderr, "bench_consumer: CAMERAS, BOARDS and REPEAT must be >= 1\n");
    return 2;
  }
  const fgcal::bench::CalibrationProblem problem = fgcal::bench::makeCalibrationProblem(o);
  fgcal::FactorGraph graph;
  fgcal::Values initial;
  buildGraph(problem, graph, initial);
  fgcal::OptimizerResult res;
  double seconds = 0.0;
  for (int k = 0; k < repeat; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    res = fgcal::optimize(graph, initial, fgcal::OptimizerOptions{});
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (k == 0 || s < seconds) seconds = s;
  }
  std::printf("M=%d N=%d see=%g factors=%zu: %s, %d iterations, cost %.9g -> %.9g, %.6f s, %s\n", o.cameras,
              o.frames, o.see_probability, problem.numFactors(), fgcal::toString(res.termination).c_str(),
              res.iterations, res.initial_cost, res.final_cost, seconds, res.linear_solver.c_str());
  return res.converged ? 0 : 1;
}
