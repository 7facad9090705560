// What every command's file (commands/<name>/<name>_command.cpp) shares: the
// Command it hands to fgcal_main.cpp, the subcommand with its example, the
// end of every --help and the list splitting. Each command file holds its options,
// their parsing into the library's options struct and its run; fgcal_main.cpp
// only lists the commands and maps exceptions to exit codes. CLI11 is
// included by these files and fgcal_main.cpp only, never by the library.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace fgcal::apps::commands {

/// A subcommand: its CLI11 node and how it runs once parsed (the exit code).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// The end of every --help: the exit codes and where the documentation is.
inline const char* const kHelpTrailer =
    "Exit codes: 0 success (verdict ok or check); 1 the data cannot support a calibration, or the\n"
    "            verdict is unusable (the message or the findings say why and name the input);\n"
    "            2 bad input or usage (the message names the file, field or option).\n"
    "Documentation: README.md, docs/formats.md (dataset folder, rig.yaml, bags) and\n"
    "docs/outputs.md (what calibrate writes, evaluate) in fgcal's source tree.";

/// The subcommand `name`; `example` is shown by its --help with the exit
/// codes. The command's options bind to state its run lambda shares.
inline CLI::App* subcommand(CLI::App& app, const char* name, const char* description, const char* example) {
  CLI::App* cmd = app.add_subcommand(name, description);
  cmd->footer(std::string("Example:\n  ") + example + "\n\n" + kHelpTrailer);
  return cmd;
}

/// "a,b,,c" -> {a, b, c}.
inline std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// Each command adds itself to `app`, in the order of fgcal --help.
Command addCalibrateCommand(CLI::App& app);
Command addImportCommand(CLI::App& app);
Command addSimulateCommand(CLI::App& app);
Command addEvaluateCommand(CLI::App& app);
Command addDemoCommand(CLI::App& app);
Command addPoseGraphDemoCommand(CLI::App& app);
Command addBagInfoCommand(CLI::App& app);
Command addInitCommand(CLI::App& app);

}  // namespace fgcal::apps::commands
