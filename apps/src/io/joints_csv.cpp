// joints.csv reader (streamed, with what a JointLogFilter keeps), column check,
// interpolation and writer (see joints_csv.hpp).
#include "fgcal/apps/joints_csv.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps {

int JointLog::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Splits on ',' into `out` (reused between rows to avoid allocation).
void splitFields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      out.push_back(trim(line.substr(start)));
      return;
    }
    out.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

std::string quoteField(std::string_view s) {
  std::string v(s.substr(0, 40));
  if (s.size() > 40) v += "...";
  return "'" + v + "'";
}

bool parseValue(std::string_view s, double* out) {
  if (s.empty()) return false;
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (*first == '+') ++first;
  const auto res = std::from_chars(first, last, *out);  // accepts nan, inf, infinity in any case
  return res.ec == std::errc() && res.ptr == last;
}

/// The error of a chain joint without a column: all missing ones, with the columns present.
[[noreturn]] void throwMissingColumns(const std::vector<std::string>& missing, std::size_t wanted,
                                      const std::vector<std::string>& present, const std::string& file) {
  throw InputError(file, "line 1 (header)",
                   "expected a column for every joint of the kinematic chain; missing " +
                       std::to_string(missing.size()) + " of " + std::to_string(wanted) + ": " +
                       detail::joinNames(missing) + "; the file has: stamp_ns, " + detail::joinNames(present));
}

/// Which samples a filter keeps, decided as rows arrive in stamp order: the
/// first and the last, and those interpolate() reads at each stamp asked for
/// (the two around it, or the one it hits).
class SampleSelector {
 public:
  explicit SampleSelector(const std::vector<std::int64_t>* around) : around_(around) {}
  struct Decision {
    bool keep_previous = false;  ///< the row before this one, not kept when it came, is needed now
    bool keep = false;           ///< this row
  };
  Decision next(std::int64_t stamp) {
    if (!around_) return {false, true};
    const std::vector<std::int64_t>& s = *around_;
    bool inside = false, hit = false;
    for (; next_ < s.size() && s[next_] <= stamp; ++next_) {
      if (s[next_] == stamp) hit = true;
      else if (rows_ > 0) inside = true;  // after the previous row (earlier stamps were consumed by it)
    }
    const Decision d{inside && !previous_kept_, rows_ == 0 || inside || hit};
    previous_kept_ = d.keep;
    ++rows_;
    return d;
  }
  /// After the last row: true when it is still to be kept.
  bool keepLast() const { return around_ && rows_ > 0 && !previous_kept_; }

 private:
  const std::vector<std::int64_t>* around_;
  std::size_t next_ = 0, rows_ = 0;
  bool previous_kept_ = false;
};

/// joints.csv read line by line, keeping what a JointLogFilter asks for.
class JointsCsvReader {
 public:
  JointsCsvReader(std::string file, const JointLogFilter* filter)
      : file_(std::move(file)), filter_(filter), selector_(filter ? filter->around_stamps_ns : nullptr) {}

  /// One line, without its '\n'.
  void line(std::string_view line) {
    ++line_no_;
    if (line_no_ == 1 && line.size() >= 3 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 BOM
    if (trim(line).empty()) return;
    const std::string where = "line " + std::to_string(line_no_);
    splitFields(line, fields_);
    if (have_header_) {
      row(where);
    } else {
      header(line, where);
      have_header_ = true;
    }
  }

  JointLog finish() {
    if (!have_header_)
      throw InputError(file_, "line 1", "expected the header 'stamp_ns,<joint name>,...', got an empty file");
    if (rows_ == 0)
      throw InputError(file_, "line " + std::to_string(line_no_),
                       "expected at least one data row after the header, got none");
    if (selector_.keepLast()) keep(previous_stamp_, previous_);
    if (filter_) log_.source_samples = rows_;
    const Eigen::Index rows = static_cast<Eigen::Index>(log_.stamps_ns.size());
    const Eigen::Index cols = static_cast<Eigen::Index>(log_.names.size());
    log_.positions = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        values_.data(), rows, cols);
    if (nonfinite_ > 0) {
      std::string per;
      for (const auto& [name, n] : nonfinite_by_joint_) per += (per.empty() ? "" : ", ") + name + " " + std::to_string(n);
      log_.warnings.push_back(file_ + ": " + std::to_string(nonfinite_) + " NaN/inf/empty value" +
                              (nonfinite_ == 1 ? "" : "s") + " (" + per +
                              (empty_ ? "; " + std::to_string(empty_) + " of them empty fields" : "") +
                              "); images needing them are skipped");
    }
    return std::move(log_);
  }

