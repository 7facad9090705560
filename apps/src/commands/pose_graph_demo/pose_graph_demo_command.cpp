// `fgcal pose-graph-demo`: options and the run (pose_graph_demo.hpp).
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "commands/pose_graph_demo/pose_graph_demo.hpp"

namespace fgcal::apps::commands {

namespace {

void addPoseGraphDemoOptions(CLI::App* cmd, PoseGraphDemoOptions& o) {
  cmd->add_option("--poses", o.poses, "number of poses")->check(CLI::Range(2, 10000000));
  cmd->add_option("--seed", o.seed, "random seed");
}

int runPoseGraphDemoCommand(PoseGraphDemoOptions& o) { return runPoseGraphDemo(o); }

}  // namespace

Command addPoseGraphDemoCommand(CLI::App& app) {
  return command(app, "pose-graph-demo", "The core engine alone on a noisy SE(3) pose graph",
                 "fgcal pose-graph-demo --poses 1000 --seed 1", addPoseGraphDemoOptions, runPoseGraphDemoCommand);
}

}  // namespace fgcal::apps::commands
