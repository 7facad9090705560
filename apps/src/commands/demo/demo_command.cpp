// `fgcal demo`: options and the run (runDemo, demo.hpp).
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/demo.hpp"

namespace fgcal::apps::commands {

namespace {

void addDemoOptions(CLI::App* cmd, DemoOptions& o) {
  cmd->add_option("--frames", o.frames, "image instants")->capture_default_str()->check(CLI::Range(10, 100000));
  cmd->add_option("--seed", o.seed, "random seed")->capture_default_str();
  cmd->add_option("--keep", o.keep_dir, "keep the dataset and results in this folder");
}

int runDemoCommand(DemoOptions& o) { return runDemo(o, std::cout); }

}  // namespace

Command addDemoCommand(CLI::App& app) {
  return command(app, "demo", "Simulate, calibrate with F1 and F2, evaluate: the whole product",
                 "fgcal demo --frames 60 --keep demo_out", addDemoOptions, runDemoCommand);
}

}  // namespace fgcal::apps::commands
