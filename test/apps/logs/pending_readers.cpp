// Test-only, while the ROS 1 and MCAP readers live on other branches: openBag
// (bag.cpp) refers to them, so the sqlite tests link only if something
// defines them. These refuse the format; the CMakeLists.txt beside this file
// drops them as soon as ros1_bag.cpp and mcap_reader.cpp exist.
#include "fgcal/logs/log_error.hpp"
#include "readers.hpp"

namespace fgcal::logs::detail {

#ifndef FGCAL_HAVE_ROS1_READER
std::unique_ptr<BagReader> openRos1Bag(const std::string& path, const ReadLimits&) {
  throw LogError(path, "", "the ROS 1 bag reader is not part of this test build");
}
#endif
#ifndef FGCAL_HAVE_MCAP_READER
std::unique_ptr<BagReader> openMcapFile(const std::string& path, const ReadLimits&) {
  throw LogError(path, "", "the MCAP reader is not part of this test build");
}
#endif

}  // namespace fgcal::logs::detail
