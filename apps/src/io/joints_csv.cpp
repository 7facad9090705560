// joints.csv reader, column check, interpolation and writer (see joints_csv.hpp).
#include "fgcal/apps/joints_csv.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"
#include "text_format.hpp"

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

/// The header's joint names (unique, none empty, none called stamp_ns) into log.names.
void parseHeader(const std::vector<std::string_view>& fields, std::string_view line, const std::string& file,
                 const std::string& where, JointLog& log) {
  if (fields[0] != "stamp_ns")
    throw InputError(file, where,
                     "expected the header 'stamp_ns,<joint name>,...' with stamp_ns as first column, got " +
                         quoteField(line));
  if (fields.size() < 2)
    throw InputError(file, where, "expected at least one joint column after stamp_ns, got only stamp_ns");
  for (std::size_t i = 1; i < fields.size(); ++i) {
    const std::string name(fields[i]);
    if (name.empty())
      throw InputError(file, where, "expected a joint name in column " + std::to_string(i + 1) + ", got an empty one");
    const int prev = log.column(name);
    if (prev >= 0 || name == "stamp_ns")
      throw InputError(file, where,
                       "expected unique column names, got '" + name + "' twice (columns " +
                           std::to_string(prev >= 0 ? prev + 2 : 1) + " and " + std::to_string(i + 1) + ")");
    log.names.push_back(name);
  }
}

/// A row's stamp: an integer, strictly after the previous row's.
std::int64_t parseStamp(std::string_view f, const std::string& file, const std::string& where, const JointLog& log) {
  std::int64_t stamp = 0;
  const auto res = std::from_chars(f.data(), f.data() + f.size(), stamp);
  if (f.empty() || res.ec != std::errc() || res.ptr != f.data() + f.size())
    throw InputError(file, where + ", column stamp_ns",
                     "expected an integer time stamp in nanoseconds, got " + quoteField(f));
  if (!log.stamps_ns.empty() && stamp <= log.stamps_ns.back())
    throw InputError(file, where + ", column stamp_ns",
                     "expected stamps strictly increasing, got " + std::to_string(stamp) +
                         (stamp == log.stamps_ns.back() ? " again" : " after " + std::to_string(log.stamps_ns.back())));
  return stamp;
}

/// The values read so far (row-major samples x joints) and the count of
/// those that are not finite numbers, for the warning.
struct JointValues {
  std::vector<double> values;
  std::size_t empty = 0, nonfinite = 0;
  std::map<std::string, int> nonfinite_by_joint;
};

/// One data row: its stamp into log.stamps_ns, its positions into `v`
/// (NaN for an empty, NaN or infinite field).
void parseRow(const std::vector<std::string_view>& fields, const std::string& file, const std::string& where,
              JointLog& log, JointValues& v) {
  const std::size_t ncols = log.names.size() + 1;
  if (fields.size() != ncols)
    throw InputError(file, where,
                     "expected " + std::to_string(ncols) + " comma-separated fields (stamp_ns and " +
                         std::to_string(log.names.size()) + " joints, as in the header), got " +
                         std::to_string(fields.size()));
  log.stamps_ns.push_back(parseStamp(fields[0], file, where, log));
  for (std::size_t j = 1; j < ncols; ++j) {
    double x = 0.0;
    if (fields[j].empty()) {
      x = std::numeric_limits<double>::quiet_NaN();
      ++v.empty;
    } else if (!parseValue(fields[j], &x)) {
      throw InputError(file, where + ", column " + log.names[j - 1],
                       "expected a number (joint position), got " + quoteField(fields[j]));
    }
    if (!std::isfinite(x)) {
      x = std::numeric_limits<double>::quiet_NaN();
      ++v.nonfinite;
      ++v.nonfinite_by_joint[log.names[j - 1]];
    }
    v.values.push_back(x);
  }
}

/// The positions matrix from the values, and the warning on those not finite.
void finishLog(const std::string& file, const JointValues& v, JointLog& log) {
  const Eigen::Index rows = static_cast<Eigen::Index>(log.stamps_ns.size());
  const Eigen::Index cols = static_cast<Eigen::Index>(log.names.size());
  log.positions = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      v.values.data(), rows, cols);
  if (v.nonfinite == 0) return;
  std::string per;
  for (const auto& [name, n] : v.nonfinite_by_joint) per += (per.empty() ? "" : ", ") + name + " " + std::to_string(n);
  log.warnings.push_back(file + ": " + std::to_string(v.nonfinite) + " NaN/inf/empty value" +
                         (v.nonfinite == 1 ? "" : "s") + " (" + per +
                         (v.empty ? "; " + std::to_string(v.empty) + " of them empty fields" : "") +
                         "); images needing them are skipped");
}

}  // namespace

JointLog parseJointsCsv(const std::string& text, const std::string& file) {
  JointLog log;
  JointValues values;
  std::vector<std::string_view> fields;
  std::size_t pos = 0;
  int line_no = 0;
  bool have_header = false;
  const std::string_view all(text);
  while (pos < all.size()) {
    std::size_t eol = all.find('\n', pos);
    if (eol == std::string_view::npos) eol = all.size();
    std::string_view line = all.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    if (line_no == 1 && line.size() >= 3 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 BOM
    if (trim(line).empty()) continue;
    const std::string where = "line " + std::to_string(line_no);
    splitFields(line, fields);
    if (have_header) {
      parseRow(fields, file, where, log, values);
    } else {
      parseHeader(fields, line, file, where, log);
      have_header = true;
    }
  }
  if (!have_header)
    throw InputError(file, "line 1", "expected the header 'stamp_ns,<joint name>,...', got an empty file");
  if (log.stamps_ns.empty())
    throw InputError(file, "line " + std::to_string(line_no),
                     "expected at least one data row after the header, got none");
  finishLog(file, values, log);
  return log;
}

JointLog loadJointsCsv(const std::string& path) {
  return parseJointsCsv(readTextFile(path, "joints.csv (joint positions over time)"), path);
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
    throw InputError(file, "line 1 (header)",
                     "expected a column for every joint of the kinematic chain; missing " +
                         std::to_string(missing.size()) + " of " + std::to_string(names.size()) + ": " +
                         detail::joinNames(missing) + "; the file has: stamp_ns, " + detail::joinNames(log.names));
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
                                           std::string* why) {
  const auto& st = log.stamps_ns;
  if (st.empty() || stamp < st.front() || stamp > st.back()) {
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
      if (why) *why = "joint column index " + std::to_string(c) + " out of range";
      return std::nullopt;
    }
    const double v0 = log.positions(lo, c), v1 = log.positions(hi, c);
    if (!std::isfinite(v0) || !std::isfinite(v1)) {
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
