// The Schur complement without H (streamed_schur.hpp): a pass that reduces
// each eliminated variable's block as soon as its factors are evaluated, and
// a pass that evaluates them again for its step.
#include "fgcal/core/internal/streamed_schur.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Core>

#include "block_cholesky.hpp"
#include "dense_cholesky.hpp"
#include "elimination_set.hpp"
#include "fgcal/core/internal/system_pattern.hpp"
#include "fgcal/core/optimizer.hpp"
#include "normal_equation_blocks.hpp"
#include "parallel.hpp"

namespace fgcal {

namespace {

// Up to 9x9: the elimination set holds variables of at most 9 degrees of freedom.
using SmallMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 9, 9>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 9, 1>;

}  // namespace

// One thread's buffers: a factor's blocks, an eliminated variable's block
// and couplings, and its share of the reduced system.
struct StreamedSchur::Scratch {
  std::vector<const Variable*> vars;
  std::vector<double> r, J, g, H;
  std::vector<double*> jp, gp, hp;
  SmallMat A;
  SmallVec ge;
  std::vector<double> B;                  // A's couplings, column-major, de rows
  std::vector<std::uint32_t> touched;     // reduced value indices the block's factors touch
  std::vector<Index> touched_col;         // their first column in B
  std::vector<double> S;                  // this thread's part of S's values
  VecX g_r, rhs, diag;
  double max_gradient = 0.0, xDx = 0.0, gx = 0.0;
  SolverStatus status;

