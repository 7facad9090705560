# The solver from Python: SE(3)/SO(3) on numpy matrices against an
# independent matrix exponential, values, noise models, a pose graph solved
# through the module against the same graph solved by C++ directly, a factor
# written in Python (alone, among the library's factors, on worker threads,
# with wrong Jacobians or failing), marginals, and the GIL released in optimize.
import os
import subprocess
import sys

import numpy as np
import pytest

import fgcal
from conftest import env_path, runs_without_gil

RNG = np.random.default_rng(7)


# ---- an independent SE(3): the matrix exponential of the 4x4 twist ----

def hat3(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def twist(xi):
    """The 4x4 Lie algebra element of xi = [w v] (rotation first)."""
    X = np.zeros((4, 4))
    X[:3, :3] = hat3(xi[:3])
    X[:3, 3] = xi[3:]
    return X


def expm(A):
    """Matrix exponential by scaling and squaring with a Taylor series."""
    s = max(0, int(np.ceil(np.log2(max(np.linalg.norm(A, 1), 1e-300)))) + 1)
    B = A / 2.0**s
    E, term = np.eye(len(A)), np.eye(len(A))
    for k in range(1, 30):
        term = term @ B / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def random_xi(scale=1.0):
    xi = RNG.normal(size=6) * scale
    return xi


def random_pose():
    return fgcal.se3.exp(random_xi())


def numerical_jacobian(f, x, plus, minus, h=1e-6):
    """d f / d x through the retractions, central differences."""
    y0 = f(x)
    cols = []
    n = 6 if np.shape(x) == (4, 4) else 3 if np.shape(x) == (3, 3) else len(x)
    for i in range(n):
        d = np.zeros(n)
        d[i] = h
        yp = minus(y0, f(plus(x, d)))
        d[i] = -h
        ym = minus(y0, f(plus(x, d)))
        cols.append((yp - ym) / (2 * h))
    return np.array(cols).T


def test_se3_exp_is_the_matrix_exponential_of_the_w_v_twist():
    for scale in (1e-9, 1e-3, 0.5, 1.0, 2.0):
        for _ in range(5):
            xi = random_xi(scale)
            np.testing.assert_allclose(fgcal.se3.exp(xi), expm(twist(xi)), atol=1e-12)
    # near pi
    xi = np.array([np.pi - 1e-7, 0, 0, 0.3, -0.2, 0.1])
    np.testing.assert_allclose(fgcal.se3.exp(xi), expm(twist(xi)), atol=1e-11)


def test_se3_round_trips():
    for scale in (1e-8, 1e-3, 0.3, 1.0):
        for _ in range(10):
            xi = random_xi(scale)
            xi[:3] *= min(1.0, 3.0 / max(np.linalg.norm(xi[:3]), 1e-300))  # angle below pi
            np.testing.assert_allclose(fgcal.se3.log(fgcal.se3.exp(xi)), xi, atol=1e-12)
    for _ in range(10):
        A, B = random_pose(), random_pose()
        np.testing.assert_allclose(fgcal.se3.exp(fgcal.se3.log(A)), A, atol=1e-12)
        np.testing.assert_allclose(fgcal.se3.compose(A, B), A @ B, atol=1e-12)
        np.testing.assert_allclose(fgcal.se3.compose(A, fgcal.se3.inverse(A)), np.eye(4), atol=1e-12)
        np.testing.assert_allclose(fgcal.se3.between(A, B), np.linalg.inv(A) @ B, atol=1e-12)
        xi = random_xi(0.3)
        # right perturbation: A ⊕ xi = A Exp(xi), and minus inverts it
        np.testing.assert_allclose(fgcal.se3.plus(A, xi), A @ expm(twist(xi)), atol=1e-12)
        np.testing.assert_allclose(fgcal.se3.minus(A, fgcal.se3.plus(A, xi)), xi, atol=1e-12)
        # adjoint: A Exp(xi) A^-1 = Exp(Ad(A) xi)
        np.testing.assert_allclose(A @ expm(twist(xi)) @ np.linalg.inv(A),
                                   expm(twist(fgcal.se3.adjoint(A) @ xi)), atol=1e-11)
        p = RNG.normal(size=3)
        np.testing.assert_allclose(fgcal.se3.act(A, p), A[:3, :3] @ p + A[:3, 3], atol=1e-12)
        np.testing.assert_allclose(fgcal.se3.from_xyz_rpy(*np.split(fgcal.se3.xyz_rpy(A), 2)), A, atol=1e-12)


def test_so3_round_trips():
    for _ in range(10):
        w = RNG.normal(size=3)
        w *= 2.5 / np.linalg.norm(w)
        R = fgcal.so3.exp(w)
        np.testing.assert_allclose(R, expm(hat3(w)), atol=1e-12)
        np.testing.assert_allclose(fgcal.so3.log(R), w, atol=1e-12)
        S = fgcal.so3.exp(RNG.normal(size=3))
        np.testing.assert_allclose(fgcal.so3.compose(R, S), R @ S, atol=1e-12)
        np.testing.assert_allclose(fgcal.so3.inverse(R), R.T, atol=1e-15)
        np.testing.assert_allclose(fgcal.so3.adjoint(R), R)
        np.testing.assert_allclose(fgcal.so3.vee(fgcal.so3.hat(w)), w)
        np.testing.assert_allclose(fgcal.so3.from_rpy(*fgcal.so3.rpy(R)), R, atol=1e-12)


def test_jacobians_match_central_differences():
    A, B = random_pose(), random_pose()
    _, J_A, J_B = fgcal.se3.compose(A, B, jacobians=True)
    np.testing.assert_allclose(
        J_A, numerical_jacobian(lambda X: fgcal.se3.compose(X, B), A, fgcal.se3.plus, fgcal.se3.minus), atol=1e-6)
    np.testing.assert_allclose(
        J_B, numerical_jacobian(lambda X: fgcal.se3.compose(A, X), B, fgcal.se3.plus, fgcal.se3.minus), atol=1e-6)
    _, J = fgcal.se3.inverse(A, jacobians=True)
    np.testing.assert_allclose(
        J, numerical_jacobian(fgcal.se3.inverse, A, fgcal.se3.plus, fgcal.se3.minus), atol=1e-6)
    xi = random_xi(0.7)
    _, J = fgcal.se3.log(fgcal.se3.exp(xi), jacobians=True)
    np.testing.assert_allclose(
        J, numerical_jacobian(fgcal.se3.log, fgcal.se3.exp(xi), fgcal.se3.plus, lambda a, b: b - a), atol=1e-6)
    np.testing.assert_allclose(J, fgcal.se3.right_jacobian_inverse(xi), atol=1e-12)
    p = RNG.normal(size=3)
    _, J_T, J_p = fgcal.se3.act(A, p, jacobians=True)
    np.testing.assert_allclose(
        J_T, numerical_jacobian(lambda X: fgcal.se3.act(X, p), A, fgcal.se3.plus, lambda a, b: b - a), atol=1e-6)
    np.testing.assert_allclose(J_p, A[:3, :3])


def test_matrices_that_are_not_rigid_transforms_are_value_errors():
    T = random_pose()
    T[0, 0] += 1e-3
    with pytest.raises(ValueError, match="T: matrix is not a rotation"):
        fgcal.se3.log(T)
    T = random_pose()
    T[3, 0] = 1.0
    with pytest.raises(ValueError, match=r"last row .* \[0, 0, 0, 1\]"):
        fgcal.se3.inverse(T)
    with pytest.raises(TypeError):
        fgcal.se3.log(np.eye(3))


def test_keys():
    k = fgcal.key("x", 12)
    assert fgcal.key_symbol(k) == "x" and fgcal.key_index(k) == 12 and fgcal.key_to_string(k) == "x12"
    with pytest.raises(ValueError):
        fgcal.key("xy", 1)


def test_values_round_trip_each_variable_type():
    v = fgcal.Values()
    T, R, p = random_pose(), fgcal.so3.exp(RNG.normal(size=3)), RNG.normal(size=5)
    v.insert(fgcal.key("T", 0), T)
    v.insert(fgcal.key("R", 0), R)
    v[fgcal.key("p", 0)] = p
    assert np.array_equal(v.at(fgcal.key("T", 0)), T)  # taken as given, bit for bit
    assert np.array_equal(v[fgcal.key("R", 0)], R)
    assert np.array_equal(v[fgcal.key("p", 0)], p)
    assert [v.dim(k) for k in v.keys()] == [6, 3, 5]
    assert len(v) == 3 and fgcal.key("T", 0) in v and fgcal.key("T", 1) not in v
    w = v.copy()
    w[fgcal.key("p", 0)] = np.zeros(5)
    assert np.array_equal(v[fgcal.key("p", 0)], p)  # a copy is independent
    with pytest.raises(ValueError, match="already"):
        v.insert(fgcal.key("T", 0), T)
    with pytest.raises(KeyError, match="T1"):
        v.at(fgcal.key("T", 1))
    with pytest.raises(ValueError, match=r"value of q0: expected .* got shape \(2, 5\)"):
        v.insert(fgcal.key("q", 0), np.zeros((2, 5)))
    with pytest.raises(ValueError, match="another type"):
        v.update(fgcal.key("T", 0), R)


def test_noise_models_and_kernels():
    A = RNG.normal(size=(6, 6))
    C = A @ A.T + 0.1 * np.eye(6)
    n = fgcal.NoiseModel.from_covariance(C)
    np.testing.assert_allclose(n.covariance, C, rtol=1e-10, atol=1e-12)
    W = n.sqrt_information
    np.testing.assert_allclose(W.T @ W, np.linalg.inv(C), rtol=1e-9, atol=1e-9)
    r = RNG.normal(size=6)
    np.testing.assert_allclose(n.whiten(r), W @ r)
    d = fgcal.NoiseModel.diagonal([1.0, 2.0, 3.0])
    assert d.is_diagonal and d.dim == 3
    np.testing.assert_allclose(d.covariance, np.diag([1.0, 4.0, 9.0]))
    with pytest.raises(ValueError):
        fgcal.NoiseModel.from_covariance(-np.eye(3))
    h = fgcal.huber(1.0)
    assert h.name and h.rho(0.25) == pytest.approx(0.25) and h.weight(4.0) == pytest.approx(0.5)
    with pytest.raises(ValueError):
        fgcal.huber(-1.0)


# ---- a pose graph solved through the module and by C++ directly ----

def pose_graph(n, seed):
    """A noisy helix of poses: odometry, loop closures (robust), a prior; initial = chained odometry."""
    rng = np.random.default_rng(seed)
    truth = [fgcal.se3.exp(np.array([0, 0, 2 * np.pi * i / 20 + np.pi / 2, 0, 0, 0]))
             @ fgcal.se3.exp(np.array([0, 0, 0, 5.0, 0, 0.05 * i])) for i in range(n)]
    sig = np.array([0.01, 0.01, 0.01, 0.05, 0.05, 0.05])
    noisy = lambda T: fgcal.se3.plus(T, sig * rng.normal(size=6))
    prior = ("prior", 0, truth[0], np.full(6, 1e-3))
    edges = [("between", i, i + 1, noisy(fgcal.se3.between(truth[i], truth[i + 1])), sig, 0.0) for i in range(n - 1)]
    edges += [("between", i, i + 20, noisy(fgcal.se3.between(truth[i], truth[i + 20])), sig, 3.0)
              for i in range(0, n - 20, 3)]
    initial = [truth[0]]
    for e in edges[:n - 1]:
        initial.append(initial[-1] @ e[3])
    return truth, prior, edges, initial


def numbers(a):
    return " ".join(repr(float(x)) for x in np.ravel(a))


def solve_in_cpp(tmp_path, prior, edges, initial, algorithm, max_iterations, cov_key):
    text = [f"options {algorithm} {max_iterations}"]
    text += [f"pose {i} {numbers(T)}" for i, T in enumerate(initial)]
    text.append(f"prior {prior[1]} {numbers(prior[2])} {numbers(prior[3])}")
    text += [f"between {a} {b} {numbers(Z)} {numbers(s)} {k!r}" for _, a, b, Z, s, k in edges]
    text.append(f"covariance {cov_key}")
    path = tmp_path / "graph.txt"
    path.write_text("\n".join(text) + "\n")
    out = subprocess.run([env_path("FGCAL_POSE_GRAPH_REFERENCE"), str(path)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    poses, cov, result = {}, None, None
    for line in out.stdout.splitlines():
        kind, *rest = line.split()
        if kind == "pose":
            poses[int(rest[0])] = np.array([float(x) for x in rest[1:]]).reshape(4, 4)
        elif kind == "covariance":
            cov = np.array([float(x) for x in rest[1:]]).reshape(6, 6)
        elif kind == "result":
            result = (int(rest[0]), float(rest[1]), float(rest[2]), rest[3] == "1")
    return poses, cov, result


@pytest.mark.parametrize("algorithm", ["gauss_newton", "levenberg_marquardt"])
def test_pose_graph_solve_matches_the_cpp_solve(tmp_path, algorithm):
    n = 80
    truth, prior, edges, initial = pose_graph(n, seed=3)
    graph, values = fgcal.FactorGraph(), fgcal.Values()
    x = lambda i: fgcal.key("x", i)
    for i, T in enumerate(initial):
        values.insert(x(i), T)
    graph.add(fgcal.PriorFactorSE3(x(prior[1]), prior[2], fgcal.NoiseModel.diagonal(prior[3])))
    for _, a, b, Z, s, k in edges:
        graph.add(fgcal.RelativePoseFactor(x(a), x(b), Z, fgcal.NoiseModel.diagonal(s),
                                           fgcal.huber(k) if k > 0 else None))
    res = fgcal.optimize(graph, values, algorithm=algorithm, max_iterations=50)
    cov = fgcal.Marginals(graph, res.values).covariance(x(n - 1))

    poses, cov_cpp, (iterations, initial_cost, final_cost, converged) = solve_in_cpp(
        tmp_path, prior, edges, initial, algorithm, 50, n - 1)
    assert res.converged and converged
    assert res.iterations == iterations
    assert res.initial_cost == pytest.approx(initial_cost, rel=1e-12)
    assert res.final_cost == pytest.approx(final_cost, rel=1e-9)
    for i in range(n):
        np.testing.assert_allclose(res.values[x(i)], poses[i], atol=1e-9)
    np.testing.assert_allclose(cov, cov_cpp, rtol=1e-9, atol=1e-15)
    # and the solve is a real one: no worse than the truth itself, and much
    # closer to it than the chained odometry
    at_truth = fgcal.Values()
    for i, T in enumerate(truth):
        at_truth.insert(x(i), T)
    assert res.final_cost <= graph.cost(at_truth)
    err = lambda vals: np.sqrt(np.mean([np.sum((vals(i)[:3, 3] - truth[i][:3, 3]) ** 2) for i in range(n)]))
    assert err(lambda i: res.values[x(i)]) < 0.6 * err(lambda i: initial[i])
    history = res.cost_history
    assert len(history) == len(res.reports) + 1 and history[0] == res.initial_cost
    assert history[-1] == pytest.approx(res.final_cost) and min(history) == pytest.approx(res.final_cost)


def test_optimize_options_and_keyword_errors():
    opts = fgcal.OptimizerOptions()
    assert opts.algorithm == "levenberg_marquardt"
    opts.algorithm = "gn"
    assert opts.algorithm == "gauss_newton"
    with pytest.raises(ValueError, match="algorithm"):
        opts.algorithm = "newton"
    g, v = fgcal.FactorGraph(), fgcal.Values()
    v.insert(fgcal.key("x", 0), random_pose())
    g.add(fgcal.PriorFactorSE3(fgcal.key("x", 0), np.eye(4), fgcal.NoiseModel.isotropic(6, 0.1)))
    seen = []
    res = fgcal.optimize(g, v, opts, callback=lambda r: seen.append((r.iteration, r.cost)))
    assert res.converged and np.allclose(res.values[fgcal.key("x", 0)], np.eye(4), atol=1e-9)
    assert seen and [c for _, c in seen] == res.cost_history[1:]
    with pytest.raises(TypeError, match="unexpected keyword argument 'max_iter'"):
        fgcal.optimize(g, v, max_iter=3)


def test_streamed_schur_complement_reaches_the_stored_ones_optimum():
    # Two cameras seeing 40 board poses (each also placed by a factor written
    # in Python, which the streamed solver evaluates through its Jacobians).
    rng = np.random.default_rng(3)
    c, b = (lambda i: fgcal.key("c", i)), (lambda i: fgcal.key("b", i))
    g, v = fgcal.FactorGraph(), fgcal.Values()
    cams = [random_pose() for _ in range(2)]
    for i, T in enumerate(cams):
        v.insert(c(i), T @ fgcal.se3.exp(0.05 * rng.standard_normal(6)))
    g.add(fgcal.PriorFactorSE3(c(0), cams[0], fgcal.NoiseModel.isotropic(6, 0.01)))
    for j in range(40):
        B = random_pose()
        v.insert(b(j), B @ fgcal.se3.exp(0.05 * rng.standard_normal(6)))
        g.add(PositionOfPose(b(j), B[:3, 3] + 0.01 * rng.standard_normal(3), np.zeros(3), 0.01))
        for i, T in enumerate(cams):
            Z = np.linalg.inv(T) @ B @ fgcal.se3.exp(0.002 * rng.standard_normal(6))
            g.add(fgcal.RelativePoseFactor(c(i), b(j), Z, fgcal.NoiseModel.isotropic(6, 0.002)))
    stored = fgcal.optimize(g, v, linear_solver="schur_complement", relative_cost_tolerance=1e-14)
    streamed = fgcal.optimize(g, v, linear_solver="streamed_schur_complement", relative_cost_tolerance=1e-14)
    assert stored.converged and streamed.converged
    assert streamed.linear_solver.startswith("streamed Schur complement (40 blocks eliminated, 12 reduced columns")
    assert streamed.final_cost == pytest.approx(stored.final_cost, rel=1e-9)
    for k in [c(0), c(1), b(0), b(39)]:
        assert np.allclose(streamed.values[k], stored.values[k], atol=1e-8)
    with pytest.raises(ValueError, match="'streamed_schur_complement'"):
        fgcal.OptimizerOptions().linear_solver = "streamed"


# ---- factors written in Python ----

class RangeFactor(fgcal.PythonFactor):
    """|p - anchor| = range, one residual on a 3-vector."""

    def __init__(self, key, anchor, measured, sigma, wrong_jacobian=False):
        super().__init__([key], fgcal.NoiseModel.isotropic(1, sigma))
        self.anchor, self.measured, self.wrong = np.asarray(anchor, float), measured, wrong_jacobian

    def evaluate(self, values, jacobians):
        d = values[0] - self.anchor
        r = np.array([np.linalg.norm(d) - self.measured])
        if not jacobians:
            return r
        J = (d / np.linalg.norm(d)).reshape(1, 3)
        return r, [2.0 * J if self.wrong else J]


class PositionOfPose(fgcal.PythonFactor):
    """A point known in a pose's frame (p_body) seen at p_world: r = T p_body - p_world."""

    def __init__(self, key, p_world, p_body, sigma):
        super().__init__([key], fgcal.NoiseModel.isotropic(3, sigma))
        self.p_world, self.p_body = p_world, p_body

    def evaluate(self, values, jacobians):
        T = values[0]
        q, J_T, _ = fgcal.se3.act(T, self.p_body, jacobians=True)
        return q - self.p_world, [J_T]


def test_python_factor_is_solved():
    truth = np.array([1.0, 2.0, 0.5])
    anchors = [np.zeros(3), [5, 0, 0], [0, 5, 0], [0, 0, 5], [5, 5, 5]]
    g, v = fgcal.FactorGraph(), fgcal.Values()
    p = fgcal.key("p", 0)
    for a in anchors:
        g.add(RangeFactor(p, a, np.linalg.norm(truth - a) + 1e-3 * RNG.normal(), 1e-3))
    v.insert(p, np.array([0.5, 0.5, 0.5]))
    res = fgcal.optimize(g, v, check_jacobians=True)
    assert res.converged, res.message
    np.testing.assert_allclose(res.values[p], truth, atol=5e-3)
    cov = fgcal.Marginals(g, res.values).covariance(p)
    assert np.all(np.linalg.eigvalsh(cov) > 0) and np.sqrt(cov[0, 0]) < 5e-3
    assert fgcal.check_factor_jacobians(g[0], res.values) == []
    assert "RangeFactor" in g[0].describe() and isinstance(g[0], RangeFactor)


def test_python_factor_among_library_factors_on_se3():
    # A pose seen through Python position factors and a C++ rotation-only prior.
    truth = random_pose()
    x = fgcal.key("x", 0)
    g, v = fgcal.FactorGraph(), fgcal.Values()
    for _ in range(6):
        b = RNG.normal(size=3)
        g.add(PositionOfPose(x, fgcal.se3.act(truth, b), b, 1e-3))
    v.insert(x, fgcal.se3.plus(truth, 0.2 * RNG.normal(size=6)))
    g.add(fgcal.PriorFactorSE3(x, truth, fgcal.NoiseModel.diagonal([1e-3] * 3 + [10.0] * 3)))
    assert fgcal.check_factor_jacobians(g[0], v) == []
    res = fgcal.optimize(g, v, algorithm="gauss_newton")
    assert res.converged
    np.testing.assert_allclose(res.values[x], truth, atol=1e-9)


def test_check_factor_jacobians_finds_a_wrong_python_jacobian():
    v = fgcal.Values()
    p = fgcal.key("p", 0)
    v.insert(p, np.array([1.0, 2.0, 3.0]))
    bad = fgcal.check_factor_jacobians(RangeFactor(p, np.zeros(3), 1.0, 0.1, wrong_jacobian=True), v)
    assert len(bad) == 1 and bad[0].key == p and "p0" in bad[0].message
    g = fgcal.FactorGraph()
    g.add(RangeFactor(p, np.zeros(3), 1.0, 0.1, wrong_jacobian=True))
    res = fgcal.optimize(g, v, check_jacobians=True)
    assert not res.converged and res.termination == "jacobian_check_failed" and "RangeFactor" in res.message


def test_python_factor_errors_reach_the_caller():
    class Failing(fgcal.PythonFactor):
        def evaluate(self, values, jacobians):
            raise ZeroDivisionError("from inside evaluate")

    class WrongShape(fgcal.PythonFactor):
        def evaluate(self, values, jacobians):
            return np.zeros(3), [np.zeros((3, 2))]

    class Unimplemented(fgcal.PythonFactor):
        pass

    p = fgcal.key("p", 0)
    v = fgcal.Values()
    v.insert(p, np.zeros(3))
    noise = fgcal.NoiseModel.isotropic(3, 1.0)
    for factor, error, text in [(Failing([p], noise), ZeroDivisionError, "from inside evaluate"),
                                (WrongShape([p], noise), ValueError, r"WrongShape .*Jacobian 0 \(of p0\) must be 3 x 3"),
                                (Unimplemented([p], noise), RuntimeError, "pure virtual")]:
        g = fgcal.FactorGraph()
        g.add(factor)
        with pytest.raises(error, match=text):
            fgcal.optimize(g, v)


def test_graph_keeps_a_python_factor_alive():
    g, v = fgcal.FactorGraph(), fgcal.Values()
    p = fgcal.key("p", 0)
    truth = np.array([1.0, 2.0, 0.5])
    for a in [np.zeros(3), [5, 0, 0], [0, 5, 0], [0, 0, 5]]:
        g.add(RangeFactor(p, a, np.linalg.norm(truth - a), 0.1))  # no other reference to the Python object
    import gc
    gc.collect()
    v.insert(p, np.array([0.5, 0.5, 0.5]))
    res = fgcal.optimize(g, v)
    assert res.converged and isinstance(g[1], RangeFactor) and g[1].measured == 4.5
    np.testing.assert_allclose(res.values[p], truth, atol=1e-9)


def test_python_factors_on_worker_threads():
    # Enough factors for the optimizer to evaluate them on two threads: each
    # worker takes the GIL to call Python; the answer is the single-thread one.
    n = 4200
    g, v = fgcal.FactorGraph(), fgcal.Values()
    rng = np.random.default_rng(1)
    truth = rng.normal(size=(n, 3))
    for i in range(n):
        k = fgcal.key("p", i)
        g.add(VectorPrior(k, truth[i], 0.1))
        v.insert(k, truth[i] + 0.5)
    one = fgcal.optimize(g, v, threads=1, algorithm="gauss_newton")
    two = fgcal.optimize(g, v, threads=2, algorithm="gauss_newton")
    assert one.converged and two.converged and one.iterations == two.iterations
    for i in range(0, n, 97):
        np.testing.assert_allclose(two.values[fgcal.key("p", i)], truth[i], atol=1e-12)
        np.testing.assert_allclose(two.values[fgcal.key("p", i)], one.values[fgcal.key("p", i)], atol=1e-12)


class VectorPrior(fgcal.PythonFactor):
    def __init__(self, key, z, sigma):
        super().__init__([key], fgcal.NoiseModel.isotropic(len(z), sigma))
        self.z = z

    def evaluate(self, values, jacobians):
        return values[0] - self.z, [np.eye(len(self.z))]


def test_optimize_releases_the_gil():
    n = 3000
    truth, prior, edges, initial = pose_graph(n, seed=5)
    graph, values = fgcal.FactorGraph(), fgcal.Values()
    for i, T in enumerate(initial):
        values.insert(fgcal.key("x", i), T)
    graph.add(fgcal.PriorFactorSE3(fgcal.key("x", 0), prior[2], fgcal.NoiseModel.diagonal(prior[3])))
    for _, a, b, Z, s, k in edges:
        graph.add(fgcal.RelativePoseFactor(fgcal.key("x", a), fgcal.key("x", b), Z, fgcal.NoiseModel.diagonal(s)))
    assert runs_without_gil(fgcal.optimize, graph, values)
    assert not runs_without_gil(sum, range(3_000_000))  # the check itself: a call that keeps the GIL


def test_import_needs_no_numpy():
    # A Python without numpy (like a pyenv python3 first on PATH) imports the
    # module and reads its version, the CMake project version.
    code = "import sys; sys.modules['numpy'] = None; import fgcal; print(fgcal.__version__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == env_path("FGCAL_PROJECT_VERSION")
