// Private: how fgcal writes numbers, matrices and strings into its YAML and CSV
// outputs. Numbers use the shortest decimal form that reads back to the same
// double, with a '.' kept in every float so YAML 1.1 readers (PyYAML) do not
// take "1e-05" for a string.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace fgcal::apps::detail {

/// Shortest round-trip form: "0.02", "1.0e-05", "3.0", ".nan", ".inf", "-.inf".
std::string formatDouble(double v);
/// Shortest round-trip form for CSV: "0.02", "1e-05", "nan", "inf".
std::string formatDoubleCsv(double v);
/// "[a, b, c]".
std::string formatList(const Eigen::Ref<const Eigen::VectorXd>& v);
std::string formatList(const std::vector<double>& v);
/// A matrix as a YAML block list of flow rows, each on its own line:
/// "\n<indent>- [a, b]\n<indent>- [c, d]" (starts with a newline, so it goes
/// right after "key:").
std::string formatMatrixBlock(const Eigen::Ref<const Eigen::MatrixXd>& m, int indent);
/// A mapping key or plain value: as is when YAML reads it back as the same
/// string, double-quoted otherwise.
std::string yamlScalar(const std::string& s);
/// Always double-quoted, with escapes.
std::string yamlQuoted(const std::string& s);
/// "a, b, c": names listed in messages.
std::string joinNames(const std::vector<std::string>& names);
/// Text made safe for XML/HTML character data and attribute values (the URDF
/// snippet, the report): & < > " ' escaped, control characters other than tab
/// and newline (not allowed in XML) replaced by a space.
std::string xmlEscape(std::string_view text);

}  // namespace fgcal::apps::detail
