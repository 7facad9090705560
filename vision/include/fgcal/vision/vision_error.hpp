// The one exception type of fgcal::vision: bad input (unknown names, wrong
// coefficient counts, unreadable files) is reported by throwing VisionError
// whose message names the file or field and what was expected.
#pragma once

#include <stdexcept>
#include <string>

namespace fgcal::vision {

class VisionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fgcal::vision
