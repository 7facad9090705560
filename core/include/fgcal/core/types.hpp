// Fixed-size Eigen aliases used across fgcal.
#pragma once

#include <Eigen/Core>

namespace fgcal {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat36 = Eigen::Matrix<double, 3, 6>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

}  // namespace fgcal
