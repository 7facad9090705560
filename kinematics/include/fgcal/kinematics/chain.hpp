// A kinematic chain between any two links of a robot: forward kinematics
// T_base_tip(q), its Jacobian in docs/design.md's convention, and encoder noise
// propagated to the pose (Sigma = J Sigma_q J^T).
//
// Everything is precomputed when the chain is built: consecutive fixed joints
// are collapsed into one constant transform, so evaluating a leg costs
// (number of movable joints) small rotations and compositions, and no
// allocation.
//
// Conventions (docs/design.md): T_a_b maps points of b into a; SE(3) tangent
// vectors are [wx wy wz vx vy vz] with right perturbation T ⊕ xi = T Exp(xi).
// The Jacobian J (6 x n) satisfies T(q + dq) ≈ T(q) Exp(J dq): rows [w v],
// expressed in the tip frame (or the marker frame when a tip-to-marker
// transform is given). Joint values are in the URDF's sense (radians or
// metres), whatever the direction in which the chain walks a joint.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fgcal/core/se3.hpp"
#include "fgcal/kinematics/joint.hpp"

namespace fgcal::kinematics {

/// One movable joint of a chain, in chain order (base to tip).
struct ChainJoint {
  std::string name;
  JointType type = JointType::Revolute;
  JointLimits limits;
  /// True when the chain walks this joint from its child link to its parent
  /// link (the path goes up the tree here, e.g. from one foot to another).
  bool upward = false;
};

/// One step of a path through the tree, as RobotModel finds it.
struct PathStep {
  JointInfo joint;
  bool upward = false;  ///< walked from joint.child_link to joint.parent_link
};

class KinematicChain {
 public:
  /// 6 x n, one column per movable joint in chain order.
  using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

  /// Builds a chain from a path of joints (usually through RobotModel::chain).
  /// Throws UrdfError when a joint on the path is floating or planar, or has a
  /// zero axis; `source` (the URDF file) goes into the message.
  KinematicChain(std::string base_link, std::string tip_link, const std::vector<PathStep>& path,
                 std::string source = "");

  const std::string& baseLink() const { return base_link_; }
  const std::string& tipLink() const { return tip_link_; }
  const std::string& source() const { return source_; }

  /// Number of movable joints n (the size of q).
  int numJoints() const { return static_cast<int>(joints_.size()); }
  /// URDF joints walked between base and tip, fixed ones included.
  int numPathJoints() const { return num_path_joints_; }
  const std::vector<ChainJoint>& joints() const { return joints_; }
  /// Movable joint names in chain order: the columns joints.csv must provide.
  const std::vector<std::string>& jointNames() const { return joint_names_; }
  std::vector<JointType> jointTypes() const;
  std::vector<JointLimits> jointLimits() const;
  /// Index of a movable joint in q, or -1 when the chain does not contain it.
  int indexOf(const std::string& joint_name) const;

  // ---- Forward kinematics; q in chain order, q.size() == numJoints() ----
  // A wrong size throws KinematicsError. Values are not range-checked (limits
  // are reported, not enforced) and a NaN in q gives a NaN pose: callers skip
  // such frames (docs/design.md, Errors).

  /// T_base_tip(q).
  SE3 forward(const Eigen::Ref<const VecX>& q) const;
  /// T_base_tip(q) and, when J_T_q is given, its Jacobian (resized to 6 x n if
  /// needed; no allocation when the caller keeps the same buffer).
  SE3 forward(const Eigen::Ref<const VecX>& q, Jacobian* J_T_q) const;
  /// T_base_marker = T_base_tip(q) * T_tip_marker and its Jacobian
  /// Ad(T_tip_marker^-1) J_tip.
  SE3 forward(const Eigen::Ref<const VecX>& q, const SE3& T_tip_marker, Jacobian* J_T_q) const;

