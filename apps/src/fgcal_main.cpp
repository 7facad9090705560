// The fgcal command: the list of commands and the exit codes of docs/ (0 ok,
// 1 data cannot support a calibration, 2 bad input or usage). Each command's
// options, their parsing and its run live in commands/<name>/<name>_command.cpp
// (commands/command_line.hpp); every command is a library call in fgcal::apps.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/errors.hpp"
#include "version.hpp"

int main(int argc, char** argv) {
  namespace commands = fgcal::apps::commands;
  // The name is given, not taken from argv[0], so that --help says "fgcal",
  // not the path the program was started from.
  CLI::App app{"fgcal: multi-camera extrinsic calibration of legged robots on a factor graph", "fgcal"};
  app.require_subcommand(1);
  app.footer(std::string("Examples:\n"
                         "  fgcal simulate --out ds && fgcal calibrate ds -o out/calibration.yaml\n"
                         "  fgcal evaluate out/calibration.yaml ds/ground_truth.yaml\n"
                         "  fgcal COMMAND --help   (each command's options and an example)\n\n") +
             commands::kHelpTrailer);
  // fgcal --version: project version and git commit (version.hpp).
  app.set_version_flag("--version", fgcal::apps::versionText(), "Print the version (and git commit) and exit");
  const std::vector<commands::Command> all = {
      commands::addCalibrateCommand(app), commands::addImportCommand(app), commands::addSimulateCommand(app),
      commands::addEvaluateCommand(app),  commands::addDemoCommand(app),   commands::addPoseGraphDemoCommand(app),
      commands::addBagInfoCommand(app),   commands::addInitCommand(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // help and version print and return 0
    return rc == 0 ? 0 : 2;
  }
  try {
    for (const commands::Command& c : all)
      if (*c.app) return c.run();
  } catch (const std::exception& e) {
    std::cerr << "fgcal: error: " << e.what() << "\n";
    return fgcal::apps::exitCodeFor(e);
  }
  return 2;
}
