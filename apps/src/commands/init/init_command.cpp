// `fgcal init`: its options and its run (runInit, rig_init.hpp): a commented
// starter rig.yaml.
#include <iostream>
#include <memory>

#include "commands/command_line.hpp"
#include "fgcal/apps/rig_init.hpp"

namespace fgcal::apps::commands {

Command addInitCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "init", "Write a starter rig.yaml from a URDF, the board and camera_info",
                             "fgcal init --urdf robot.urdf --base-link base --marker-link LF_FOOT "
                             "--board 5x7:0.04:0.03:DICT_4X4_50 --bag run.mcap -o rig.yaml");
  auto o = std::make_shared<InitOptions>();
  cmd->add_option("--urdf", o->urdf, "robot description")->required();
  cmd->add_option("--base-link", o->base_link, "base link")->required();
  cmd->add_option("--marker-link", o->marker_link, "link the board is fixed to")->required();
  cmd->add_option("--board", o->board,
                  "SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY, e.g. 5x7:0.04:0.03:DICT_4X4_50 (metres)")
      ->required();
  CLI::Option* bag =
      cmd->add_option("--bag", o->bag, "ROS 1 .bag, ROS 2 bag folder or .mcap: cameras from its CameraInfo topics");
  cmd->add_option("--camera-info", o->camera_infos,
                  "NAME:FILE or FILE: intrinsics in ROS camera_info, Kalibr camchain or OpenCV format")
      ->excludes(bag);
  cmd->add_option("-o,--out,--output", o->output,
                  "rig.yaml to write (its folder must exist; --output: the old spelling)")
      ->required();
  cmd->add_flag("--force", o->overwrite, "replace an existing output file");
  return {cmd, [o] {
            runInit(*o, std::cout);
            return 0;
          }};
}

}  // namespace fgcal::apps::commands
