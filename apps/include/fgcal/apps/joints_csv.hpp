// joints.csv (docs/formats.md): header "stamp_ns,<joint>,...",
// then one row per sample with strictly increasing integer stamps (ns). Its
// reader (InputError with "line N" and the column name), a check of its columns
// against a kinematic chain, interpolation at image stamps, and a writer (for
// the simulator).
//
// NaN and inf values are legal in the file (a logged robot produces them) and
// are stored as NaN, so that the frames that need them are skipped and counted
// later instead of failing the whole run. An empty field is read as NaN too
// (pandas writes missing values that way) and counted in the warnings.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace fgcal::apps {

struct JointLog {
  std::vector<std::string> names;   ///< joint columns, file order (stamp_ns excluded)
  std::vector<int64_t> stamps_ns;   ///< strictly increasing
  Eigen::MatrixXd positions;        ///< samples x joints; non-finite values stored as NaN
  std::vector<std::string> warnings;
  /// When a JointLogFilter kept part of the source: every column of the
  /// source in its order (empty otherwise: names are all of them), and the
  /// number of samples it had.
  std::vector<std::string> source_names;
  std::size_t source_samples = 0;

  /// Column index of a joint, or -1.
  int column(const std::string& name) const;
};

/// What a reader keeps of a joint log. A calibration needs the joints of one
/// chain at the images' stamps; a long recording's log holds every joint of
/// the robot at hundreds of samples a second.
struct JointLogFilter {
  /// The joints kept, in this order; each must be a column (InputError as
  /// columnIndices gives). Empty: every column.
  std::vector<std::string> columns;
  /// Sorted stamps; when given, only the samples interpolate() reads at these
  /// stamps are kept (the two around each, or the one it hits) and the first
  /// and the last: interpolate() then gives at them exactly what it gives on
  /// the whole log. Not owned.
  const std::vector<int64_t>* around_stamps_ns = nullptr;
};

/// Reads joints.csv, in blocks (never whole), keeping what `filter` asks for
/// (everything when null); the file's own checks and warnings cover every
/// column and row all the same. Throws InputError naming the file and line
/// for: missing or empty file, header not starting with stamp_ns, empty or
/// duplicate column names, a row with the wrong number of fields, a
/// non-integer stamp, a non-numeric value (with the column name), a stamp not
/// larger than the one before, no data rows. Blank lines are ignored.
JointLog loadJointsCsv(const std::string& path, const JointLogFilter* filter = nullptr);
/// The same from text; `source_name` names it in messages.
JointLog parseJointsCsv(const std::string& text, const std::string& source_name,
                        const JointLogFilter* filter = nullptr);
/// The same selection applied to a log in memory; `file` names it in the
/// error for a missing column.
JointLog filterJointLog(const JointLog& log, const JointLogFilter& filter, const std::string& file);

/// Checks that every joint of the chain has a column. Missing ones: InputError
/// listing all of them and the columns present. Columns the chain does not use
/// are fine (a log holds every joint of the robot): returned as one warning
/// naming them (empty when none).
std::vector<std::string> checkColumns(const JointLog& log, const std::vector<std::string>& chain_joints,
                                      const std::string& file);

/// Column indices of `names` in log (e.g. a chain's jointNames()); throws
/// InputError like checkColumns when one is missing.
std::vector<int> columnIndices(const JointLog& log, const std::vector<std::string>& names,
                               const std::string& file);

/// Positions of the selected columns at `stamp_ns`, linear between the two
/// samples around it (the sample itself when the stamp hits one), found by
/// binary search: O(log n). Nullopt, with `why` set when given, when the stamp
/// is outside [first, last] stamp ("outside the recorded span ...") or a value
/// used is NaN ("NaN/inf in joint X near stamp S"); `failure`, when given,
/// says which of the two it was.
enum class JointLookupFailure { OutsideSpan, NotFinite };
std::optional<Eigen::VectorXd> interpolate(const JointLog& log, int64_t stamp_ns, const std::vector<int>& columns,
                                           std::string* why = nullptr, JointLookupFailure* failure = nullptr);

/// CSV text of a log; values round-trip exactly (shortest exact decimal form),
/// NaN written as "nan". positions: stamps.size() x names.size().
std::string formatJointsCsv(const std::vector<std::string>& names, const std::vector<int64_t>& stamps_ns,
                            const Eigen::MatrixXd& positions);
/// Writes that text atomically (see writeFileAtomically). Throws InputError on
/// a size mismatch or when the file cannot be written.
void writeJointsCsv(const std::string& path, const std::vector<std::string>& names,
                    const std::vector<int64_t>& stamps_ns, const Eigen::MatrixXd& positions);

}  // namespace fgcal::apps