  Scratch(int max_keys, int max_dof, int max_dim, Index reduced, std::size_t s_values) {
    const auto k = static_cast<std::size_t>(std::max(max_keys, 1)), dof = static_cast<std::size_t>(max_dof);
    vars.resize(k);
    r.resize(static_cast<std::size_t>(std::max(max_dim, 1)));
    J.resize(static_cast<std::size_t>(max_dim) * dof * k);
    g.resize(dof * k);
    H.resize(k * (k + 1) / 2 * dof * dof);
    jp.resize(k);
    gp.resize(k);
    hp.resize(k * (k + 1) / 2);
    B.resize(9 * static_cast<std::size_t>(reduced));
    S.assign(s_values, 0.0);
    g_r.setZero(reduced);
    rhs.setZero(reduced);
    diag.setZero(reduced);
  }
};

StreamedSchur::StreamedSchur(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
                             int threads)
    : graph_(graph), threads_(threads), num_values_(values.size()) {
  if (threads < 1) throw std::invalid_argument("StreamedSchur: threads must be >= 1, got " + std::to_string(threads));
  if (values.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("StreamedSchur: more than 2^32 - 1 variables");
  const std::size_t nv = values.size();
  var_dof_.resize(nv);
  for (std::size_t vi = 0; vi < nv; ++vi) var_dof_[vi] = values.variableAt(vi).dim();
  std::vector<char> touched(nv, 0), is_fixed(nv, 0);
  for (Key k : fixed)
    if (const std::size_t vi = values.find(k); vi != Values::npos) is_fixed[vi] = 1;
  indexFactorSlots(values, touched);

  std::vector<char> is_free(nv, 0);
  for (std::size_t vi = 0; vi < nv; ++vi) is_free[vi] = touched[vi] && !is_fixed[vi];
  const std::vector<char> in_set = detail::eliminationSet(
      slot_begin_, [&](std::size_t s) { return static_cast<std::size_t>(slot_value_[s]); }, is_free, var_dof_);
  const std::vector<std::uint32_t> elim_index = orderColumns(in_set, is_free);
  groupFactors(in_set, is_free, elim_index);
  layOutReducedSystem();
  keys_of_free_.reserve(elim_value_.size() + reduced_value_.size());
  for (std::uint32_t vi : elim_value_) keys_of_free_.push_back(values.keys()[vi]);
  for (std::uint32_t vi : reduced_value_) keys_of_free_.push_back(values.keys()[vi]);
}

// Each factor's keys as value indices (slots), its fast path, and the
// largest factor's sizes for the scratch; marks the values some factor touches.
void StreamedSchur::indexFactorSlots(const Values& values, std::vector<char>& touched) {
  const std::size_t nf = graph_.size();
  slot_begin_.resize(nf + 1);
  slot_value_.reserve(nf * 2);
  fast_path_.resize(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const Factor& factor = graph_[f];
    slot_begin_[f] = slot_value_.size();
    for (Key k : factor.keys()) {
      const std::size_t vi = values.find(k);
      if (vi == Values::npos) throwKeyWithoutValue(f, factor, k);
      for (std::size_t s = slot_begin_[f]; s < slot_value_.size(); ++s)
        if (slot_value_[s] == vi) throwKeyNamedTwice(f, k);
      touched[vi] = 1;
      slot_value_.push_back(static_cast<std::uint32_t>(vi));
      max_dof_ = std::max(max_dof_, var_dof_[vi]);
    }
    max_keys_ = std::max(max_keys_, static_cast<int>(slot_value_.size() - slot_begin_[f]));
    max_dim_ = std::max(max_dim_, factor.dim());
    fast_path_[f] = internal::normalEquationsFor(typeid(factor));
  }
  slot_begin_[nf] = slot_value_.size();
}

// Columns: the eliminated variables in value order, then the reduced ones.
// Returns each eliminated value's index among the eliminated.
std::vector<std::uint32_t> StreamedSchur::orderColumns(const std::vector<char>& in_set,
                                                       const std::vector<char>& is_free) {
  const std::size_t nv = in_set.size();
  var_col0_.assign(nv, -1);
  std::vector<std::uint32_t> elim_index(nv, 0);
  for (std::size_t vi = 0; vi < nv; ++vi)
    if (in_set[vi]) {
      elim_index[vi] = static_cast<std::uint32_t>(elim_value_.size());
      elim_value_.push_back(static_cast<std::uint32_t>(vi));
      var_col0_[vi] = num_cols_;
      num_cols_ += var_dof_[vi];
    }
  reduced_col0_ = num_cols_;
  for (std::size_t vi = 0; vi < nv; ++vi)
    if (is_free[vi] && !in_set[vi]) {
      reduced_value_.push_back(static_cast<std::uint32_t>(vi));
      var_col0_[vi] = num_cols_;
      num_cols_ += var_dof_[vi];
    }
  const Index n = reducedColumns();
  if (n > OptimizerOptions::kStreamedMaxReducedColumns)
    throw std::invalid_argument("StreamedSchur: the reduced system has " + std::to_string(n) +
                                " columns (variables not in the elimination set), more than the " +
                                std::to_string(OptimizerOptions::kStreamedMaxReducedColumns) +
                                " it factors densely");
  return elim_index;
}

// Each eliminated variable's factors (a counting sort; a factor touches at
// most one: the set is independent), and the factors on reduced ones only.
void StreamedSchur::groupFactors(const std::vector<char>& in_set, const std::vector<char>& is_free,
                                 const std::vector<std::uint32_t>& elim_index) {
  const std::size_t nf = graph_.size();
  elim_factor_begin_.assign(elim_value_.size() + 1, 0);
  auto eliminatedOf = [&](std::size_t f) -> std::ptrdiff_t {
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
      if (in_set[slot_value_[s]]) return elim_index[slot_value_[s]];
    return -1;
  };
  for (std::size_t f = 0; f < nf; ++f) {
    const std::ptrdiff_t e = eliminatedOf(f);
    if (e >= 0) {
      ++elim_factor_begin_[static_cast<std::size_t>(e) + 1];
      continue;
    }
    bool any_free = false;
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s) any_free = any_free || is_free[slot_value_[s]];
    if (any_free) reduced_factors_.push_back(static_cast<std::uint32_t>(f));
  }
  for (std::size_t e = 0; e < elim_value_.size(); ++e) elim_factor_begin_[e + 1] += elim_factor_begin_[e];
  elim_factors_.resize(elim_factor_begin_.back());
  std::vector<std::size_t> fill(elim_factor_begin_.begin(), elim_factor_begin_.end() - 1);
  for (std::size_t f = 0; f < nf; ++f)
    if (const std::ptrdiff_t e = eliminatedOf(f); e >= 0)
      elim_factors_[fill[static_cast<std::size_t>(e)]++] = static_cast<std::uint32_t>(f);
}

// S: the reduced system's whole upper triangle, column by column.
void StreamedSchur::layOutReducedSystem() {
  const Index n = reducedColumns();
  S_.rows = S_.cols = n;
  S_.colptr.resize(static_cast<std::size_t>(n) + 1);
  S_.rowind.clear();
  for (Index c = 0; c < n; ++c) {
    S_.colptr[static_cast<std::size_t>(c)] = static_cast<Index>(S_.rowind.size());
    for (Index r = 0; r <= c; ++r) S_.rowind.push_back(r);
  }
  S_.colptr[static_cast<std::size_t>(n)] = static_cast<Index>(S_.rowind.size());
  S_.values.assign(S_.rowind.size(), 0.0);
  dense_ = std::make_unique<detail::DenseCholesky>();
}

StreamedSchur::~StreamedSchur() = default;

double StreamedSchur::factorBlocks(std::size_t f, const Values& values, Scratch& s) const {
  const Factor& factor = graph_[f];
  const std::size_t s0 = slot_begin_[f], n = slot_begin_[f + 1] - s0;
  const int d = factor.dim();
  for (std::size_t i = 0; i < n; ++i) s.vars[i] = &values.variableAt(slot_value_[s0 + i]);
  {
    double* at = s.g.data();
    for (std::size_t i = 0; i < n; ++i) {
      s.gp[i] = at;
      at += var_dof_[slot_value_[s0 + i]];
    }
    at = s.H.data();
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i; j < n; ++j, ++k) {
        s.hp[k] = at;
        at += static_cast<std::ptrdiff_t>(var_dof_[slot_value_[s0 + i]]) * var_dof_[slot_value_[s0 + j]];
      }
  }
  double* r = s.r.data();
  if (const internal::NormalEquations* path = fast_path_[f]) {
    path->whitened(factor, s.vars.data(), r, s.gp.data(), s.hp.data());
  } else {
    double* J = s.J.data();
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t vi = slot_value_[s0 + i];
      s.jp[i] = var_col0_[vi] >= 0 ? J : nullptr;
      if (s.jp[i]) J += static_cast<std::ptrdiff_t>(d) * var_dof_[vi];
    }
    factor.evaluate(s.vars.data(), r, s.jp.data());
    const NoiseModel& noise = factor.noiseModel();
    noise.whitenResidual(r);
    const Eigen::Map<const VecX> rv(r, d);
    for (std::size_t i = 0; i < n; ++i)
      if (s.jp[i]) noise.whitenJacobian(s.jp[i], var_dof_[slot_value_[s0 + i]], d);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const int di = var_dof_[slot_value_[s0 + i]];
      if (s.jp[i])
        Eigen::Map<VecX>(s.gp[i], di).noalias() = Eigen::Map<const MatX>(s.jp[i], d, di).transpose() * rv;
      for (std::size_t j = i; j < n; ++j, ++k) {
        const int dj = var_dof_[slot_value_[s0 + j]];
        if (s.jp[i] && s.jp[j])
          Eigen::Map<MatX>(s.hp[k], di, dj).noalias() =
              Eigen::Map<const MatX>(s.jp[i], d, di).transpose() * Eigen::Map<const MatX>(s.jp[j], d, dj);
      }
    }
  }
  const double sq = detail::squaredNorm(r, d);
  const double cost = factor.costOfWhitened(sq);
  if (const RobustKernel* robust = factor.robustKernel()) {  // IRLS: H and g scaled by the weight
    const double w = robust->weight(sq);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t vi = slot_value_[s0 + i];
      if (var_col0_[vi] >= 0)
        for (int c = 0; c < var_dof_[vi]; ++c) s.gp[i][c] *= w;
      for (std::size_t j = i; j < n; ++j, ++k) {
        const std::uint32_t vj = slot_value_[s0 + j];
        if (var_col0_[vi] >= 0 && var_col0_[vj] >= 0)
          for (int c = 0; c < var_dof_[vi] * var_dof_[vj]; ++c) s.hp[k][c] *= w;
      }
    }
  }
  return cost;
}

