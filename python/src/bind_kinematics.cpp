// Robot kinematics from Python: a RobotModel read from a URDF, the chain
// between two links, its forward kinematics, Jacobian ([w v] rows, right
// perturbation, in the tip or marker frame) and encoder noise propagated to
// the pose (J diag(sigma^2) J^T).
#include <map>
#include <optional>

#include "bindings.hpp"
#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal/kinematics/robot_model.hpp"

namespace fgcal::python {

namespace {

using kinematics::KinematicChain;
using kinematics::RobotModel;

SE3 markerOf(const std::optional<Mat4>& T_tip_marker) {
  return T_tip_marker ? toSE3(*T_tip_marker, "T_tip_marker") : SE3();
}

// Joint sigmas: one number for every joint, a vector in chain order, or a
// dict joint -> sigma.
VecX sigmasOf(const KinematicChain& chain, const py::handle& sigma_q) {
  if (py::isinstance<py::dict>(sigma_q)) return chain.sigmaVector(sigma_q.cast<std::map<std::string, double>>());
  if (py::isinstance<py::float_>(sigma_q) || py::isinstance<py::int_>(sigma_q))
    return chain.sigmaVector(sigma_q.cast<double>());
  return sigma_q.cast<VecX>();
}

// Joint values: a vector in chain order, or a dict joint -> value.
VecX jointsOf(const KinematicChain& chain, const py::handle& q) {
  if (py::isinstance<py::dict>(q)) return chain.jointVector(q.cast<std::map<std::string, double>>());
  return q.cast<VecX>();
}

void bindJoints(py::module_& m) {
  py::class_<kinematics::JointLimits>(m, "JointLimits")
      .def_readonly("has_position_limits", &kinematics::JointLimits::has_position_limits)
      .def_readonly("lower", &kinematics::JointLimits::lower)
      .def_readonly("upper", &kinematics::JointLimits::upper)
      .def_readonly("effort", &kinematics::JointLimits::effort)
      .def_readonly("velocity", &kinematics::JointLimits::velocity);
  py::class_<kinematics::JointInfo>(m, "JointInfo", "A URDF joint.")
      .def_readonly("name", &kinematics::JointInfo::name)
      .def_property_readonly("type", [](const kinematics::JointInfo& j) { return kinematics::toString(j.type); })
      .def_readonly("parent_link", &kinematics::JointInfo::parent_link)
      .def_readonly("child_link", &kinematics::JointInfo::child_link)
      .def_property_readonly("T_parent_joint",
                             [](const kinematics::JointInfo& j) { return j.T_parent_joint.matrix(); })
      .def_readonly("axis", &kinematics::JointInfo::axis)
      .def_readonly("limits", &kinematics::JointInfo::limits)
      .def_readonly("mimic_joint", &kinematics::JointInfo::mimic_joint)
      .def("__repr__", [](const kinematics::JointInfo& j) {
        return "<JointInfo " + j.name + " (" + kinematics::toString(j.type) + ") " + j.parent_link + " -> " +
               j.child_link + ">";
      });
}

void bindChain(py::module_& m) {
  py::class_<KinematicChain>(m, "KinematicChain", R"doc(
The kinematic chain between two links of a RobotModel (RobotModel.chain).
q holds the movable joints in chain order (joint_names), or is a dict
joint name -> value. Jacobians are 6 x n with rows [w v]: T(q + dq) ~ T(q) Exp(J dq),
expressed in the tip frame (or the marker frame when T_tip_marker is given).
)doc")
      .def_property_readonly("base_link", &KinematicChain::baseLink)
      .def_property_readonly("tip_link", &KinematicChain::tipLink)
      .def_property_readonly("num_joints", &KinematicChain::numJoints)
      .def_property_readonly("joint_names", &KinematicChain::jointNames)
      .def(
          "forward",
          [](const KinematicChain& c, const py::handle& q, const std::optional<Mat4>& T_tip_marker,
             bool jacobian) -> py::object {
            KinematicChain::Jacobian J;
            const SE3 T = c.forward(jointsOf(c, q), markerOf(T_tip_marker), jacobian ? &J : nullptr);
            if (!jacobian) return py::cast(T.matrix());
            return py::make_tuple(T.matrix(), MatX(J));
          },
          py::arg("q"), py::arg("T_tip_marker") = py::none(), py::arg("jacobian") = false,
          "T_base_tip(q) (times T_tip_marker when given); with jacobian=True, (T, J).")
      .def(
          "covariance",
          [](const KinematicChain& c, const py::handle& q, const py::handle& sigma_q,
             const std::optional<Mat4>& T_tip_marker) {
            return c.covariance(jointsOf(c, q), sigmasOf(c, sigma_q), markerOf(T_tip_marker));
          },
          py::arg("q"), py::arg("sigma_q"), py::arg("T_tip_marker") = py::none(),
          "The 6x6 covariance of the pose's right perturbation, J diag(sigma_q^2) J^T; sigma_q is one number, "
          "a vector in chain order or a dict joint -> sigma.")
      .def(
          "forward_with_covariance",
          [](const KinematicChain& c, const py::handle& q, const py::handle& sigma_q,
             const std::optional<Mat4>& T_tip_marker) {
            Mat6 Sigma;
            KinematicChain::Jacobian J;
            const SE3 T = c.forwardWithCovariance(jointsOf(c, q), sigmasOf(c, sigma_q), &Sigma,
                                                  markerOf(T_tip_marker), &J);
            return py::make_tuple(T.matrix(), Sigma, MatX(J));
          },
          py::arg("q"), py::arg("sigma_q"), py::arg("T_tip_marker") = py::none(), "(T, covariance, J) in one pass.")
      .def(
          "joint_vector",
          [](const KinematicChain& c, const std::map<std::string, double>& values) { return c.jointVector(values); },
          py::arg("values"), "q in chain order from a dict joint -> value (other joints are ignored).")
      .def("__repr__", [](const KinematicChain& c) {
        return "<KinematicChain " + c.baseLink() + " -> " + c.tipLink() + ", " + std::to_string(c.numJoints()) +
               " joints>";
      });
}

void bindRobot(py::module_& m) {
  py::class_<RobotModel>(m, "RobotModel", "A robot read from a URDF: links, joints and the chains between links.")
      .def_static("from_file", &RobotModel::fromFile, py::arg("path"),
                  "Reads a URDF file; InputError naming the file when it cannot be used.")
      .def_static("from_string", &RobotModel::fromString, py::arg("urdf_xml"), py::arg("source") = "<string>")
      .def_static("default", &kinematics::loadDefaultRobot, "fgcal's own HyQ-like quadruped (built in).")
      .def_property_readonly("name", &RobotModel::name)
      .def_property_readonly("source", &RobotModel::source)
      .def_property_readonly("root_link", &RobotModel::rootLink)
      .def_property_readonly("link_names", &RobotModel::linkNames)
      .def_property_readonly("joint_names", &RobotModel::jointNames)
      .def_property_readonly("movable_joint_names", &RobotModel::movableJointNames)
      .def_property_readonly("leaf_links", &RobotModel::leafLinks)
      .def_property_readonly("joints", &RobotModel::joints)
      .def("has_link", &RobotModel::hasLink, py::arg("name"))
      .def("joint", &RobotModel::joint, py::arg("name"), py::return_value_policy::copy)
      .def("total_mass", &RobotModel::totalMass)
      .def("chain", &RobotModel::chain, py::arg("base_link"), py::arg("tip_link"),
           "The chain between any two links (up from base_link to the common ancestor, then down).")
      .def("__repr__", [](const RobotModel& r) {
        return "<RobotModel " + r.name() + " from " + r.source() + ", " + std::to_string(r.links().size()) +
               " links>";
      });
}

}  // namespace

void bindKinematics(py::module_& m) {
  bindJoints(m);
  bindChain(m);
  bindRobot(m);
}

}  // namespace fgcal::python
