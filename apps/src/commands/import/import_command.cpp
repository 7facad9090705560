// `fgcal import`: its options and its run (runImport, import.hpp).
#include <iostream>
#include <memory>

#include "commands/command_line.hpp"
#include "fgcal/apps/import.hpp"

namespace fgcal::apps::commands {

Command addImportCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "import", "Write a robot bag out as a dataset folder (images, joints.csv, rig.yaml)",
                             "fgcal import run.bag --rig rig.yaml -o dataset");
  auto o = std::make_shared<ImportOptions>();
  cmd->add_option("bag", o->bag, "a ROS 1 .bag, a ROS 2 bag folder (.db3 or .mcap) or an .mcap file")->required();
  cmd->add_option("--rig", o->rig, "rig.yaml naming each camera's topic")->required();
  cmd->add_option("-o,--out", o->out, "dataset folder to create (must not exist, or be empty)")->required();
  return {cmd, [o] {
            runImport(*o, std::cerr);
            return 0;
          }};
}

}  // namespace fgcal::apps::commands
