// The fgcal command. CLI11 lives in this one translation unit only (it costs
// seconds of compile time per unit that includes it).
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "pose_graph_demo.hpp"

int main(int argc, char** argv) {
  CLI::App app{"fgcal: multi-camera extrinsic calibration of legged robots on a factor graph"};
  app.require_subcommand(1);

  fgcal::apps::PoseGraphDemoOptions demo;
  CLI::App* demo_cmd = app.add_subcommand("demo", "Run the built-in demo");
  demo_cmd->add_option("--poses", demo.poses, "number of poses")->check(CLI::Range(2, 10000000));
  demo_cmd->add_option("--seed", demo.seed, "random seed");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints help with exit 0; every other parse error is a usage error: exit 2.
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  try {
    if (*demo_cmd) return fgcal::apps::runPoseGraphDemo(demo);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fgcal: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
