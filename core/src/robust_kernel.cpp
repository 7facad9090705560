#include "fgcal/core/robust_kernel.hpp"

#include <cmath>
#include <stdexcept>

namespace fgcal {

namespace {

void checkThreshold(double k, const char* name) {
  if (!std::isfinite(k) || !(k > 0.0))
    throw std::invalid_argument(std::string(name) + " kernel threshold must be finite and > 0, got " +
                                std::to_string(k));
}

class Huber final : public RobustKernel {
 public:
  explicit Huber(double k) : k_(k), k2_(k * k) {}
  double rho(double s) const override { return s <= k2_ ? s : 2.0 * k_ * std::sqrt(s) - k2_; }
  double weight(double s) const override { return s <= k2_ ? 1.0 : k_ / std::sqrt(s); }
  std::string name() const override { return "huber(" + std::to_string(k_) + ")"; }

 private:
  double k_, k2_;
};

class Cauchy final : public RobustKernel {
 public:
  explicit Cauchy(double k) : k_(k), k2_(k * k) {}
  double rho(double s) const override { return k2_ * std::log1p(s / k2_); }
  double weight(double s) const override { return 1.0 / (1.0 + s / k2_); }
  std::string name() const override { return "cauchy(" + std::to_string(k_) + ")"; }

 private:
  double k_, k2_;
};

class Tukey final : public RobustKernel {
 public:
  explicit Tukey(double k) : k_(k), k2_(k * k) {}
  double rho(double s) const override {
    if (s >= k2_) return k2_ / 3.0;
    const double u = 1.0 - s / k2_;
    return k2_ / 3.0 * (1.0 - u * u * u);
  }
  double weight(double s) const override {
    if (s >= k2_) return 0.0;
    const double u = 1.0 - s / k2_;
    return u * u;
  }
  std::string name() const override { return "tukey(" + std::to_string(k_) + ")"; }

 private:
  double k_, k2_;
};

}  // namespace

RobustKernel::Ptr huber(double k) {
  checkThreshold(k, "Huber");
  return std::make_shared<Huber>(k);
}
RobustKernel::Ptr cauchy(double k) {
  checkThreshold(k, "Cauchy");
  return std::make_shared<Cauchy>(k);
}
RobustKernel::Ptr tukey(double k) {
  checkThreshold(k, "Tukey");
  return std::make_shared<Tukey>(k);
}

}  // namespace fgcal
