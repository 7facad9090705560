// `fgcal bag-info`: its options and its run (bag_info.hpp).
#include <iostream>
#include <memory>
#include <string>

#include "commands/command_line.hpp"
#include "fgcal/apps/bag_info.hpp"

namespace fgcal::apps::commands {

Command addBagInfoCommand(CLI::App& app) {
  CLI::App* cmd =
      subcommand(app, "bag-info", "List a ROS 1 / ROS 2 bag's topics, types, counts and rates (no ROS needed)",
                 "fgcal bag-info run.mcap --stamps");
  auto bag = std::make_shared<std::string>();
  auto stamps = std::make_shared<bool>(false);
  cmd->add_option("bag", *bag, "a ROS 1 .bag, a ROS 2 bag folder or .db3, or an .mcap file")->required();
  cmd->add_flag("--stamps", *stamps,
                "also read header.stamp of every JointState, Image, CompressedImage and CameraInfo message "
                "(reads those topics whole)");
  return {cmd, [bag, stamps] {
            std::cout << formatBagInfo(summarizeBag(*bag, *stamps));
            return 0;
          }};
}

}  // namespace fgcal::apps::commands
