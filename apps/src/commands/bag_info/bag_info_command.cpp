// `fgcal bag-info`: options and the run (bag_info.hpp).
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/bag_info.hpp"

namespace fgcal::apps::commands {

namespace {

struct BagInfoArgs {
  std::string bag;
  bool stamps = false;  ///< --stamps: read every header stamp
};

void addBagInfoOptions(CLI::App* cmd, BagInfoArgs& a) {
  cmd->add_option("bag", a.bag, "a ROS 1 .bag, a ROS 2 bag folder or .db3, or an .mcap file")->required();
  cmd->add_flag("--stamps", a.stamps,
                "also read header.stamp of every JointState, Image, CompressedImage and CameraInfo message "
                "(reads those topics whole)");
}

int runBagInfoCommand(BagInfoArgs& a) {
  std::cout << formatBagInfo(summarizeBag(a.bag, a.stamps));
  return 0;
}

}  // namespace

Command addBagInfoCommand(CLI::App& app) {
  return command(app, "bag-info", "List a ROS 1 / ROS 2 bag's topics, types, counts and rates (no ROS needed)",
                 "fgcal bag-info run.mcap --stamps", addBagInfoOptions, runBagInfoCommand);
}

}  // namespace fgcal::apps::commands
