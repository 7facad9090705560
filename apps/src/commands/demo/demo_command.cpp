// `fgcal demo`: its options and its run (runDemo, demo.hpp).
#include <iostream>
#include <memory>

#include "commands/command_line.hpp"
#include "fgcal/apps/demo.hpp"

namespace fgcal::apps::commands {

Command addDemoCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "demo", "Simulate, calibrate with F1 and F2, evaluate: the whole product",
                             "fgcal demo --frames 60 --keep demo_out");
  auto o = std::make_shared<DemoOptions>();
  cmd->add_option("--frames", o->frames, "image instants")->capture_default_str()->check(CLI::Range(10, 100000));
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--keep", o->keep_dir, "keep the dataset and results in this folder");
  return {cmd, [o] { return runDemo(*o, std::cout); }};
}

}  // namespace fgcal::apps::commands
