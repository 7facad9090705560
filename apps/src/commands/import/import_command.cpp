// `fgcal import`: options and the run (runImport, import.hpp).
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/import.hpp"

namespace fgcal::apps::commands {

namespace {

void addImportOptions(CLI::App* cmd, ImportOptions& o) {
  cmd->add_option("bag", o.bag, "a ROS 1 .bag, a ROS 2 bag folder (.db3 or .mcap) or an .mcap file")->required();
  cmd->add_option("--rig", o.rig, "rig.yaml naming each camera's topic")->required();
  cmd->add_option("--out", o.out, "dataset folder to create (must not exist, or be empty)")->required();
}

int runImportCommand(ImportOptions& o) {
  runImport(o, std::cerr);
  return 0;
}

}  // namespace

Command addImportCommand(CLI::App& app) {
  return command(app, "import", "Write a robot bag out as a dataset folder (images, joints.csv, rig.yaml)",
                 "fgcal import run.bag --rig rig.yaml --out dataset", addImportOptions, runImportCommand);
}

}  // namespace fgcal::apps::commands