 private:
  /// The joint names: unique, none empty, none called stamp_ns; then the
  /// columns kept (every one, or the filter's, each required).
  void header(std::string_view line, const std::string& where) {
    if (fields_[0] != "stamp_ns")
      throw InputError(file_, where,
                       "expected the header 'stamp_ns,<joint name>,...' with stamp_ns as first column, got " +
                           quoteField(line));
    if (fields_.size() < 2)
      throw InputError(file_, where, "expected at least one joint column after stamp_ns, got only stamp_ns");
    for (std::size_t i = 1; i < fields_.size(); ++i) {
      const std::string name(fields_[i]);
      if (name.empty())
        throw InputError(file_, where,
                         "expected a joint name in column " + std::to_string(i + 1) + ", got an empty one");
      const auto prev = std::find(all_names_.begin(), all_names_.end(), name);
      if (prev != all_names_.end() || name == "stamp_ns")
        throw InputError(file_, where,
                         "expected unique column names, got '" + name + "' twice (columns " +
                             std::to_string(prev != all_names_.end() ? prev - all_names_.begin() + 2 : 1) + " and " +
                             std::to_string(i + 1) + ")");
      all_names_.push_back(name);
    }
    chooseColumns();
  }

  void chooseColumns() {
    if (!filter_ || filter_->columns.empty()) {
      log_.names = all_names_;
      for (std::size_t i = 0; i < all_names_.size(); ++i) kept_.push_back(i);
      return;
    }
    std::vector<std::string> missing;
    for (const auto& n : filter_->columns) {
      const auto it = std::find(all_names_.begin(), all_names_.end(), n);
      if (it == all_names_.end()) missing.push_back(n);
      else kept_.push_back(static_cast<std::size_t>(it - all_names_.begin()));
    }
    if (!missing.empty()) throwMissingColumns(missing, filter_->columns.size(), all_names_, file_);
    log_.names = filter_->columns;
    log_.source_names = all_names_;
  }

  /// A data row: its stamp (an integer, strictly after the previous row's)
  /// and every value checked; the kept columns kept when the row is.
  void row(const std::string& where) {
    const std::size_t ncols = all_names_.size() + 1;
    if (fields_.size() != ncols)
      throw InputError(file_, where,
                       "expected " + std::to_string(ncols) + " comma-separated fields (stamp_ns and " +
                           std::to_string(all_names_.size()) + " joints, as in the header), got " +
                           std::to_string(fields_.size()));
    const std::int64_t stamp = parseStamp(fields_[0], where);
    row_.resize(all_names_.size());
    for (std::size_t j = 1; j < ncols; ++j) row_[j - 1] = parseJointValue(j, where);
    const SampleSelector::Decision d = selector_.next(stamp);
    if (d.keep_previous) keep(previous_stamp_, previous_);
    previous_.clear();
    for (std::size_t k : kept_) previous_.push_back(row_[k]);
    previous_stamp_ = stamp;
    if (d.keep) keep(stamp, previous_);
    ++rows_;
  }

  std::int64_t parseStamp(std::string_view f, const std::string& where) const {
    std::int64_t stamp = 0;
    const auto res = std::from_chars(f.data(), f.data() + f.size(), stamp);
    if (f.empty() || res.ec != std::errc() || res.ptr != f.data() + f.size())
      throw InputError(file_, where + ", column stamp_ns",
                       "expected an integer time stamp in nanoseconds, got " + quoteField(f));
    if (rows_ > 0 && stamp <= previous_stamp_)
      throw InputError(file_, where + ", column stamp_ns",
                       "expected stamps strictly increasing, got " + std::to_string(stamp) +
                           (stamp == previous_stamp_ ? " again" : " after " + std::to_string(previous_stamp_)));
    return stamp;
  }

  /// Field j's position; NaN (counted) for an empty, NaN or infinite field.
  double parseJointValue(std::size_t j, const std::string& where) {
    double x = 0.0;
    if (fields_[j].empty()) {
      x = std::numeric_limits<double>::quiet_NaN();
      ++empty_;
    } else if (!parseValue(fields_[j], &x)) {
      throw InputError(file_, where + ", column " + all_names_[j - 1],
                       "expected a number (joint position), got " + quoteField(fields_[j]));
    }
    if (!std::isfinite(x)) {
      x = std::numeric_limits<double>::quiet_NaN();
      ++nonfinite_;
      ++nonfinite_by_joint_[all_names_[j - 1]];
    }
    return x;
  }

