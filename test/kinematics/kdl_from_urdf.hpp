// Test oracle: a KDL::Chain built straight from urdfdom's model (no
// kdl_parser, which drags in ROS), walking parent links from the tip up to the
// base. Independent of fgcal's own chain walker on purpose.
#pragma once

#include <string>

#include <kdl/chain.hpp>
#include <urdf_model/model.h>

namespace fgcal::test {

/// The chain base -> tip; base must be an ancestor of tip (KDL chains only go
/// down the tree). Throws std::runtime_error otherwise.
KDL::Chain kdlChainFromUrdf(const urdf::ModelInterface& model, const std::string& base, const std::string& tip);

}  // namespace fgcal::test
