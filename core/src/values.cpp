#include "fgcal/core/values.hpp"

namespace fgcal {

Values::Values(const Values& other) : keys_(other.keys_), index_(other.index_) {
  variables_.reserve(other.variables_.size());
  for (const auto& v : other.variables_) variables_.push_back(v->clone());
}

Values& Values::operator=(const Values& other) {
  if (this != &other) {
    Values copy(other);
    *this = std::move(copy);
  }
  return *this;
}

std::size_t Values::indexOf(Key k) const {
  const std::size_t i = find(k);
  if (i == npos) throw std::out_of_range("no variable " + keyToString(k) + " in the values");
  return i;
}

void Values::insertVariable(Key k, std::unique_ptr<Variable> v) {
  if (index_.count(k)) throw std::invalid_argument("variable " + keyToString(k) + " is already in the values");
  index_.emplace(k, variables_.size());
  keys_.push_back(k);
  variables_.push_back(std::move(v));
}

}  // namespace fgcal
