// A factor graph: the list of factors. The structure (which factor touches
// which variable) is read by the linearizer once and cached there.
#pragma once

#include <memory>
#include <vector>

#include "fgcal/core/factor.hpp"

namespace fgcal {

class FactorGraph {
 public:
  void add(Factor::Ptr factor) {
    if (!factor) throw std::invalid_argument("cannot add a null factor to the graph");
    factors_.push_back(std::move(factor));
  }
  template <class F, class... Args>
  std::shared_ptr<F> emplace(Args&&... args) {
    auto f = std::make_shared<F>(std::forward<Args>(args)...);
    factors_.push_back(f);
    return f;
  }

  std::size_t size() const { return factors_.size(); }
  bool empty() const { return factors_.empty(); }
  const Factor& operator[](std::size_t i) const { return *factors_[i]; }
  const Factor::Ptr& at(std::size_t i) const { return factors_.at(i); }
  auto begin() const { return factors_.begin(); }
  auto end() const { return factors_.end(); }
  void reserve(std::size_t n) { factors_.reserve(n); }

  /// Sum of 0.5 rho(|W r|^2) over all factors.
  double cost(const Values& values) const {
    double c = 0.0;
    for (const auto& f : factors_) c += f->cost(values);
    return c;
  }

 private:
  std::vector<Factor::Ptr> factors_;
};

}  // namespace fgcal
