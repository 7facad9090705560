#include "schur_six_avx2.hpp"

#include <stdexcept>

#include "fgcal/core/internal/pivot_rule.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(_MSC_VER)
#define FGCAL_HAVE_AVX2_KERNEL 1
#include <immintrin.h>
#endif

namespace fgcal::detail {

#if defined(FGCAL_HAVE_AVX2_KERNEL)

bool cpuHasAvx2Fma() {
  // GCC's and Clang's checks include the operating system's support of the
  // AVX registers (XGETBV), not only the CPU's. Asked once (a thread-safe
  // static): the CPU model is initialized before static constructors run.
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
}

namespace {
constexpr int packed(int i, int k) { return i * (i + 1) / 2 + k; }

// The library's pivot rule, lane by lane: the decision is pivot_rule.hpp's,
// only the arithmetic before it is vectorised.
__attribute__((target("avx2,fma"))) bool pivotsAccepted(__m256d d, __m256d a) {
  double dl[4], al[4];
  _mm256_storeu_pd(dl, d);
  _mm256_storeu_pd(al, a);
  for (int k = 0; k < 4; ++k)
    if (!pivotAccepted(dl[k], al[k])) return false;
  return true;
}
}  // namespace

// A row of 6 as a 4-lane and a 2-lane packet; Y_p by rows, 6 doubles apart.
// Multiply-adds fused: the results differ from the baseline kernel's in the
// last bits.
__attribute__((target("avx2,fma"))) void eliminateSixAvx2(const SixElimination& at, const SchurLink* links,
                                                           std::size_t k, const double* Linv, const double* z,
                                                           const std::int64_t* pair_offset, double* Y) {
  for (std::size_t p = 0; p < k; ++p) {
    const std::int64_t hcol = at.reduced_col0[links[p].j];
    double Bt[6 * 6];  // row r of B_p at Bt + 6 r
    for (int c = 0; c < 6; ++c) {
      const double* col = at.hv + at.hp[hcol + c] + links[p].h_offset;
      for (int r = 0; r < 6; ++r) Bt[c + 6 * r] = col[r];
    }
    double* Yp = Y + 36 * p;
    __m256d g_lo = _mm256_setzero_pd();
    __m128d g_hi = _mm_setzero_pd();
#pragma GCC unroll 6
    for (int i = 0; i < 6; ++i) {
      __m256d y_lo = _mm256_setzero_pd();
      __m128d y_hi = _mm_setzero_pd();
#pragma GCC unroll 6
      for (int j = 0; j <= i; ++j) {
        const double l = Linv[packed(i, j)];
        const __m256d lv = _mm256_set1_pd(l);
        y_lo = _mm256_fmadd_pd(lv, _mm256_loadu_pd(Bt + 6 * j), y_lo);
        y_hi = _mm_fmadd_pd(_mm256_castpd256_pd128(lv), _mm_loadu_pd(Bt + 6 * j + 4), y_hi);
      }
      _mm256_storeu_pd(Yp + 6 * i, y_lo);
      _mm_storeu_pd(Yp + 6 * i + 4, y_hi);
      g_lo = _mm256_fmadd_pd(y_lo, _mm256_set1_pd(z[i]), g_lo);
      g_hi = _mm_fmadd_pd(y_hi, _mm_set1_pd(z[i]), g_hi);
    }
    double* rj = at.rhs + (hcol - at.offset);
    _mm256_storeu_pd(rj, _mm256_sub_pd(_mm256_loadu_pd(rj), g_lo));
    _mm_storeu_pd(rj + 4, _mm_sub_pd(_mm_loadu_pd(rj + 4), g_hi));
  }
  std::size_t pair = 0;
  for (std::size_t p = 0; p < k; ++p) {
    const double* Yp = Y + 36 * p;
    for (std::size_t q = p; q < k; ++q, ++pair) {
      const double* Yq = Y + 36 * q;
      const std::int64_t* sp = at.sp + (at.reduced_col0[links[q].j] - at.offset);
      const std::int64_t so = pair_offset[pair];
      // The six columns of Y_p^T Y_q at once (twelve independent sums): the
      // sum over i of row i of Y_p times Y_q(i, c), for each column c.
      __m256d m_lo[6];
      __m128d m_hi[6];
#pragma GCC unroll 6
      for (int c = 0; c < 6; ++c) {
        m_lo[c] = _mm256_setzero_pd();
        m_hi[c] = _mm_setzero_pd();
      }
#pragma GCC unroll 6
      for (int i = 0; i < 6; ++i) {
        const __m256d row_lo = _mm256_loadu_pd(Yp + 6 * i);
        const __m128d row_hi = _mm_loadu_pd(Yp + 6 * i + 4);
#pragma GCC unroll 6
        for (int c = 0; c < 6; ++c) {
          const __m256d y = _mm256_broadcast_sd(Yq + 6 * i + c);
          m_lo[c] = _mm256_fmadd_pd(row_lo, y, m_lo[c]);
          m_hi[c] = _mm_fmadd_pd(row_hi, _mm256_castpd256_pd128(y), m_hi[c]);
        }
      }
#pragma GCC unroll 6
      for (int c = 0; c < 6; ++c) {
        double* col = at.sv + sp[c] + so;
        if (p != q) {
          _mm256_storeu_pd(col, _mm256_sub_pd(_mm256_loadu_pd(col), m_lo[c]));
          _mm_storeu_pd(col + 4, _mm_sub_pd(_mm_loadu_pd(col + 4), m_hi[c]));
        } else {  // S_pp's upper triangle: rows 0..c of column c
          double m[6];
          _mm256_storeu_pd(m, m_lo[c]);
          _mm_storeu_pd(m + 4, m_hi[c]);
          for (int r = 0; r <= c; ++r) col[r] -= m[r];
        }
      }
    }
  }
}

// The baseline's inverseCholeskyFactor<6> on four lanes of one register.
__attribute__((target("avx2,fma"))) bool inverseCholeskySixAvx2(const double* A, double* Linv) {
  auto at = [](int i, int j) { return 4 * (i + 6 * j); };
  __m256d L[36], inv_diag[6];
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
#pragma GCC unroll 6
  for (int j = 0; j < 6; ++j) {
    __m256d d = _mm256_loadu_pd(A + at(j, j));
#pragma GCC unroll 6
    for (int k = 0; k < j; ++k) d = _mm256_fnmadd_pd(L[j + 6 * k], L[j + 6 * k], d);
    if (!pivotsAccepted(d, _mm256_loadu_pd(A + at(j, j)))) return false;
    inv_diag[j] = _mm256_div_pd(one, _mm256_sqrt_pd(d));
#pragma GCC unroll 6
    for (int i = j + 1; i < 6; ++i) {
      __m256d v = _mm256_loadu_pd(A + at(i, j));
#pragma GCC unroll 6
      for (int k = 0; k < j; ++k) v = _mm256_fnmadd_pd(L[i + 6 * k], L[j + 6 * k], v);
      L[i + 6 * j] = _mm256_mul_pd(v, inv_diag[j]);
    }
  }
  __m256d X[36];  // L^-1, by rows: row i needs rows < i only
#pragma GCC unroll 6
  for (int i = 0; i < 6; ++i) {
#pragma GCC unroll 6
    for (int j = 0; j < i; ++j) {
      __m256d v = _mm256_mul_pd(L[i + 6 * j], X[j + 6 * j]);
#pragma GCC unroll 6
      for (int k = j + 1; k < i; ++k) v = _mm256_fmadd_pd(L[i + 6 * k], X[k + 6 * j], v);
      X[i + 6 * j] = _mm256_mul_pd(_mm256_sub_pd(zero, v), inv_diag[i]);
      _mm256_storeu_pd(Linv + at(i, j), X[i + 6 * j]);
    }
    X[i + 6 * i] = inv_diag[i];
    _mm256_storeu_pd(Linv + at(i, i), inv_diag[i]);
  }
  return true;
}

#else

bool cpuHasAvx2Fma() { return false; }
bool inverseCholeskySixAvx2(const double*, double*) {
  throw std::logic_error("inverseCholeskySixAvx2: not built for this CPU (cpuHasAvx2Fma() is false)");
}
void eliminateSixAvx2(const SixElimination&, const SchurLink*, std::size_t, const double*, const double*,
                      const std::int64_t*, double*) {
  throw std::logic_error("eliminateSixAvx2: not built for this CPU (cpuHasAvx2Fma() is false)");
}

#endif

}  // namespace fgcal::detail
