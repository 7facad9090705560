// Marginal covariances of a few variables of a large graph whose other
// variables each touch only a handful of factors, without factorizing the
// whole system: every other variable is eliminated in turn (its Schur
// complement folded into the kept ones' information), then the small
// information of the kept variables is inverted. The calibration keeps the
// cameras and the mount and eliminates one board pose per instant, so the
// memory is that of the kept variables, not of the graph.
#pragma once

#include <vector>

#include "fgcal/core/factor_graph.hpp"

namespace fgcal::apps {

/// The covariance of each of `keep` at `values` (in its tangent space, as
/// core's Marginals gives it), with every variable that is neither kept nor
/// in `fixed` eliminated. Each factor may touch at most one eliminated
/// variable, and the factors of one eliminated variable must follow each
/// other in the graph (std::logic_error otherwise); robust kernels are not
/// supported (std::logic_error). DataError when the kept variables'
/// information is not positive definite.
std::vector<MatX> reducedMarginals(const FactorGraph& graph, const Values& values, const std::vector<Key>& keep,
                                   const std::vector<Key>& fixed);

/// The same elimination, and the joint covariance of `keep` (their blocks
/// in that order, cross-covariances included).
MatX reducedJointCovariance(const FactorGraph& graph, const Values& values, const std::vector<Key>& keep,
                            const std::vector<Key>& fixed);

}  // namespace fgcal::apps
