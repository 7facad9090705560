// See version.hpp; fgcal_version.hpp is generated in the build tree.
#include "version.hpp"

#include "fgcal_version.hpp"

namespace fgcal::apps {

std::string versionText() {
  const std::string git = FGCAL_GIT_DESCRIBE;
  return std::string("fgcal ") + FGCAL_VERSION + (git.empty() ? "" : " (git " + git + ")");
}

}  // namespace fgcal::apps
