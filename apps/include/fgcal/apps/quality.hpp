// A calibration's verdict on itself (docs/outputs.md, "quality"): findings
// that the graph's own statistics justify, each naming the inputs to check,
// and the verdict they add up to. calibration.yaml writes it as its top-level
// `quality:` block; `fgcal calibrate` prints it first and exits 1, writing no
// calibration output, when the verdict is `unusable`.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace fgcal::apps {

/// How much a finding weighs. A note informs and leaves the verdict alone; a
/// check says the result may be wrong and which input to look at; unusable
/// says the result must not be used.
enum class Severity { Note, Check, Unusable };
/// "note", "check", "unusable".
const char* toString(Severity s);

/// One finding. `check` is a stable id (docs/outputs.md lists them all);
/// `fields` name what to fix: rig.yaml paths as docs/formats.md spells them
/// (`target.square_size`, `robot.T_link_marker`, `cameras[cam0].intrinsics`)
/// or inputs (`joints.csv`, `joints.csv:COLUMN`).
struct Finding {
  std::string check;
  Severity severity = Severity::Note;
  std::vector<std::string> fields;
  std::string message;
  /// What the data suggest instead, when they allow an estimate: (key, value)
  /// pairs, the value a YAML scalar or flow sequence as written.
  std::vector<std::pair<std::string, std::string>> estimate;
  /// The exact command that applies the suggested fix, when it is an option
  /// of fgcal's; empty otherwise.
  std::string command;
};

enum class Verdict { Ok, Check, Unusable };
/// "ok", "check", "unusable".
const char* toString(Verdict v);

/// One test's statistic: its chi-square, the degrees of freedom of its
/// distribution on a correct input, and the probability of a larger value
/// there (a finding fires below the false-alarm rate, docs/outputs.md).
struct Statistic {
  std::string test;  ///< e.g. "fiducial cam0", "kinematic", "mount_prior", "time_offset cam1"
  double chi2 = 0.0;
  double dof = 0.0;
  double p = 1.0;
};

struct Quality {
  Verdict verdict = Verdict::Ok;
  std::vector<Finding> findings;
  /// Every test's statistic, flagged or not (written as `statistics:`).
  std::vector<Statistic> statistics;

  /// Adds a finding and raises the verdict to its severity (a note leaves it).
  void add(Finding f);
  /// True when a finding with this check id is present.
  bool has(const std::string& check) const;
};

}  // namespace fgcal::apps
