// Typed, validated reads from yaml-cpp nodes (see yaml_read.hpp).
#include "io/yaml_read.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "fgcal/apps/urdf_update.hpp"  // closestNames

namespace fgcal::apps::detail {

bool parseNumber(const std::string& raw, double* out) {
  std::string s = raw;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && (s[b] == ' ' || s[b] == '\t')) ++b;
  s = s.substr(b);
  if (s.empty()) return false;
  // YAML's own spellings of the special values.
  if (s == ".nan" || s == ".NaN" || s == ".NAN") {
    *out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  for (const char* inf : {".inf", ".Inf", ".INF"}) {
    const std::string i(inf);
    if (s == i || s == "+" + i) {
      *out = std::numeric_limits<double>::infinity();
      return true;
    }
    if (s == "-" + i) {
      *out = -std::numeric_limits<double>::infinity();
      return true;
    }
  }
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (*first == '+') ++first;
  if (first == last) return false;
  // from_chars would accept "nan"/"inf" spelled C's way; YAML would read those
  // as strings, and so do we.
  const char c0 = (*first == '-' && first + 1 < last) ? first[1] : *first;
  if (!((c0 >= '0' && c0 <= '9') || c0 == '.')) return false;
  double v = 0.0;
  const auto res = std::from_chars(first, last, v);
  if (res.ec != std::errc() || res.ptr != last) return false;
  *out = v;
  return true;
}

YNode parseYaml(const std::string& text, const std::string& file) {
  try {
    return YNode{YAML::Load(text), file, ""};
  } catch (const YAML::Exception& e) {
    std::string where;
    if (!e.mark.is_null())
      where = "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1);
    throw InputError(file, where, "YAML syntax error: " + e.msg + "; expected a valid YAML document");
  }
}

std::string YNode::childPath(const std::string& key) const { return path.empty() ? key : path + "." + key; }

std::string YNode::lineSuffix() const {
  if (!node.IsDefined()) return "";
  const YAML::Mark m = node.Mark();
  if (m.is_null() || m.line < 0) return "";
  return " (line " + std::to_string(m.line + 1) + ")";
}

std::string YNode::found() const {
  if (!node.IsDefined() || node.IsNull()) return "an empty value";
  if (node.IsScalar()) {
    std::string s = node.Scalar();
    if (s.size() > 40) s = s.substr(0, 37) + "...";
    return "'" + s + "'";
  }
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + " item" + (node.size() == 1 ? "" : "s");
  return "a mapping";
}

void YNode::fail(const std::string& detail) const { throw InputError(file, path, detail + lineSuffix()); }

YNode YNode::maybe(const std::string& key) const {
  // Absent and null ("key:" with nothing after it) both read as "not given".
  YNode child{YAML::Node(YAML::NodeType::Undefined), file, childPath(key)};
  if (node.IsMap()) {
    const YAML::Node& self = node;  // const access never inserts the key
    const YAML::Node c = self[key];
    if (c.IsDefined() && !c.IsNull()) child.node = c;
  }
  return child;
}

bool YNode::has(const std::string& key) const { return maybe(key).node.IsDefined(); }

YNode YNode::at(const std::string& key, const std::string& expected) const {
  YNode child = maybe(key);
  if (!child.node.IsDefined()) {
    const std::string parent = path.empty() ? "the top level" : "'" + path + "'";
    throw InputError(file, child.path, "missing (or empty); expected " + expected + " under " + parent + lineSuffix());
  }
  return child;
}

YNode YNode::operator[](std::size_t i) const {
  const YAML::Node& self = node;
  return YNode{self[i], file, path + "[" + std::to_string(i) + "]"};
}

void YNode::requireMap(const std::string& expected) const {
  if (!node.IsMap()) fail("expected " + expected + ", got " + found());
}

void YNode::requireList(const std::string& expected) const {
  if (!node.IsSequence()) fail("expected " + expected + ", got " + found());
}

std::size_t YNode::listSize(const std::string& expected) const {
  requireList(expected);
  return node.size();
}

double YNode::number() const {
  double v = 0.0;
  if (!node.IsScalar() || !parseNumber(node.Scalar(), &v)) fail("expected a number, got " + found());
  if (!std::isfinite(v)) fail("expected a finite number, got " + found());
  return v;
}

double YNode::positive() const {
  const double v = number();
  if (!(v > 0.0)) fail("expected a number > 0, got " + found());
  return v;
}

double YNode::nonNegative() const {
  const double v = number();
  if (!(v >= 0.0)) fail("expected a number >= 0, got " + found());
  return v;
}

int YNode::integer(int min_value) const {
  double v = 0.0;
  const std::string expected = "an integer >= " + std::to_string(min_value);
  if (!node.IsScalar() || !parseNumber(node.Scalar(), &v) || !std::isfinite(v) || v != std::floor(v) ||
      v > std::numeric_limits<int>::max() || v < std::numeric_limits<int>::min())
    fail("expected " + expected + ", got " + found());
  if (v < min_value) fail("expected " + expected + ", got " + found());
  return static_cast<int>(v);
}

bool YNode::boolean() const {
  if (node.IsScalar()) {
    const std::string& s = node.Scalar();
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
  }
  fail("expected true or false, got " + found());
}

std::string YNode::string() const {
  if (!node.IsScalar() || node.Scalar().empty()) fail("expected a text value, got " + found());
  return node.Scalar();
}

std::vector<double> YNode::numbers() const {
  const std::size_t n = listSize("a list of numbers");
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back((*this)[i].number());
  return out;
}

std::vector<double> YNode::sigmas() const {
  const std::size_t n = listSize("a list of sigmas (numbers >= 0, .inf allowed)");
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const YNode e = (*this)[i];
    const double v = e.anyNumber();
    if (!(v >= 0.0)) e.fail("expected a sigma >= 0 (.inf allowed), got " + e.found());
    out.push_back(v);
  }
  return out;
}

