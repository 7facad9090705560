// The C++ side of the Python module's pose-graph test: reads a pose graph in
// a small text format (written by test_core.py), solves it with fgcal's
// optimizer directly, and prints the solution, the solver's figures and a
// marginal covariance, every number in the shortest form that reads back to
// the same double. The Python test builds the same graph through the module
// and compares: what the bindings convert (matrices, noise models, keys,
// options) must not change the answer.
//
// Input, one item per line (4x4 matrices as 16 numbers row-major):
//   options ALGORITHM MAX_ITERATIONS          ALGORITHM: gauss_newton | levenberg_marquardt
//   pose KEY_INDEX T                          initial value of key('x', KEY_INDEX)
//   prior KEY_INDEX T SIGMA*6
//   between A B T SIGMA*6 HUBER_K             HUBER_K 0: no robust kernel
//   covariance KEY_INDEX                      print this marginal covariance
// Output: "pose I T", "covariance I C (36)", "result ITERATIONS INITIAL_COST FINAL_COST CONVERGED".
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "fgcal/core/marginals.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace {

fgcal::SE3 readPose(std::istream& in) {
  fgcal::Mat4 T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) in >> T(r, c);
  return fgcal::SE3(T);
}

fgcal::Vec6 readSigmas(std::istream& in) {
  fgcal::Vec6 s;
  for (int i = 0; i < 6; ++i) in >> s[i];
  return s;
}

void print(const char* what, long index, const double* data, int n) {
  std::printf("%s %ld", what, index);
  for (int i = 0; i < n; ++i) std::printf(" %.17g", data[i]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: pose_graph_reference GRAPH.txt\n";
    return 2;
  }
  std::ifstream file(argv[1]);
  if (!file) {
    std::cerr << "pose_graph_reference: cannot read " << argv[1] << "\n";
    return 2;
  }
  fgcal::FactorGraph graph;
  fgcal::Values initial;
  fgcal::OptimizerOptions options;
  std::vector<long> covariance_keys;
  for (std::string line; std::getline(file, line);) {
    std::istringstream in(line);
    std::string kind;
    in >> kind;
    if (kind == "options") {
      std::string algorithm;
      in >> algorithm >> options.max_iterations;
      options.algorithm = algorithm == "gauss_newton" ? fgcal::OptimizerOptions::Algorithm::GaussNewton
                                                      : fgcal::OptimizerOptions::Algorithm::LevenbergMarquardt;
    } else if (kind == "pose") {
      long i;
      in >> i;
      initial.insert(fgcal::key('x', i), readPose(in));
    } else if (kind == "prior") {
      long i;
      in >> i;
      const fgcal::SE3 Z = readPose(in);
      graph.emplace<fgcal::PriorFactorSE3>(fgcal::key('x', i), Z, fgcal::NoiseModel::diagonal(readSigmas(in)));
    } else if (kind == "between") {
      long a, b;
      double k;
      in >> a >> b;
      const fgcal::SE3 Z = readPose(in);
      const fgcal::Vec6 s = readSigmas(in);
      in >> k;
      graph.emplace<fgcal::RelativePoseFactor>(fgcal::key('x', a), fgcal::key('x', b), Z,
                                               fgcal::NoiseModel::diagonal(s), k > 0 ? fgcal::huber(k) : nullptr);
    } else if (kind == "covariance") {
      long i;
      in >> i;
      covariance_keys.push_back(i);
    }
    if (!kind.empty() && in.fail()) {
      std::cerr << "pose_graph_reference: cannot read the line '" << line << "'\n";
      return 2;
    }
  }
  const fgcal::OptimizerResult res = fgcal::optimize(graph, initial, options);
  for (const fgcal::Key k : res.values.keys()) {
    const fgcal::Mat4 T = res.values.at<fgcal::SE3>(k).matrix().transpose();  // row-major
    print("pose", static_cast<long>(fgcal::keyIndex(k)), T.data(), 16);
  }
  const fgcal::Marginals marginals(graph, res.values);
  for (const long i : covariance_keys) {
    const fgcal::MatX C = marginals.covariance(fgcal::key('x', i));  // symmetric: storage order does not matter
    print("covariance", i, C.data(), 36);
  }
  std::printf("result %d %.17g %.17g %d\n", res.iterations, res.initial_cost, res.final_cost, res.converged ? 1 : 0);
  return 0;
}
