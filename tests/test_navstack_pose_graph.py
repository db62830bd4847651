"""navstack.pose_graph: SE(2) errors, the analytic Jacobian, loop closure by least squares."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navstack.pose_graph import PoseGraph, compose, relative


def square(n_side=10, size=4.0):
    corners = [(0, 0), (size, 0), (size, size), (0, size)]
    out = []
    for side in range(4):
        a, b = np.array(corners[side]), np.array(corners[(side + 1) % 4])
        for f in range(n_side):
            p = a + (b - a) * f / n_side
            out.append((float(p[0]), float(p[1]), math.remainder(math.pi / 2 * side, 2 * math.pi)))
    return out


def chain(truth, rng, sigma=(0.02, 0.02, 0.01)):
    g = PoseGraph()
    est = truth[0]
    g.add_node(est)
    info = [1 / s**2 for s in sigma]
    for k in range(1, len(truth)):
        z = relative(truth[k - 1], truth[k])
        z = tuple(v + rng.normal(0, s) for v, s in zip(z, sigma))
        est = compose(est, z)
        g.add_node(est)
        g.add_edge(k - 1, k, z, info)
    return g


def rms(g, truth):
    return float(np.sqrt(np.mean([(p[0] - t[0]) ** 2 + (p[1] - t[1]) ** 2 for p, t in zip(g.poses, truth)])))


def test_relative_and_compose_are_inverse():
    a, b = (1.0, 2.0, 0.7), (-0.5, 3.0, -2.9)
    assert compose(a, relative(a, b)) == pytest.approx(b)
    assert relative(a, compose(a, (0.3, -0.1, 3.0))) == pytest.approx((0.3, -0.1, 3.0))


def test_the_jacobian_matches_finite_differences():
    rng = np.random.default_rng(0)
    truth = square(4)
    g = chain(truth, rng)
    g.add_edge(len(truth) - 1, 0, relative(truth[-1], truth[0]), [[400, 50, 0], [50, 300, 10], [0, 10, 900]], "loop")
    # the errors as optimize() builds them, differentiated numerically
    Ei = np.array([e.i for e in g.edges])
    Ej = np.array([e.j for e in g.edges])
    Z = np.array([e.z for e in g.edges])
    W = g._whiteners()
    X = g.poses + rng.normal(0, 0.05, g.poses.shape)

    def f(x):
        e, _ = g._errors(x.reshape(-1, 3), Ei, Ej, Z)
        return np.einsum("eab,eb->ea", W, e).ravel()

    num = np.zeros((3 * len(g.edges), X.size))
    for k in range(X.size):
        d = np.zeros(X.size)
        d[k] = 1e-6
        num[:, k] = (f(X.ravel() + d) - f(X.ravel() - d)) / 2e-6
    # the analytic one, for all nodes free
    g.fixed = set()
    captured = {}
    import navstack.pose_graph as pg

    real = pg.least_squares

    def spy(fun, x0, jac, **kw):
        captured["J"] = jac(X.ravel()).toarray()
        return real(fun, x0, jac=jac, **kw)

    pg.least_squares = spy
    try:
        g.optimize(max_iterations=1)
    finally:
        pg.least_squares = real
    assert np.allclose(captured["J"], num, atol=1e-5)


def test_a_loop_closure_pulls_the_drifted_chain_back():
    rng = np.random.default_rng(1)
    truth = square()
    g = chain(truth, rng)
    end = len(truth) - 1
    before = math.dist(g.pose(end)[:2], truth[end][:2])
    g.add_edge(len(truth) - 1, 0, relative(truth[-1], truth[0]), [1e4, 1e4, 1e4], "loop")
    res = g.optimize()
    assert res.success and res.cost_after < 0.01 * res.cost_before
    assert g.pose(0) == truth[0]  # the first node is fixed
    after = math.dist(g.pose(end)[:2], truth[end][:2])
    assert before > 0.2 and after < 0.02
    # the end meets the start as the loop edge says
    assert relative(g.pose(len(truth) - 1), g.pose(0)) == pytest.approx(relative(truth[-1], truth[0]), abs=0.01)


def test_consistent_edges_are_met_exactly_and_a_robust_loss_resists_a_bad_edge():
    truth = square(5)
    g = PoseGraph()
    for k, p in enumerate(truth):
        g.add_node((p[0] + 0.3 * (k > 0), p[1] - 0.2 * (k > 0), p[2] + 0.1 * (k > 0)))
    for k in range(1, len(truth)):
        g.add_edge(k - 1, k, relative(truth[k - 1], truth[k]), [100, 100, 100])
    g.add_edge(len(truth) - 1, 0, relative(truth[-1], truth[0]), [100, 100, 100], "loop")
    g.optimize()
    d = g.poses - np.asarray(truth)
    d[:, 2] = np.remainder(d[:, 2] + np.pi, 2 * np.pi) - np.pi
    assert np.abs(d).max() < 1e-4
    # a wrong loop edge, 1 m off: a Cauchy loss keeps the chain near the truth
    g.add_edge(10, 0, compose(relative(truth[10], truth[0]), (1.0, 0.0, 0.0)), [1e4, 1e4, 1e4], "loop")
    g.optimize(loss="cauchy", f_scale=1.0)
    assert rms(g, truth) < 0.05


def test_bad_edges_are_refused():
    g = PoseGraph()
    g.add_node((0, 0, 0))
    with pytest.raises(ValueError):
        g.add_edge(0, 1, (1, 0, 0), [1, 1, 1])
    g.add_node((1, 0, 0))
    with pytest.raises(ValueError):
        g.add_edge(0, 1, (1, 0, 0), np.eye(2))
    assert g.optimize().success


def test_direction_links_hold_a_drifting_chain_to_one_shared_direction():
    # A straight corridor: every relative edge turns 0.5 degrees too far (a drift); each
    # node also sees the walls, which say its heading is 0.2 rad from their direction.
    n, drift = 30, math.radians(0.5)
    truth = [(0.2 * k, 0.0, 0.3) for k in range(n)]
    g = PoseGraph()
    for p in truth:
        g.add_node(p)
    for k in range(1, n):
        z = relative(truth[k - 1], truth[k])
        g.add_edge(k - 1, k, (z[0], z[1], z[2] + drift), [1e4, 1e4, (1 / math.radians(0.3)) ** 2])
    g.optimize()
    assert abs(g.pose(n - 1)[2] - 0.3) > math.radians(10)  # the chain alone turns away
    for k in range(n):
        g.add_direction(k, -0.2, math.radians(0.2))
    assert g.direction == 0.0  # a first guess; the optimisation finds the walls' direction
    g.optimize()
    assert g.direction == pytest.approx(0.5, abs=math.radians(0.25))
    yaw_err = [abs(math.remainder(g.pose(k)[2] - 0.3, 2 * math.pi)) for k in range(n)]
    assert max(yaw_err) < math.radians(3) and np.mean(yaw_err) < math.radians(1.5)


def test_an_edge_on_the_heading_alone_leaves_the_position_free():
    g = PoseGraph()
    g.add_node((0, 0, 0))
    g.add_node((1.0, 0.5, 0.2))
    g.add_edge(0, 1, (0.0, 0.0, 0.1), np.diag([0.0, 0.0, 1e4]), "gyro")
    g.add_edge(0, 1, (1.0, 0.0, 0.3), np.diag([1e4, 1e4, 0.0]), "position")
    assert g.optimize().success
    assert g.pose(1) == pytest.approx((math.cos(0.0) * 1.0, 0.0, 0.1), abs=1e-4)
    with pytest.raises(ValueError):
        g.add_direction(2, 0.0, 0.1)
    with pytest.raises(ValueError):
        g.add_direction(1, 0.0, 0.0)
