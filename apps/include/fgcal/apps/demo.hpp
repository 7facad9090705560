// `fgcal demo`: the whole product on a built-in default. Simulates a dataset
// of fgcal's HyQ-like robot into a temporary folder, calibrates it with one
// camera at a time (F1) and with both cameras jointly (F2), evaluates both
// against the ground truth and prints the table.
#pragma once

#include <iosfwd>
#include <string>

namespace fgcal::apps {

struct DemoOptions {
  int frames = 300;
  unsigned seed = 1;
  std::string keep_dir;  // keep the dataset and results here instead of a temporary folder
  int threads = 0;
};

/// Returns the exit code (0 when both calibrations succeeded).
int runDemo(const DemoOptions& options, std::ostream& log);

}  // namespace fgcal::apps
