// The spellings of --method and --estimate (calibrate_options.hpp).
#include "fgcal/apps/calibrate_options.hpp"

#include <sstream>

#include "fgcal/apps/errors.hpp"

namespace fgcal::apps {

std::string toString(Method m) { return m == Method::Corners ? "corners" : "pnp"; }

Method methodFromString(const std::string& name) {
  if (name == "pnp") return Method::Pnp;
  if (name == "corners") return Method::Corners;
  throw InputError("", "--method",
                   "expected pnp (a PnP pose per image, the paper's method) or corners (a factor "
                   "per detected corner), got '" +
                       name + "'");
}

const std::vector<std::string>& estimateNames() {
  static const std::vector<std::string> n{"time-offset", "joint-offsets", "intrinsics", "backlash",
                                          "rolling-shutter"};
  return n;
}

namespace {

/// The member of EstimateSet that estimateNames()[i] sets.
bool EstimateSet::*const kMembers[] = {&EstimateSet::time_offset, &EstimateSet::joint_offsets,
                                       &EstimateSet::intrinsics, &EstimateSet::backlash,
                                       &EstimateSet::rolling_shutter};

}  // namespace

EstimateSet parseEstimateSet(const std::string& list) {
  const std::vector<std::string>& valid = estimateNames();
  EstimateSet s;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) {
    std::size_t i = 0;
    while (i < valid.size() && valid[i] != item) ++i;
    if (i == valid.size()) {
      std::string names;
      for (const std::string& n : valid) names += (names.empty() ? "" : ", ") + n;
      throw InputError("", "--estimate",
                       "expected a comma-separated list of " + names + ", got '" + item + "' in '" + list + "'");
    }
    s.*kMembers[i] = true;
  }
  return s;
}

std::vector<std::string> names(const EstimateSet& set) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < estimateNames().size(); ++i)
    if (set.*kMembers[i]) out.push_back(estimateNames()[i]);
  return out;
}

}  // namespace fgcal::apps