  void keep(std::int64_t stamp, const std::vector<double>& values) {
    log_.stamps_ns.push_back(stamp);
    values_.insert(values_.end(), values.begin(), values.end());
  }

  std::string file_;
  const JointLogFilter* filter_;
  SampleSelector selector_;
  JointLog log_;
  std::vector<std::string> all_names_;
  std::vector<std::size_t> kept_;  ///< kept columns, indices into all_names_
  std::vector<std::string_view> fields_;
  std::vector<double> row_, previous_, values_;  ///< values_: kept rows x kept columns, row-major
  std::int64_t previous_stamp_ = 0;
  std::size_t rows_ = 0, empty_ = 0, nonfinite_ = 0;
  std::map<std::string, int> nonfinite_by_joint_;
  int line_no_ = 0;
  bool have_header_ = false;
};

/// Feeds `text` to the reader line by line; a last line without '\n' counts
/// when it is not empty. Returns what was left after the last '\n'.
std::string_view feedLines(std::string_view text, JointsCsvReader& reader) {
  std::size_t pos = 0;
  for (std::size_t eol; (eol = text.find('\n', pos)) != std::string_view::npos; pos = eol + 1)
    reader.line(text.substr(pos, eol - pos));
  return text.substr(pos);
}

}  // namespace

JointLog parseJointsCsv(const std::string& text, const std::string& source_name, const JointLogFilter* filter) {
  JointsCsvReader reader(source_name, filter);
  const std::string_view rest = feedLines(text, reader);
  if (!rest.empty()) reader.line(rest);
  return reader.finish();
}

JointLog loadJointsCsv(const std::string& path, const JointLogFilter* filter) {
  const std::string what = "joints.csv (joint positions over time)";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "", what + " not found");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "", "expected " + what + ", got a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open " + what + " for reading: " + std::strerror(errno));
  // Read in blocks, never whole: a long recording's joints.csv is hundreds of megabytes.
  JointsCsvReader reader(path, filter);
  std::string carry;
  std::vector<char> block(1 << 20);
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    carry.append(block.data(), static_cast<std::size_t>(in.gcount()));
    carry.erase(0, carry.size() - feedLines(carry, reader).size());
  }
  if (in.bad()) throw InputError(path, "", "error while reading " + what);
  if (!carry.empty()) reader.line(carry);
  return reader.finish();
}

JointLog filterJointLog(const JointLog& log, const JointLogFilter& filter, const std::string& file) {
  const std::vector<std::string>& present = log.source_names.empty() ? log.names : log.source_names;
  std::vector<Eigen::Index> columns;
  std::vector<std::string> missing;
  for (const auto& name : filter.columns) {
    const int c = log.column(name);
    if (c < 0) missing.push_back(name);
    columns.push_back(c);
  }
  if (!missing.empty()) throwMissingColumns(missing, filter.columns.size(), present, file);
  if (filter.columns.empty())
    for (std::size_t c = 0; c < log.names.size(); ++c) columns.push_back(static_cast<Eigen::Index>(c));
  std::vector<Eigen::Index> rows;
  SampleSelector selector(filter.around_stamps_ns);
  for (std::size_t r = 0; r < log.stamps_ns.size(); ++r) {
    const SampleSelector::Decision d = selector.next(log.stamps_ns[r]);
    if (d.keep_previous) rows.push_back(static_cast<Eigen::Index>(r) - 1);
    if (d.keep) rows.push_back(static_cast<Eigen::Index>(r));
  }
  if (selector.keepLast()) rows.push_back(static_cast<Eigen::Index>(log.stamps_ns.size()) - 1);
  JointLog out;
  for (Eigen::Index c : columns) out.names.push_back(log.names[static_cast<std::size_t>(c)]);
  for (Eigen::Index r : rows) out.stamps_ns.push_back(log.stamps_ns[static_cast<std::size_t>(r)]);
  out.positions = log.positions(rows, columns);
  out.warnings = log.warnings;
  out.source_names = present;
  out.source_samples = log.source_samples ? log.source_samples : log.stamps_ns.size();
  return out;
}

std::vector<int> columnIndices(const JointLog& log, const std::vector<std::string>& names, const std::string& file) {
  std::vector<int> idx;
  std::vector<std::string> missing;
  for (const auto& n : names) {
    const int c = log.column(n);
    if (c < 0) missing.push_back(n);
    idx.push_back(c);
  }
  if (!missing.empty())
    throwMissingColumns(missing, names.size(), log.source_names.empty() ? log.names : log.source_names, file);
  return idx;
}

