// The choices a LinearSystem is built with, read by each of its parts: the
// column order (order_for_schur), the pattern (store_jacobian) and the
// evaluator (store_jacobian, threads, the pairing of like factors).
#pragma once

#include <cstddef>

namespace fgcal {

struct LinearSystemOptions {
  /// Give an independent set of variables (no factor joins two of them, e.g. a
  /// calibration's board poses) the first columns, so that H = [[A B] [B^T C]]
  /// with A block diagonal.
  bool order_for_schur = false;
  /// Keep the whitened Jacobian J (compressed columns) and r. The optimizer
  /// needs only H and g and turns this off, which saves J's memory (most of
  /// the system's) and the writes into it.
  bool store_jacobian = true;
  /// Threads (>= 1) that evaluate factors in linearize() and cost() (each accumulates its own
  /// H and g, summed at the end). Factors' evaluate() must then be safe to
  /// call concurrently (const and without shared mutable state).
  int threads = 1;
  /// Without a stored J, on graphs of up to pair_max_factors factors,
  /// evaluate like factors whose fast path pairs (NormalEquations::pairs)
  /// two in one call: a factor goes with the next factor of the same type in
  /// the graph's order at most kPairWindow places later. H, g and the cost
  /// then differ from the unpaired ones in rounding only.
  bool pair_factors = true;
  /// Pairs pay while the factors' data (about 1 kB a factor with its noise
  /// model and variables) comes from cache; from memory, a pair (one larger
  /// unit of work) overlaps fewer of the next loads with its arithmetic
  /// (BENCHMARKS.md: whole solves 9-13.5 % faster with pairs at 6,000-11,000
  /// factors, 2.5-15 % slower at 20,000-58,000, where the first
  /// linearizations read the factors from memory).
  std::size_t pair_max_factors = 16384;
};

}  // namespace fgcal