namespace {

// S(a, b) += v for reduced columns a, b, into the upper triangle S keeps.
inline void addToUpper(const CscMatrix& S, double* sv, CscMatrix::Index a, CscMatrix::Index b, double v) {
  if (a > b) std::swap(a, b);
  sv[S.colptr[static_cast<std::size_t>(b)] + a] += v;
}

}  // namespace

// A factor's blocks between reduced variables into this thread's S, g_r and diagonal.
void StreamedSchur::addReducedFactor(std::size_t f, const Values& values, Scratch& s) const {
  factorBlocks(f, values, s);
  const std::size_t s0 = slot_begin_[f], n = slot_begin_[f + 1] - s0;
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t vi = slot_value_[s0 + i];
    const Index ci = var_col0_[vi] - reduced_col0_;
    const int di = var_dof_[vi];
    if (ci >= 0)
      for (int c = 0; c < di; ++c) s.g_r[ci + c] += s.gp[i][c];
    for (std::size_t j = i; j < n; ++j, ++k) {
      const std::uint32_t vj = slot_value_[s0 + j];
      const Index cj = var_col0_[vj] - reduced_col0_;
      if (ci < 0 || cj < 0 || var_col0_[vi] < 0 || var_col0_[vj] < 0) continue;
      const int dj = var_dof_[vj];
      const double* blk = s.hp[k];  // di x dj, column-major
      for (int c = 0; c < dj; ++c)
        for (int r = 0; r < di; ++r) {
          if (i == j && r > c) continue;  // a diagonal block's upper triangle
          addToUpper(S_, s.S.data(), ci + r, cj + c, blk[r + di * c]);
          if (i == j && r == c) s.diag[ci + r] += blk[r + di * c];
        }
    }
  }
}

