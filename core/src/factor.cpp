#include "fgcal/core/factor.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace fgcal {

Factor::Factor(std::vector<Key> keys, NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : keys_(std::move(keys)), noise_(std::move(noise)), robust_(std::move(robust)) {
  if (!noise_) throw std::invalid_argument("a factor needs a noise model");
  dim_ = noise_->dim();
  if (keys_.empty()) throw std::invalid_argument("a factor needs at least one key");
}

VecX Factor::error(const Values& values, std::vector<MatX>* jacobians) const {
  std::vector<const Variable*> vars;
  vars.reserve(keys_.size());
  for (Key k : keys_) vars.push_back(&values.variable(k));
  VecX r(dim());
  if (!jacobians) {
    evaluate(vars.data(), r.data(), nullptr);
    return r;
  }
  jacobians->resize(keys_.size());
  std::vector<double*> ptrs(keys_.size());
  for (std::size_t i = 0; i < keys_.size(); ++i) {
    (*jacobians)[i].setZero(dim(), vars[i]->dim());
    ptrs[i] = (*jacobians)[i].data();
  }
  evaluate(vars.data(), r.data(), ptrs.data());
  return r;
}

double Factor::cost(const Values& values) const {
  return costOfWhitened(noise_->whiten(error(values)).squaredNorm());
}

std::string Factor::describe() const {
  std::ostringstream s;
  s << "factor on ";
  for (std::size_t i = 0; i < keys_.size(); ++i) s << (i ? ", " : "") << keyToString(keys_[i]);
  return s.str();
}

std::vector<JacobianMismatch> checkFactorJacobians(const Factor& factor, const Values& values, double step,
                                                   double tolerance) {
  std::vector<MatX> analytic;
  factor.error(values, &analytic);
  const auto& keys = factor.keys();
  std::vector<const Variable*> vars;
  for (Key k : keys) vars.push_back(&values.variable(k));

  std::vector<JacobianMismatch> out;
  VecX rp(factor.dim()), rm(factor.dim());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const int n = vars[i]->dim();
    MatX numeric(factor.dim(), n);
    VecX d = VecX::Zero(n);
    std::vector<const Variable*> shifted = vars;
    for (int c = 0; c < n; ++c) {
      d[c] = step;
      auto plus = vars[i]->clone();
      plus->retract(d.data());
      d[c] = -step;
      auto minus = vars[i]->clone();
      minus->retract(d.data());
      d[c] = 0.0;
      shifted[i] = plus.get();
      factor.evaluate(shifted.data(), rp.data(), nullptr);
      shifted[i] = minus.get();
      factor.evaluate(shifted.data(), rm.data(), nullptr);
      numeric.col(c) = (rp - rm) / (2.0 * step);
    }
    const MatX diff = (analytic[i] - numeric).cwiseAbs();
    double worst = 0.0;
    for (Eigen::Index r = 0; r < diff.rows(); ++r)
      for (Eigen::Index c = 0; c < diff.cols(); ++c) {
        double ratio = diff(r, c) / (1.0 + std::abs(numeric(r, c)));
        if (!std::isfinite(ratio)) ratio = std::numeric_limits<double>::infinity();
        worst = std::max(worst, ratio);
      }
    if (worst > tolerance) {
      std::ostringstream msg;
      msg << factor.describe() << ": Jacobian block of " << keyToString(keys[i]) << " (position " << i
          << ") differs from central differences by up to " << diff.maxCoeff() << "\nanalytic:\n"
          << analytic[i] << "\nnumeric:\n"
          << numeric;
      out.push_back({i, keys[i], diff.maxCoeff(), numeric.cwiseAbs().maxCoeff(), msg.str()});
    }
  }
  return out;
}

}  // namespace fgcal
