// Number and string formatting for fgcal's output files (see text_format.hpp).
#include "io/text_format.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace fgcal::apps::detail {

namespace {
std::string shortest(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}
}  // namespace

std::string formatDouble(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  std::string s = shortest(v);
  // YAML 1.1 floats need a '.' in the mantissa; integers would still read as
  // numbers but as ints, so make every value visibly a float.
  if (s.find('.') == std::string::npos) {
    const auto e = s.find('e');
    if (e == std::string::npos)
      s += ".0";
    else
      s.insert(e, ".0");
  }
  return s;
}

std::string formatDoubleCsv(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return shortest(v);
}

std::string formatList(const Eigen::Ref<const Eigen::VectorXd>& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (i) s += ", ";
    s += formatDouble(v[i]);
  }
  return s + "]";
}

std::string formatList(const std::vector<double>& v) {
  return formatList(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
}

std::string formatMatrixBlock(const Eigen::Ref<const Eigen::MatrixXd>& m, int indent) {
  std::string s;
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    s += "\n" + pad + "- [";
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      if (c) s += ", ";
      s += formatDouble(m(r, c));
    }
    s += "]";
  }
  return s;
}

std::string yamlQuoted(const std::string& s) {
  std::string out = "\"";
  for (const unsigned char ch : s) {
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (ch < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\x%02x", ch);
          out += buf;
        } else {
          out += static_cast<char>(ch);
        }
    }
  }
  return out + "\"";
}

std::string yamlScalar(const std::string& s) {
  // Plain only for identifiers that no YAML reader turns into a bool, null or
  // number: a letter first, then letters, digits, '_', '-', '.'.
  if (s.empty()) return "\"\"";
  const auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
  bool plain = alpha(s[0]);
  for (const char c : s)
    plain = plain && (alpha(c) || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.');
  if (plain) {
    std::string lower;
    for (const char c : s) lower += static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    for (const char* word : {"y", "n", "yes", "no", "true", "false", "on", "off", "null", "nan", "inf"})
      if (lower == word) plain = false;
  }
  return plain ? s : yamlQuoted(s);
}

std::string xmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        // Control characters other than tab and newline are not allowed in XML.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n')
          out += ' ';
        else
          out += c;
    }
  }
  return out;
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace fgcal::apps::detail
