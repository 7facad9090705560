# Robot kinematics from Python: forward kinematics against the URDF's joint
# origins composed in numpy, the Jacobian against central differences through
# the right perturbation ([w v] rows), the propagated covariance against
# J diag(sigma^2) J^T, and errors naming the file or joint.
import os

import numpy as np
import pytest

import fgcal


def rodrigues(axis, angle):
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def fk_oracle(robot, base, tip, q):
    """T_base_tip from the joints' origins and axes, base an ancestor of tip."""
    by_child = {j.child_link: j for j in robot.joints}
    path, link = [], tip
    while link != base:
        j = by_child[link]
        path.append(j)
        link = j.parent_link
    T = np.eye(4)
    for j in reversed(path):
        M = np.eye(4)
        if j.type in ("revolute", "continuous"):
            M[:3, :3] = rodrigues(j.axis, q[j.name])
        elif j.type == "prismatic":
            M[:3, 3] = j.axis * q[j.name]
        T = T @ j.T_parent_joint @ M
    return T


def check_chain(robot, base, tip, rng):
    chain = robot.chain(base, tip)
    names = chain.joint_names
    q = rng.uniform(-1.0, 1.0, size=len(names))
    qmap = dict(zip(names, q))
    T = chain.forward(q)
    np.testing.assert_allclose(T, fk_oracle(robot, base, tip, qmap), atol=1e-12)
    np.testing.assert_allclose(chain.forward(qmap), T, atol=0)  # a dict in any order
    # Jacobian: T(q + dq) = T(q) Exp(J dq)
    T2, J = chain.forward(q, jacobian=True)
    assert J.shape == (6, len(names))
    h = 1e-6
    for i in range(len(names)):
        dq = np.zeros(len(q))
        dq[i] = h
        col = (fgcal.se3.minus(T, chain.forward(q + dq)) - fgcal.se3.minus(T, chain.forward(q - dq))) / (2 * h)
        np.testing.assert_allclose(J[:, i], col, atol=1e-7)
    # with a marker on the tip, and the covariance
    M = fgcal.se3.exp(rng.normal(size=6) * 0.1)
    sigma = rng.uniform(1e-3, 3e-3, size=len(names))
    TM, JM = chain.forward(q, T_tip_marker=M, jacobian=True)
    np.testing.assert_allclose(TM, T @ M, atol=1e-12)
    np.testing.assert_allclose(JM, fgcal.se3.adjoint(fgcal.se3.inverse(M)) @ J, atol=1e-12)
    C = chain.covariance(q, sigma, T_tip_marker=M)
    np.testing.assert_allclose(C, JM @ np.diag(sigma**2) @ JM.T, atol=1e-15)
    T3, C3, J3 = chain.forward_with_covariance(q, dict(zip(names, sigma)), T_tip_marker=M)
    np.testing.assert_allclose(T3, TM, atol=0)
    np.testing.assert_allclose(C3, C, atol=1e-18)
    np.testing.assert_allclose(chain.covariance(q, 0.002), J @ J.T * 0.002**2, atol=1e-15)
    return chain


def test_default_robot_leg():
    robot = fgcal.RobotModel.default()
    assert robot.name == "fgcal_quadruped" and robot.root_link == "base_link"
    chain = check_chain(robot, "base_link", "lf_foot", np.random.default_rng(1))
    assert chain.num_joints == 3 and chain.base_link == "base_link" and chain.tip_link == "lf_foot"


def test_shared_urdf_leg():
    data = os.environ.get("FGCAL_SHARED_DATA_DIR", "")
    path = os.path.join(data, "urdf", "anymal_c.urdf")
    if not os.path.isfile(path):
        pytest.skip("SKIPPED: shared data not found (FGCAL_SHARED_DATA_DIR)")
    robot = fgcal.RobotModel.from_file(path)
    assert robot.root_link == "base" and len(robot.joint_names) == 77  # SOURCES.md's facts
    chain = check_chain(robot, "base", "LF_FOOT", np.random.default_rng(2))
    assert chain.joint_names == ["LF_HAA", "LF_HFE", "LF_KFE"]


def test_kinematics_errors_name_the_file_and_joint(tmp_path):
    robot = fgcal.RobotModel.default()
    with pytest.raises(fgcal.InputError, match="no_such_link") as e:
        robot.chain("base_link", "no_such_link")
    assert isinstance(e.value, ValueError) and isinstance(e.value, fgcal.Error)
    chain = robot.chain("base_link", "lf_foot")
    with pytest.raises(fgcal.InputError, match="has 3 movable joints, but the joint vector has 2 values"):
        chain.forward(np.zeros(2))
    with pytest.raises(fgcal.InputError, match=f"needs a value for joint '{chain.joint_names[0]}'"):
        chain.forward({n: 0.0 for n in chain.joint_names[1:]})
    missing = tmp_path / "missing.urdf"
    with pytest.raises(fgcal.InputError, match=str(missing)):
        fgcal.RobotModel.from_file(str(missing))
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='r'><link name='a'/><joint name='j' type='revolute'>")
    with pytest.raises(fgcal.InputError, match="bad.urdf"):
        fgcal.RobotModel.from_file(str(bad))
