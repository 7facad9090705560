#include "fgcal/core/values.hpp"

#include <atomic>

namespace fgcal {

const std::vector<Key>& Values::emptyKeys() {
  static const std::vector<Key> empty;
  return empty;
}

Values::Values(const Values& other) : index_(other.index_) {
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
  if (find(k) != npos) throw std::invalid_argument("variable " + keyToString(k) + " is already in the values");
  if (!index_)
    index_ = std::make_shared<Index>();
  else if (index_.use_count() > 1)
    index_ = std::make_shared<Index>(*index_);  // shared with a copy: this one gets its own
  else
    // The last other owner may have let go on another thread: its reads of
    // the index happen before the writes below (use_count() is a relaxed load).
    std::atomic_thread_fence(std::memory_order_acquire);
  index_->position.emplace(k, variables_.size());
  index_->keys.push_back(k);
  variables_.push_back(std::move(v));
}

}  // namespace fgcal
