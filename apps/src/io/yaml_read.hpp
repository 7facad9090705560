// Private: typed, validated reads from yaml-cpp nodes. Every failure is an
// InputError naming the file, the field path ("cameras[1].intrinsics"), what
// was expected, what was found and the line. yaml-cpp is a private dependency:
// this header is only included by our .cpp files.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "fgcal/apps/errors.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps::detail {

/// A node and where it sits: the file and the field path.
struct YNode {
  YAML::Node node;
  std::string file;
  std::string path;  ///< "" for the document root

  /// Required key of a mapping; InputError "missing; expected <expected>".
  YNode at(const std::string& key, const std::string& expected) const;
  /// Optional key: a node with IsDefined() false when absent (or null).
  YNode maybe(const std::string& key) const;
  bool has(const std::string& key) const;
  YNode operator[](std::size_t i) const;
  std::string childPath(const std::string& key) const;

  [[noreturn]] void fail(const std::string& detail) const;
  /// " (line N)" when the node has a position, else "".
  std::string lineSuffix() const;
  /// "'abc'", "a list of 3 items", "a mapping", "an empty value".
  std::string found() const;

  void requireMap(const std::string& expected) const;
  void requireList(const std::string& expected) const;
  std::size_t listSize(const std::string& expected) const;

  double number() const;  ///< finite
  double positive() const;
  double nonNegative() const;
  int integer(int min_value) const;
  bool boolean() const;
  std::string string() const;  ///< non-empty scalar
  std::vector<double> numbers() const;  ///< list of finite numbers
  /// List of 1-sigmas: numbers >= 0, .inf allowed (a direction the data does
  /// not observe).
  std::vector<double> sigmas() const;
  /// Nested lists, row-major; finite entries unless allow_nonfinite (YAML
  /// .nan / .inf, e.g. the covariance of an unobservable direction).
  Eigen::MatrixXd matrix(int rows, int cols, bool allow_nonfinite = false) const;
  /// A number, NaN and inf included.
  double anyNumber() const;
  /// A rigid transform: 4x4 nested lists, rotation checked (tolerance 1e-6)
  /// and re-orthonormalized, last row [0 0 0 1].
  SE3 transform() const;

  /// Adds a warning per key not in `known`.
  void warnUnknownKeys(const std::set<std::string>& known, std::vector<std::string>& warnings) const;
};

/// Parses YAML text; syntax errors become InputError with line and column.
YNode parseYaml(const std::string& text, const std::string& file);

/// Parses a whole scalar as a number (YAML forms .inf, .nan included); false
/// when it is not one.
bool parseNumber(const std::string& s, double* out);

}  // namespace fgcal::apps::detail