void StreamedSchur::gatherBlock(std::size_t e, const Values& values, Scratch& s, bool reduced) const {
  const std::uint32_t ve = elim_value_[e];
  const int de = var_dof_[ve];
  s.A.setZero(de, de);
  s.ge.setZero(de);
  s.touched.clear();
  s.touched_col.clear();
  Index nb = 0;  // B's columns so far
  // The column of reduced variable vi in B (added, zeroed, when new).
  auto columnInB = [&](std::uint32_t vi) {
    for (std::size_t t = 0; t < s.touched.size(); ++t)
      if (s.touched[t] == vi) return s.touched_col[t];
    s.touched.push_back(vi);
    s.touched_col.push_back(nb);
    std::fill_n(s.B.begin() + nb * de, var_dof_[vi] * de, 0.0);
    nb += var_dof_[vi];
    return s.touched_col.back();
  };
  for (std::size_t q = elim_factor_begin_[e]; q < elim_factor_begin_[e + 1]; ++q) {
    const std::size_t f = elim_factors_[q];
    factorBlocks(f, values, s);
    const std::size_t s0 = slot_begin_[f], n = slot_begin_[f + 1] - s0;
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t vi = slot_value_[s0 + i];
      const int di = var_dof_[vi];
      const bool free_i = var_col0_[vi] >= 0, elim_i = vi == ve;
      if (elim_i) {
        s.ge += Eigen::Map<const VecX>(s.gp[i], di);
      } else if (free_i && reduced) {
        const Index ci = var_col0_[vi] - reduced_col0_;
        for (int c = 0; c < di; ++c) s.g_r[ci + c] += s.gp[i][c];
      }
      for (std::size_t j = i; j < n; ++j, ++k) {
        const std::uint32_t vj = slot_value_[s0 + j];
        const int dj = var_dof_[vj];
        const bool free_j = var_col0_[vj] >= 0, elim_j = vj == ve;
        if (!free_i || !free_j) continue;
        const double* blk = s.hp[k];  // di x dj, column-major
        if (elim_i && elim_j) {  // i == j: its upper triangle
          for (int c = 0; c < de; ++c)
            for (int r = 0; r <= c; ++r) s.A(r, c) += blk[r + di * c];
        } else if (elim_i) {
          double* Bc = s.B.data() + columnInB(vj) * de;
          for (int c = 0; c < dj; ++c)
            for (int r = 0; r < de; ++r) Bc[r + de * c] += blk[r + di * c];
        } else if (elim_j) {
          double* Bc = s.B.data() + columnInB(vi) * de;
          for (int c = 0; c < di; ++c)
            for (int r = 0; r < de; ++r) Bc[r + de * c] += blk[c + di * r];
        } else if (reduced) {
          const Index ci = var_col0_[vi] - reduced_col0_, cj = var_col0_[vj] - reduced_col0_;
          for (int c = 0; c < dj; ++c)
            for (int r = 0; r < di; ++r) {
              if (i == j && r > c) continue;
              addToUpper(S_, s.S.data(), ci + r, cj + c, blk[r + di * c]);
              if (i == j && r == c) s.diag[ci + r] += blk[r + di * c];
            }
        }
      }
    }
  }
  s.A.triangularView<Eigen::StrictlyLower>() = s.A.transpose();
}

