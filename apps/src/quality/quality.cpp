// Quality's small parts (quality.hpp).
#include "fgcal/apps/quality.hpp"

#include <algorithm>

namespace fgcal::apps {

const char* toString(Severity s) {
  switch (s) {
    case Severity::Note: return "note";
    case Severity::Check: return "check";
    case Severity::Unusable: return "unusable";
  }
  return "note";
}

const char* toString(Verdict v) {
  switch (v) {
    case Verdict::Ok: return "ok";
    case Verdict::Check: return "check";
    case Verdict::Unusable: return "unusable";
  }
  return "ok";
}

void Quality::add(Finding f) {
  if (f.severity == Severity::Check && verdict == Verdict::Ok) verdict = Verdict::Check;
  if (f.severity == Severity::Unusable) verdict = Verdict::Unusable;
  findings.push_back(std::move(f));
}

bool Quality::has(const std::string& check) const {
  return std::any_of(findings.begin(), findings.end(), [&](const Finding& f) { return f.check == check; });
}

}  // namespace fgcal::apps
