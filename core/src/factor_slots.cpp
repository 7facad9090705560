// FactorSlots: one slot per (factor, key), each factor's rows, the variables
// some factor names; the first step of a SystemPattern.
#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "fgcal/core/internal/system_pattern.hpp"

namespace fgcal {
namespace {

// The position of a factor's key in Values. A factor mostly names, at each
// place, the variable that the previous factor with as many keys named there,
// or the one inserted after it (a camera seen again, the next board pose):
// those two are compared before the hash lookup, whose scattered nodes cost
// cache misses on a large graph.
class ValueLookup {
 public:
  explicit ValueLookup(const Values& values) : values_(values), value_keys_(values.keys()) {}
  std::size_t operator()(Key k, std::size_t n, std::size_t place) {
    if (n > kHinted) return values_.find(k);
    std::size_t& h = hint_[n - 1][place];
    if (h < value_keys_.size() && value_keys_[h] == k) return h;
    if (h + 1 < value_keys_.size() && value_keys_[h + 1] == k) return ++h;
    const std::size_t vi = values_.find(k);
    if (vi != Values::npos) h = vi;
    return vi;
  }

 private:
  static constexpr std::size_t kHinted = 4;
  const Values& values_;
  const std::vector<Key>& value_keys_;
  std::size_t hint_[kHinted][kHinted] = {};  // [number of keys - 1][place]
};

}  // namespace

void throwKeyWithoutValue(std::size_t f, const Factor& factor, Key k) {
  std::ostringstream err;
  err << "factor " << f << " (" << factor.describe() << ") names variable " << keyToString(k)
      << ", which has no initial value";
  throw std::invalid_argument(err.str());
}

void throwKeyNamedTwice(std::size_t f, Key k) {
  throw std::invalid_argument("factor " + std::to_string(f) + " names variable " + keyToString(k) + " twice");
}

FactorSlots::FactorSlots(const FactorGraph& graph, const Values& values, bool store_jacobian,
                         FactorVisitor& visitor) {
  if (values.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("LinearSystem: more than 2^32 - 1 variables");
  touched.assign(values.size(), 0);
  // Tangent sizes once per variable: the slots read them from here, not
  // through a virtual call per (factor, key).
  dofs.resize(values.size());
  for (std::size_t vi = 0; vi < values.size(); ++vi) dofs[vi] = values.variableAt(vi).dim();
  if (store_jacobian) factor_row.resize(graph.size() + 1);  // r's and J's rows only
  begin.resize(graph.size() + 1);
  slots.reserve(graph.size() * 2);
  ValueLookup lookup(values);
  Index row = 0;
  for (std::size_t f = 0; f < graph.size(); ++f) {
    const Factor& factor = graph[f];
    visitor.see(f, factor);
    if (store_jacobian) factor_row[f] = row;
    begin[f] = slots.size();
    const std::vector<Key>& keys = factor.keys();
    for (std::size_t place = 0; place < keys.size(); ++place) {
      const Key k = keys[place];
      const std::size_t vi = lookup(k, keys.size(), place);
      if (vi == Values::npos) throwKeyWithoutValue(f, factor, k);
      for (std::size_t s = begin[f]; s < slots.size(); ++s)
        if (slots[s].value_index == vi) throwKeyNamedTwice(f, k);
      touched[vi] = 1;
      slots.push_back({static_cast<std::uint32_t>(vi), dofs[vi], -1});
      max_dof = std::max(max_dof, dofs[vi]);
    }
    const int d = factor.dim();
    max_dim = std::max(max_dim, d);
    row += d;
  }
  if (slots.size() >= (std::size_t{1} << 31))  // HBlock holds a slot in 31 bits
    throw std::invalid_argument("LinearSystem: more than 2^31 - 1 (factor, variable) pairs");
  if (store_jacobian) factor_row[graph.size()] = row;
  begin[graph.size()] = slots.size();
  num_rows = row;
}

}  // namespace fgcal
