#include "fgcal/core/factor.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include "fgcal/core/internal/normal_equations.hpp"

namespace fgcal {

namespace {

// Largest |a - b| over |b|'s scale: relative to 1 + max |b|, since blocks of
// H reach |W|^2 (1e4 and more) while rounding stays near 1e-16 of that.
double relativeDifference(const MatX& a, const MatX& b) {
  const double d = (a - b).cwiseAbs().maxCoeff();
  return std::isfinite(d) ? d / (1.0 + b.cwiseAbs().maxCoeff()) : std::numeric_limits<double>::infinity();
}

// What the solver's fast path for the factor (if it has one) writes, against
// the whitened residual, gradient and normal-equation blocks formed from
// evaluate()'s raw residual r and Jacobians J and the noise model:
// W r, J_i^T W^T W r and J_i^T W^T W J_j. Also that the residual-only call
// gives the same residual bits (the optimizer compares the two kinds of
// evaluation) and that a pair evaluation, where the path has one, agrees.
void checkFastPath(const Factor& factor, const std::vector<const Variable*>& vars, const VecX& r_raw,
                   const std::vector<MatX>& J_raw, double tolerance, std::vector<JacobianMismatch>& out) {
  const internal::NormalEquations* path = internal::normalEquationsFor(typeid(factor));
  if (!path) return;
  const std::vector<Key>& keys = factor.keys();
  const std::size_t n = keys.size();
  const MatX& W = factor.noiseModel().sqrtInformation();
  const VecX rw = W * r_raw;
  std::vector<MatX> Jw(n);
  for (std::size_t i = 0; i < n; ++i) Jw[i] = W * J_raw[i];

  struct Blocks {
    VecX r;
    std::vector<VecX> g;
    std::vector<MatX> H;  // pairs (i, j), i <= j
    std::vector<double*> gp, hp;
  };
  const auto blocks = [&] {
    Blocks b;
    b.r.setZero(factor.dim());
    for (std::size_t i = 0; i < n; ++i) b.g.push_back(VecX::Zero(vars[i]->dim()));
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i; j < n; ++j) b.H.push_back(MatX::Zero(vars[i]->dim(), vars[j]->dim()));
    for (auto& x : b.g) b.gp.push_back(x.data());
    for (auto& x : b.H) b.hp.push_back(x.data());
    return b;
  };
  const auto report = [&](std::size_t i, const std::string& what, const MatX& fast, const MatX& ref) {
    const double diff = relativeDifference(fast, ref);
    if (diff <= tolerance) return;
    std::ostringstream msg;
    msg << factor.describe() << ": the solver's fast path gives a " << what
        << " that differs from the one formed from evaluate() and the noise model by " << diff
        << " (relative)\nfast path:\n"
        << fast << "\nfrom evaluate():\n"
        << ref;
    out.push_back({i, keys[i], (fast - ref).cwiseAbs().maxCoeff(), ref.cwiseAbs().maxCoeff(), msg.str()});
  };
  const auto compare = [&](const Blocks& b, const std::string& how) {
    report(0, "whitened residual" + how, b.r, rw);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      report(i, "gradient block of " + keyToString(keys[i]) + how, b.g[i], Jw[i].transpose() * rw);
      for (std::size_t j = i; j < n; ++j, ++k)
        report(i, "block (" + keyToString(keys[i]) + ", " + keyToString(keys[j]) + ") of J^T J" + how, b.H[k],
               Jw[i].transpose() * Jw[j]);
    }
  };

  Blocks full = blocks();
  path->whitened(factor, vars.data(), full.r.data(), full.gp.data(), full.hp.data());
  compare(full, "");
  Blocks r_only = blocks();
  path->whitened(factor, vars.data(), r_only.r.data(), nullptr, nullptr);
  if (!(r_only.r.array() == full.r.array()).all())
    out.push_back({0, keys[0], (r_only.r - full.r).cwiseAbs().maxCoeff(), full.r.cwiseAbs().maxCoeff(),
                   factor.describe() +
                       ": the solver's fast path gives another residual when no Jacobian is asked for (the "
                       "optimizer compares costs of both kinds of evaluation, which must agree to the bit)"});
  if (!path->pairs()) return;
  Blocks a = blocks(), b = blocks();
  path->whitenedPair(factor, factor, vars.data(), vars.data(), a.r.data(), a.gp.data(), a.hp.data(), b.r.data(),
                     b.gp.data(), b.hp.data());
  compare(a, " (first of a pair)");
  compare(b, " (second of a pair)");
}

}  // namespace

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
  const VecX r_raw = factor.error(values, &analytic);
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
  checkFastPath(factor, vars, r_raw, analytic, tolerance, out);
  return out;
}

}  // namespace fgcal
