// Numbers as the quality findings write them in their messages.
#pragma once

#include <iomanip>
#include <sstream>
#include <string>

namespace fgcal::apps::quality {

/// `precision` significant digits: "0.513", "1.2e+03".
inline std::string num(double v, int precision = 3) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

/// `precision` digits after the point: "38.10".
inline std::string fixed(double v, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

}  // namespace fgcal::apps::quality
