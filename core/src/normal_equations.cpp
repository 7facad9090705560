// The registry of fast paths by factor type. A handful of types register,
// once each; LinearSystem asks once per dynamic type it meets while it
// builds a structure, so a lock and a short list are enough.
#include "fgcal/core/internal/normal_equations.hpp"

#include <mutex>
#include <stdexcept>
#include <string>
#include <typeindex>
#include <utility>
#include <vector>

namespace fgcal::internal {

namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::pair<std::type_index, const NormalEquations*>> paths;
};

// Constructed on first use: a factor built during another unit's static
// initialization still finds it.
Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

void registerNormalEquations(const std::type_info& type, const NormalEquations& path) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  for (const auto& [t, p] : r.paths)
    if (t == std::type_index(type)) {
      if (p != &path)
        throw std::logic_error(std::string("a second fast path registered for factor type ") + type.name());
      return;
    }
  r.paths.emplace_back(std::type_index(type), &path);
}

const NormalEquations* normalEquationsFor(const std::type_info& type) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  for (const auto& [t, p] : r.paths)
    if (t == std::type_index(type)) return p;
  return nullptr;
}

}  // namespace fgcal::internal
