// The core demo: a noisy SE(3) pose graph with loop closures, solved by
// Levenberg-Marquardt, errors against the truth printed.
#pragma once

namespace fgcal::apps {

struct PoseGraphDemoOptions {
  int poses = 1000;
  int poses_per_turn = 50;
  unsigned seed = 1;
};

/// Returns the process exit code.
int runPoseGraphDemo(const PoseGraphDemoOptions& options);

}  // namespace fgcal::apps
