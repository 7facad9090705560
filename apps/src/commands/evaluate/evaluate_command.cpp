// `fgcal evaluate`: options and the run (evaluate.hpp, camchain.hpp for a Kalibr result).
#include <iostream>
#include <string>
#include <vector>

#include "commands/command_line.hpp"
#include "fgcal/apps/camchain.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"

namespace fgcal::apps::commands {

namespace {

struct EvaluateArgs {
  std::string calibration;   ///< calibration.yaml or a Kalibr camchain.yaml
  std::string ground_truth;  ///< ground_truth.yaml
};

void addEvaluateOptions(CLI::App* cmd, EvaluateArgs& a) {
  cmd->add_option("calibration", a.calibration, "calibration.yaml, or a Kalibr camchain.yaml (relative poses only)")
      ->required();
  cmd->add_option("ground_truth", a.ground_truth, "ground_truth.yaml")->required();
}

int runEvaluateCommand(EvaluateArgs& a) {
  if (looksLikeKalibrCamchain(readTextFile(a.calibration, "calibration result"))) {
    const auto rel =
        evaluateCamchain(loadKalibrCamchain(a.calibration), loadGroundTruth(a.ground_truth), a.calibration);
    std::cout << formatRelativeEvaluationTable(rel);
    return 0;
  }
  const auto ev = evaluateFiles(a.calibration, a.ground_truth);
  std::cout << formatEvaluationTable(ev);
  return 0;
}

}  // namespace

Command addEvaluateCommand(CLI::App& app) {
  return command(app, "evaluate",
                 "Compare a calibration with ground truth (Table I, NEES; time offsets, joint offsets and intrinsics "
                 "when estimated, in sigmas)",
                 "fgcal evaluate out/calibration.yaml ds/ground_truth.yaml   (the result first, then the truth)",
                 addEvaluateOptions, runEvaluateCommand);
}

}  // namespace fgcal::apps::commands