  /// T_base_marker(q) (marker = tip when T_tip_marker is the identity) and the
  /// covariance of its right perturbation, J diag(sigma_q^2) J^T, in one pass;
  /// J_T_q, when given, also receives the Jacobian.
  SE3 forwardWithCovariance(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& sigma_q,
                            Mat6* Sigma_T, const SE3& T_tip_marker = SE3(), Jacobian* J_T_q = nullptr) const;
  // ---- Origin corrections: a robot whose geometry differs from its URDF ----
  // Before each movable joint i the chain applies a constant transform: the
  // joint's URDF <origin>, composed with the fixed joints walked since the
  // previous movable joint (from the base, for the first). With corrections u,
  // one [w v] per movable joint (6 n in chain order), that transform C_i
  // becomes C_i Exp(u_i): joint i's frame moved and turned in its own axes.
  // The fixed joints after the last movable joint get no correction (a
  // calibration's board mount absorbs their error).

  /// 6 x 6n: d T_base_marker / d u, right perturbations at the marker.
  using OriginJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

  /// T_base_marker(q, u) = T_base_tip(q, u) * T_tip_marker; J_T_q and J_T_u,
  /// when given, receive its Jacobians (T(q, u + du) = T Exp(J_T_u du)).
  /// Throws KinematicsError when u's size is not 6 n.
  SE3 forwardCorrected(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& u, const SE3& T_tip_marker,
                       Jacobian* J_T_q = nullptr, OriginJacobian* J_T_u = nullptr) const;
  /// The translation of C_i, the constant transform before movable joint i,
  /// in C_i's own axes: the v of u_i that moves joint i's frame by as much
  /// again (u_i = [0, (k - 1) originTranslation(i)] makes that link k times
  /// as long). Throws KinematicsError when i is not a joint index.
  Vec3 originTranslation(int i) const;

  /// Only the covariance of forwardWithCovariance.
  Mat6 covariance(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& sigma_q,
                  const SE3& T_tip_marker = SE3()) const;

  // ---- Joint values and sigmas by name ----

  /// q in chain order from a name -> value map. Names of joints outside the
  /// chain are ignored (a joints.csv row holds every joint); a chain joint
  /// missing from the map throws KinematicsError naming it.
  VecX jointVector(const std::map<std::string, double>& values) const;
  SE3 forward(const std::map<std::string, double>& values) const { return forward(jointVector(values)); }
  /// The same sigma for every joint.
  VecX sigmaVector(double sigma) const;
  /// Per-joint sigmas by name; joints absent from the map get `fallback`, or
  /// throw KinematicsError naming the joint when there is no fallback.
  VecX sigmaVector(const std::map<std::string, double>& sigmas, std::optional<double> fallback = std::nullopt) const;

 private:
  // C_0 M_1(q_1) C_1 ... M_n(q_n) C_n, with M_i = Exp(q_i xi_i) a pure
  // rotation about, or translation along, the (signed) axis of joint i.
  struct Step {
    Mat3 R_before;  // C_{i-1}
    Vec3 t_before;
    Vec3 axis;  // negated for a joint walked upward
    Mat3 K;     // hat(axis)
    Mat3 K2;    // hat(axis)^2, for Rodrigues' formula
    bool prismatic = false;
    // Most URDF axes are +-x, +-y or +-z: a rotation about one of them touches
    // two columns (or rows) only, which halves the cost of a leg.
    int unit_axis = -1;  // 0, 1, 2 when axis = sign * e_k, else -1
    double unit_sign = 1.0;
  };

  void checkSize(const Eigen::Ref<const VecX>& q, const char* what) const;
  // The backward pass shared by the Jacobian and covariance: walks from the tip,
  // writing column i of J (when J) or adding sigma_i^2 J_i J_i^T (when Sigma).
  // With origin corrections u (may be null), J_u receives their Jacobian.
  SE3 backward(const Eigen::Ref<const VecX>& q, const SE3* T_tip_marker, Jacobian* J,
               const Eigen::Ref<const VecX>* sigma, Mat6* Sigma, const Eigen::Ref<const VecX>* u = nullptr,
               OriginJacobian* J_u = nullptr) const;

  std::string base_link_, tip_link_, source_;
  std::vector<ChainJoint> joints_;
  std::vector<std::string> joint_names_;
  std::vector<Step> steps_;
  Mat3 R_tail_ = Mat3::Identity();  // C_n
  Vec3 t_tail_ = Vec3::Zero();
  int num_path_joints_ = 0;
};

}  // namespace fgcal::kinematics