double YNode::anyNumber() const {
  double v = 0.0;
  if (!node.IsScalar() || !parseNumber(node.Scalar(), &v)) fail("expected a number, got " + found());
  return v;
}

Eigen::MatrixXd YNode::matrix(int rows, int cols, bool allow_nonfinite) const {
  const std::string shape = std::to_string(rows) + "x" + std::to_string(cols);
  const std::string expected =
      "a " + shape + " matrix as " + std::to_string(rows) + " lists of " + std::to_string(cols) + " numbers (row-major)";
  const std::size_t n = listSize(expected);
  if (n == static_cast<std::size_t>(rows * cols) && n > 0 && node[0].IsScalar())
    fail("expected " + expected + ", got a flat list of " + std::to_string(n) + " numbers; write it as nested rows");
  if (n != static_cast<std::size_t>(rows)) {
    std::string got = "a list of " + std::to_string(n) + " rows";
    if (n > 0 && node[0].IsSequence()) got += " of " + std::to_string(node[0].size()) + " numbers";
    fail("expected " + expected + ", got " + got + " (a " + std::to_string(n) + "x" +
         (n > 0 && node[0].IsSequence() ? std::to_string(node[0].size()) : std::string("?")) + " matrix)");
  }
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    const YNode row = (*this)[static_cast<std::size_t>(r)];
    const std::size_t nc = row.listSize("a row of " + std::to_string(cols) + " numbers of a " + shape + " matrix");
    if (nc != static_cast<std::size_t>(cols))
      row.fail("expected a row of " + std::to_string(cols) + " numbers of a " + shape + " matrix, got " +
               std::to_string(nc) + " numbers");
    for (int c = 0; c < cols; ++c) {
      const YNode e = row[static_cast<std::size_t>(c)];
      m(r, c) = allow_nonfinite ? e.anyNumber() : e.number();
    }
  }
  return m;
}

SE3 YNode::transform() const {
  const Mat4 T = matrix(4, 4);
  try {
    return SE3::fromMatrix(T, 1e-6);
  } catch (const std::invalid_argument& e) {
    fail(std::string("expected a rigid transform (rotation block orthonormal with det +1 within 1e-6, last row "
                     "[0, 0, 0, 1]), but ") + e.what());
  }
}

void YNode::warnUnknownKeys(const std::set<std::string>& known, std::vector<std::string>& warnings) const {
  if (!node.IsMap()) return;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("<non-text key>");
    if (known.count(key)) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    const YNode k{it->first, file, childPath(key)};
    const std::vector<std::string> closest = closestNames(key, {known.begin(), known.end()}, 1);
    warnings.push_back(file + ": " + k.path + ": unknown key ignored" + k.lineSuffix() + " (closest known key: " +
                       (closest.empty() ? std::string("none") : closest.front()) + "; known keys here: " + list + ")");
  }
}

}  // namespace fgcal::apps::detail