// Eliminated variable e's gathered block into the thread's S and rhs: with
// A + lambda D = L L^T, Y = L^-1 B and z = L^-1 g_e, S -= Y^T Y and rhs += Y^T z.
void StreamedSchur::eliminateBlock(std::size_t e, Scratch& s) const {
  const int de = static_cast<int>(s.A.rows());
  if (damping_.lambda > 0.0)
    for (int j = 0; j < de; ++j)
      s.A(j, j) += damping_.lambda * std::clamp(s.A(j, j), damping_.min_diagonal, damping_.max_diagonal);
  if (const int failed = detail::choleskyLowerInPlace<detail::ColumnScaling::kDivide>(s.A); failed >= 0) {
    s.status.code = SolverStatus::Code::NotPositiveDefinite;
    s.status.failed_column = var_col0_[elim_value_[e]] + failed;
    s.status.message = "an eliminated block is not positive definite";
    return;
  }
  // Y = L^-1 B, z = L^-1 g_e: S -= Y^T Y, rhs += Y^T z.
  const Index nb = s.touched.empty() ? 0 : s.touched_col.back() + var_dof_[s.touched.back()];
  Eigen::Map<MatX> Y(s.B.data(), de, nb);
  s.A.triangularView<Eigen::Lower>().solveInPlace(Y);
  SmallVec z = s.ge;
  s.A.triangularView<Eigen::Lower>().solveInPlace(z);
  for (std::size_t a = 0; a < s.touched.size(); ++a) {
    const Index ga = var_col0_[s.touched[a]] - reduced_col0_, la = s.touched_col[a];
    const int da = var_dof_[s.touched[a]];
    s.rhs.segment(ga, da).noalias() += Y.middleCols(la, da).transpose() * z;
    for (std::size_t b = 0; b < s.touched.size(); ++b) {
      const Index gb = var_col0_[s.touched[b]] - reduced_col0_, lb = s.touched_col[b];
      if (ga > gb) continue;  // the upper triangle: block (a, b) with a's columns first
      const int db = var_dof_[s.touched[b]];
      const MatX M = Y.middleCols(la, da).transpose() * Y.middleCols(lb, db);
      for (int c = 0; c < db; ++c)
        for (int r = 0; r < da; ++r)
          if (ga != gb || r <= c) s.S[static_cast<std::size_t>(S_.colptr[static_cast<std::size_t>(gb + c)] + ga + r)] -= M(r, c);
    }
  }
}

