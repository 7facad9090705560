// `fgcal pose-graph-demo`: its options and its run (pose_graph_demo.hpp).
#include <memory>

#include "commands/command_line.hpp"
#include "commands/pose_graph_demo/pose_graph_demo.hpp"

namespace fgcal::apps::commands {

Command addPoseGraphDemoCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "pose-graph-demo", "The core engine alone on a noisy SE(3) pose graph",
                             "fgcal pose-graph-demo --poses 1000 --seed 1");
  auto o = std::make_shared<PoseGraphDemoOptions>();
  cmd->add_option("--poses", o->poses, "number of poses")->check(CLI::Range(2, 10000000));
  cmd->add_option("--seed", o->seed, "random seed");
  return {cmd, [o] { return runPoseGraphDemo(*o); }};
}

}  // namespace fgcal::apps::commands
