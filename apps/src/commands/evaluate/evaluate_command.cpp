// `fgcal evaluate`: its options and its run (evaluate.hpp; camchain.hpp for
// a Kalibr result, whose relative poses alone are scored).
#include <iostream>
#include <memory>
#include <string>

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

int runEvaluate(const EvaluateArgs& a) {
  if (looksLikeKalibrCamchain(readTextFile(a.calibration, "calibration result"))) {
    const auto rel =
        evaluateCamchain(loadKalibrCamchain(a.calibration), loadGroundTruth(a.ground_truth), a.calibration);
    std::cout << formatRelativeEvaluationTable(rel);
  } else {
    std::cout << formatEvaluationTable(evaluateFiles(a.calibration, a.ground_truth));
  }
  return 0;
}

}  // namespace

Command addEvaluateCommand(CLI::App& app) {
  CLI::App* cmd = subcommand(app, "evaluate",
                             "Compare a calibration with ground truth (Table I, NEES; time offsets, joint offsets and "
                             "intrinsics when estimated, in sigmas)",
                             "fgcal evaluate out/calibration.yaml ds/ground_truth.yaml   (the result first, then the "
                             "truth)");
  auto a = std::make_shared<EvaluateArgs>();
  cmd->add_option("calibration", a->calibration, "calibration.yaml, or a Kalibr camchain.yaml (relative poses only)")
      ->required();
  cmd->add_option("ground_truth", a->ground_truth, "ground_truth.yaml")->required();
  return {cmd, [a] { return runEvaluate(*a); }};
}

}  // namespace fgcal::apps::commands