std::vector<std::string> checkColumns(const JointLog& log, const std::vector<std::string>& chain_joints,
                                      const std::string& file) {
  columnIndices(log, chain_joints, file);
  std::vector<std::string> unused;
  for (const auto& n : log.names)
    if (std::find(chain_joints.begin(), chain_joints.end(), n) == chain_joints.end()) unused.push_back(n);
  if (unused.empty()) return {};
  return {file + ": " + std::to_string(unused.size()) + " column" + (unused.size() == 1 ? "" : "s") +
          " not on the kinematic chain, ignored: " + detail::joinNames(unused)};
}

std::optional<Eigen::VectorXd> interpolate(const JointLog& log, int64_t stamp, const std::vector<int>& columns,
                                           std::string* why, JointLookupFailure* failure) {
  const auto& st = log.stamps_ns;
  if (st.empty() || stamp < st.front() || stamp > st.back()) {
    if (failure) *failure = JointLookupFailure::OutsideSpan;
    if (why)
      *why = "outside the recorded span" +
             (st.empty() ? std::string(" (no samples)")
                         : " [" + std::to_string(st.front()) + ", " + std::to_string(st.back()) + "] ns");
    return std::nullopt;
  }
  // First sample with stamp >= the query: the upper end of the bracket.
  const auto it = std::lower_bound(st.begin(), st.end(), stamp);
  const Eigen::Index hi = static_cast<Eigen::Index>(it - st.begin());
  const bool exact = *it == stamp;
  const Eigen::Index lo = exact ? hi : hi - 1;
  // Differences of stamps in unsigned arithmetic: defined for any int64 stamps
  // in increasing order (a signed difference may overflow for extreme stamps);
  // rounded to double only above 2^53 ns.
  const auto diff = [](int64_t later, int64_t earlier) {
    return static_cast<double>(static_cast<uint64_t>(later) - static_cast<uint64_t>(earlier));
  };
  const double a = exact ? 0.0 : diff(stamp, st[lo]) / diff(st[hi], st[lo]);
  Eigen::VectorXd q(static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const int c = columns[k];
    if (c < 0 || c >= log.positions.cols()) {
      if (failure) *failure = JointLookupFailure::NotFinite;
      if (why) *why = "joint column index " + std::to_string(c) + " out of range";
      return std::nullopt;
    }
    const double v0 = log.positions(lo, c), v1 = log.positions(hi, c);
    if (!std::isfinite(v0) || !std::isfinite(v1)) {
      if (failure) *failure = JointLookupFailure::NotFinite;
      if (why) *why = "NaN/inf in joint " + log.names[static_cast<std::size_t>(c)] + " near stamp " + std::to_string(stamp);
      return std::nullopt;
    }
    q[static_cast<Eigen::Index>(k)] = exact ? v0 : v0 + a * (v1 - v0);
  }
  return q;
}

std::string formatJointsCsv(const std::vector<std::string>& names, const std::vector<int64_t>& stamps,
                            const Eigen::MatrixXd& positions) {
  if (positions.rows() != static_cast<Eigen::Index>(stamps.size()) ||
      positions.cols() != static_cast<Eigen::Index>(names.size()))
    throw InputError("joints.csv", "",
                     "expected positions of " + std::to_string(stamps.size()) + " x " + std::to_string(names.size()) +
                         " (stamps x joints), got " + std::to_string(positions.rows()) + " x " +
                         std::to_string(positions.cols()));
  std::string s = "stamp_ns";
  for (const auto& n : names) s += "," + n;
  s += "\n";
  s.reserve(s.size() + stamps.size() * (20 + names.size() * 22));
  for (std::size_t r = 0; r < stamps.size(); ++r) {
    s += std::to_string(stamps[r]);
    for (Eigen::Index c = 0; c < positions.cols(); ++c) {
      s += ',';
      s += detail::formatDoubleCsv(positions(static_cast<Eigen::Index>(r), c));
    }
    s += '\n';
  }
  return s;
}

void writeJointsCsv(const std::string& path, const std::vector<std::string>& names,
                    const std::vector<int64_t>& stamps, const Eigen::MatrixXd& positions) {
  writeFileAtomically(path, formatJointsCsv(names, stamps, positions));
}

}  // namespace fgcal::apps
