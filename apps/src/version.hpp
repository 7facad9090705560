// The text of `fgcal --version`: "fgcal 0.1.0 (git 5e14d11)", or without the
// parenthesis when not built from a git clone. Kept in its own small
// translation unit because the generated header changes with every commit.
#pragma once

#include <string>

namespace fgcal::apps {

std::string versionText();

}  // namespace fgcal::apps