SolverStatus StreamedSchur::reduce(const Values& values, const Damping& damping) {
  if (values.size() != num_values_)
    throw std::invalid_argument("StreamedSchur: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values_));
  if (!(damping.lambda >= 0.0) || !std::isfinite(damping.lambda) || !(damping.min_diagonal >= 0.0) ||
      !(damping.min_diagonal <= damping.max_diagonal))
    throw std::invalid_argument("StreamedSchur: damping needs a finite lambda >= 0 and 0 <= min_diagonal <= "
                                "max_diagonal");
  damping_ = damping;
  const Index n = reducedColumns();
  const std::size_t ne = elim_value_.size();
  const int T = detail::threadsFor(threads_, ne, 1024);
  std::vector<Scratch> parts;
  parts.reserve(static_cast<std::size_t>(T));
  for (int t = 0; t < T; ++t) parts.emplace_back(max_keys_, max_dof_, max_dim_, n, S_.values.size());
  auto clamped = [&](double h) { return std::clamp(h, damping.min_diagonal, damping.max_diagonal); };
  detail::parallelRun(T, [&](int t) {
    Scratch& s = parts[static_cast<std::size_t>(t)];
    if (t == 0)
      for (std::uint32_t f : reduced_factors_) addReducedFactor(f, values, s);
    const auto [e0, e1] = detail::chunkRange(ne, T, t);
    for (std::size_t e = e0; e < e1; ++e) {
      gatherBlock(e, values, s, true);
      const int de = static_cast<int>(s.A.rows());
      if (de > 0) s.max_gradient = std::max(s.max_gradient, s.ge.cwiseAbs().maxCoeff());
      // After a failed block only the gradient is gathered: the optimizer
      // reads it (a stationary point ends the solve) whatever the factorization says.
      if (!s.status.ok()) continue;
      eliminateBlock(e, s);
    }
  });
  std::fill(S_.values.begin(), S_.values.end(), 0.0);
  g_r_.setZero(n);
  reduced_diag_.setZero(n);
  VecX elim_rhs = VecX::Zero(n);
  max_gradient_ = 0.0;
  for (const Scratch& s : parts) {
    for (std::size_t i = 0; i < S_.values.size(); ++i) S_.values[i] += s.S[i];
    g_r_ += s.g_r;
    reduced_diag_ += s.diag;
    elim_rhs += s.rhs;
    max_gradient_ = std::max(max_gradient_, s.max_gradient);
  }
  if (n > 0) max_gradient_ = std::max(max_gradient_, g_r_.cwiseAbs().maxCoeff());
  for (const Scratch& s : parts)
    if (!s.status.ok()) return s.status;
  rhs_ = elim_rhs - g_r_;
  if (damping.lambda > 0.0)
    for (Index j = 0; j < n; ++j)
      S_.values[static_cast<std::size_t>(S_.colptr[static_cast<std::size_t>(j) + 1] - 1)] +=
          damping.lambda * clamped(reduced_diag_[j]);
  if (n == 0) return {};
  SolverStatus st = dense_->factorize(S_);
  if (!st.ok() && st.failed_column >= 0) st.failed_column += reduced_col0_;
  return st;
}

SolverStatus StreamedSchur::solve(const Values& values, VecX& step, double& predicted, double& factor_seconds) {
  const Index n = reducedColumns();
  VecX hr(n);
  if (n > 0) {
    const SolverStatus st = dense_->solve(rhs_, hr);
    if (!st.ok()) return st;
  }
  step.resize(num_cols_);
  step.tail(n) = hr;
  const std::size_t ne = elim_value_.size();
  const int T = detail::threadsFor(threads_, ne, 1024);
  std::vector<Scratch> parts;
  parts.reserve(static_cast<std::size_t>(T));
  for (int t = 0; t < T; ++t) parts.emplace_back(max_keys_, max_dof_, max_dim_, n, 0);
  const Damping damping = damping_;
  auto clamped = [&](double h) { return std::clamp(h, damping.min_diagonal, damping.max_diagonal); };
  const auto t0 = std::chrono::steady_clock::now();
  detail::parallelRun(T, [&](int t) {
    Scratch& s = parts[static_cast<std::size_t>(t)];
    const auto [e0, e1] = detail::chunkRange(ne, T, t);
    for (std::size_t e = e0; e < e1; ++e) {
      gatherBlock(e, values, s, false);
      const int de = static_cast<int>(s.A.rows());
      SmallVec D(de);
      for (int j = 0; j < de; ++j) {
        D[j] = clamped(s.A(j, j));
        if (damping.lambda > 0.0) s.A(j, j) += damping.lambda * D[j];
      }
      // reduce() factored the same block
      if (const int failed = detail::choleskyLowerInPlace<detail::ColumnScaling::kDivide>(s.A); failed >= 0) {
        s.status.code = SolverStatus::Code::NotPositiveDefinite;
        s.status.failed_column = var_col0_[elim_value_[e]] + failed;
        s.status.message = "an eliminated block is not positive definite";
        return;
      }
      // h_e = A^-1 (-g_e - B h_r)
      SmallVec u = -s.ge;
      for (std::size_t a = 0; a < s.touched.size(); ++a) {
        const int da = var_dof_[s.touched[a]];
        u.noalias() -= Eigen::Map<const MatX>(s.B.data() + s.touched_col[a] * de, de, da) *
                       hr.segment(var_col0_[s.touched[a]] - reduced_col0_, da);
      }
      s.A.triangularView<Eigen::Lower>().solveInPlace(u);
      s.A.triangularView<Eigen::Lower>().adjoint().solveInPlace(u);
      step.segment(var_col0_[elim_value_[e]], de) = u;
      s.xDx += (D.array() * u.array().square()).sum();
      s.gx += s.ge.dot(u);
    }
  });
  factor_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double xDx = 0.0, gx = 0.0;
  for (const Scratch& s : parts) {
    if (!s.status.ok()) return s.status;
    xDx += s.xDx;
    gx += s.gx;
  }
  for (Index j = 0; j < n; ++j) xDx += clamped(reduced_diag_[j]) * hr[j] * hr[j];
  gx += g_r_.dot(hr);
  predicted = 0.5 * (damping.lambda * xDx - gx);
  return {};
}

double StreamedSchur::cost(const Values& values) const {
  if (values.size() != num_values_)
    throw std::invalid_argument("StreamedSchur: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values_));
  const std::size_t nf = graph_.size();
  const int T = detail::threadsFor(threads_, nf, 4096);
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  detail::parallelRun(T, [&](int t) {
    std::vector<const Variable*> vars(static_cast<std::size_t>(std::max(max_keys_, 1)));
    std::vector<double> r(static_cast<std::size_t>(std::max(max_dim_, 1)));
    const auto [f0, f1] = detail::chunkRange(nf, T, t);
    double sum = 0.0;
    for (std::size_t f = f0; f < f1; ++f) {
      const Factor& factor = graph_[f];
      for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
        vars[s - slot_begin_[f]] = &values.variableAt(slot_value_[s]);
      if (const internal::NormalEquations* path = fast_path_[f]) {
        path->whitened(factor, vars.data(), r.data(), nullptr, nullptr);
      } else {
        factor.evaluate(vars.data(), r.data(), nullptr);
        factor.noiseModel().whitenResidual(r.data());
      }
      sum += factor.costOfWhitened(detail::squaredNorm(r.data(), factor.dim()));
    }
    costs[static_cast<std::size_t>(t)] = sum;
  });
  double total = 0.0;
  for (double c : costs) total += c;
  return total;
}

void StreamedSchur::retract(Values& values, const VecX& step) const {
  const int T = detail::threadsFor(threads_, num_values_, 16384);
  detail::parallelRun(T, [&](int t) {
    const auto [v0, v1] = detail::chunkRange(num_values_, T, t);
    for (std::size_t vi = v0; vi < v1; ++vi)
      if (var_col0_[vi] >= 0) values.variableAt(vi).retract(step.data() + var_col0_[vi]);
  });
}

Key StreamedSchur::keyOfColumn(Index col) const {
  // The free variables' first columns ascend in keys_of_free_'s order.
  std::size_t lo = 0, hi = keys_of_free_.size();
  auto col0At = [&](std::size_t b) {
    return var_col0_[b < elim_value_.size() ? elim_value_[b] : reduced_value_[b - elim_value_.size()]];
  };
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    if (col0At(mid) <= col)
      lo = mid;
    else
      hi = mid;
  }
  return keys_of_free_.at(lo);
}

}  // namespace fgcal
