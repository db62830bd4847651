"""A 2-D pose graph: keyframe poses joined by relative SE(2) constraints, least squares.

Node ``i`` is a pose ``X_i = (x [m], y [m], yaw [rad])`` in the map frame. An edge
``(i, j, z, info)`` says that ``X_j`` seen from ``X_i`` is ``z`` (the relative pose
``X_i^-1 * X_j``), with ``info`` the 3x3 information matrix (the inverse covariance of z,
units 1/m^2 and 1/rad^2). The error of an edge is ``z^-1 * (X_i^-1 * X_j)`` as a vector
(translation in z's frame, angle wrapped), whitened by the Cholesky factor of ``info``;
:meth:`PoseGraph.optimize` minimises the sum of their squares with
``scipy.optimize.least_squares`` and an analytic sparse Jacobian (each edge touches six
parameters), node 0 (or every node in ``fixed``) held still: it fixes the gauge.

A **direction link** ``(j, z, sigma)`` says that node j's heading is ``z`` [rad] from
the graph's :attr:`PoseGraph.direction`, one unknown angle shared by all such links and
estimated with the nodes (the walls' direction in the map, seen from each keyframe: what
every sighting agrees on, not the first sighting alone).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import least_squares


def relative(a, b) -> tuple:
    """b expressed in a's frame: a^-1 * b, for poses (x [m], y [m], yaw [rad])."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], 2 * math.pi))


def compose(a, b) -> tuple:
    """a * b: pose b, given in a's frame, in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], math.remainder(a[2] + b[2], 2 * math.pi))


def _sqrt_information(info: np.ndarray) -> np.ndarray:
    """W with W^T W = info: the Cholesky factor's transpose, or for an edge that constrains
    only some directions (a heading-only link: zero information along x and y), the
    eigenvectors scaled by the square roots of their eigenvalues."""
    try:
        return np.linalg.cholesky(info).T
    except np.linalg.LinAlgError:
        values, vectors = np.linalg.eigh(info)
        return np.sqrt(np.clip(values, 0.0, None))[:, None] * vectors.T


@dataclass
class Edge:
    i: int
    j: int
    z: tuple  # X_i^-1 X_j measured (x [m], y [m], yaw [rad])
    info: np.ndarray  # (3, 3) information matrix
    kind: str = "odom"  # odom, match, loop: for bookkeeping only


@dataclass
class DirectionLink:
    j: int
    z: float  # X_j's heading less the graph's direction [rad]
    sigma: float  # [rad]


@dataclass
class OptimizeResult:
    cost_before: float  # 0.5 * sum of squared whitened errors
    cost_after: float
    iterations: int
    success: bool


class PoseGraph:
    """Nodes (keyframe poses) and edges (relative constraints); node 0 fixed by default."""

    def __init__(self) -> None:
        self._poses: list[tuple] = []
        self.edges: list[Edge] = []
        self.fixed: set[int] = {0}
        self.directions: list[DirectionLink] = []
        self.direction = 0.0  # the direction links' shared angle [rad]

    def __len__(self) -> int:
        return len(self._poses)

    def add_node(self, pose) -> int:
        """Add a node at ``pose`` (x [m], y [m], yaw [rad]); returns its index."""
        self._poses.append(tuple(float(v) for v in pose))
        return len(self._poses) - 1

    def add_edge(self, i: int, j: int, z, info, kind: str = "odom") -> Edge:
        """Constrain X_i^-1 X_j to ``z`` with ``info`` (3x3, or 3 diagonal values)."""
        n = len(self._poses)
        if not (0 <= i < n and 0 <= j < n) or i == j:
            raise ValueError(f"edge ({i}, {j}) needs two distinct nodes among {n}")
        info = np.asarray(info, dtype=np.float64)
        info = np.diag(info) if info.ndim == 1 else info
        if info.shape != (3, 3):
            raise ValueError(f"information matrix must be 3x3, got {info.shape}")
        e = Edge(i, j, tuple(float(v) for v in z), info, kind)
        self.edges.append(e)
        return e

    def add_direction(self, j: int, z: float, sigma: float) -> DirectionLink:
        """Constrain node j's heading to :attr:`direction` + ``z`` [rad], within ``sigma``."""
        if not 0 <= j < len(self._poses):
            raise ValueError(f"direction link to node {j}: the graph has {len(self._poses)} nodes")
        if not sigma > 0:
            raise ValueError(f"a direction link's sigma must be positive, not {sigma}")
        link = DirectionLink(j, float(z), float(sigma))
        self.directions.append(link)
        return link

    def pose(self, i: int) -> tuple:
        return self._poses[i]

    def set_pose(self, i: int, pose) -> None:
        self._poses[i] = tuple(float(v) for v in pose)

    @property
    def poses(self) -> np.ndarray:
        """(N, 3) current estimates."""
        return np.asarray(self._poses, dtype=np.float64).reshape(-1, 3)

    # -- least squares -------------------------------------------------------------------------
    def _whiteners(self) -> np.ndarray:
        # sqrt information: L^T with L L^T = info, so ||L^T e||^2 = e^T info e
        return np.stack([_sqrt_information(e.info) for e in self.edges])

    def _errors(self, X: np.ndarray, Ei: np.ndarray, Ej: np.ndarray, Z: np.ndarray):
        """Per edge: the error vector (E, 3) and the pieces of its Jacobian."""
        xi, xj = X[Ei], X[Ej]
        ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
        cz, sz = np.cos(Z[:, 2]), np.sin(Z[:, 2])
        dx, dy = xj[:, 0] - xi[:, 0], xj[:, 1] - xi[:, 1]
        # X_i^-1 X_j translation, then into z's frame
        ux, uy = ci * dx + si * dy, -si * dx + ci * dy
        ex = cz * (ux - Z[:, 0]) + sz * (uy - Z[:, 1])
        ey = -sz * (ux - Z[:, 0]) + cz * (uy - Z[:, 1])
        et = np.remainder(xj[:, 2] - xi[:, 2] - Z[:, 2] + np.pi, 2 * np.pi) - np.pi
        return np.column_stack([ex, ey, et]), (ci, si, cz, sz, dx, dy)

    def optimize(
        self, max_iterations: int = 50, loss: str = "linear", f_scale: float = 3.0, tol: float = 1e-8
    ) -> OptimizeResult:
        """Minimise the whitened errors over the free nodes (in place).

        Args:
            max_iterations: least_squares' max_nfev
            loss: least_squares' loss ("linear"; "huber" or "cauchy" against bad edges)
            f_scale: the robust loss's inlier scale, in standard deviations
            tol: ftol and xtol
        """
        n = len(self._poses)
        if n < 2 or not self.edges:
            return OptimizeResult(0.0, 0.0, 0, True)
        free = np.array([k for k in range(n) if k not in self.fixed], dtype=np.int64)
        col = -np.ones(n, dtype=np.int64)
        col[free] = np.arange(len(free))  # node -> its block of 3 columns
        Ei = np.array([e.i for e in self.edges])
        Ej = np.array([e.j for e in self.edges])
        Z = np.array([e.z for e in self.edges])
        W = self._whiteners()  # (E, 3, 3)
        X0 = self.poses
        # the direction links: their nodes, headings and sigmas; the shared angle is the last parameter
        Dj = np.array([d.j for d in self.directions], dtype=np.int64)
        Dz = np.array([d.z for d in self.directions])
        Ds = np.array([d.sigma for d in self.directions])
        D, F = len(Dj), len(free)

        def unpack(v):
            X = X0.copy()
            X[free] = v[: 3 * F].reshape(-1, 3)
            return X

        def fun(v):
            e, _ = self._errors(unpack(v), Ei, Ej, Z)
            r = np.einsum("eab,eb->ea", W, e).ravel()
            if not D:
                return r
            yaw = unpack(v)[Dj, 2]
            return np.concatenate([r, (np.remainder(yaw - v[-1] - Dz + np.pi, 2 * np.pi) - np.pi) / Ds])

        # the Jacobian's sparsity: rows 3e..3e+2 against the 3 columns of node i and of j
        E = len(self.edges)
        rows_blk = (3 * np.arange(E))[:, None, None] + np.arange(3)[None, :, None]  # (E, 3, 1)

        def jac(v):
            X = unpack(v)
            _, (ci, si, cz, sz, dx, dy) = self._errors(X, Ei, Ej, Z)
            # d(u)/d(t_j) = R_i^T ; d(u)/d(t_i) = -R_i^T ; d(u)/d(yaw_i) = dR_i^T/dyaw (t_j - t_i)
            Rz = np.stack([np.stack([cz, sz], -1), np.stack([-sz, cz], -1)], -2)  # R_z^T (E, 2, 2)
            RiT = np.stack([np.stack([ci, si], -1), np.stack([-si, ci], -1)], -2)  # R_i^T
            dRiT = np.column_stack([-si * dx + ci * dy, -ci * dx - si * dy])  # (E, 2)
            Jt_j = Rz @ RiT  # (E, 2, 2)
            Ji = np.zeros((E, 3, 3))
            Jj = np.zeros((E, 3, 3))
            Ji[:, :2, :2] = -Jt_j
            Ji[:, :2, 2] = np.einsum("eab,eb->ea", Rz, dRiT)
            Ji[:, 2, 2] = -1.0
            Jj[:, :2, :2] = Jt_j
            Jj[:, 2, 2] = 1.0
            Ji, Jj = W @ Ji, W @ Jj
            data, rr, cc = [], [], []
            for blk, nodes in ((Ji, Ei), (Jj, Ej)):
                c = col[nodes]
                ok = c >= 0  # fixed nodes: no columns
                data.append(blk[ok].ravel())
                rr.append(np.broadcast_to(rows_blk[ok], (ok.sum(), 3, 3)).ravel())
                cc.append((3 * c[ok][:, None, None] + np.arange(3)[None, None, :]).repeat(3, 1).ravel())
            if D:  # d/d(yaw_j) = 1 / sigma, d/d(direction) = -1 / sigma
                c = col[Dj]
                ok = c >= 0
                data += [1 / Ds[ok], -1 / Ds]
                rr += [3 * E + np.arange(D)[ok], 3 * E + np.arange(D)]
                cc += [3 * c[ok] + 2, np.full(D, 3 * F)]
            return sparse.csr_matrix(
                (np.concatenate(data), (np.concatenate(rr), np.concatenate(cc))), shape=(3 * E + D, 3 * F + (D > 0))
            )

        v0 = np.concatenate([X0[free].ravel(), [self.direction] if D else []])
        cost0 = 0.5 * float(np.sum(fun(v0) ** 2))
        if len(free) == 0:
            return OptimizeResult(cost0, cost0, 0, True)
        sol = least_squares(
            fun,
            v0,
            jac=jac,
            method="trf",
            loss=loss,
            f_scale=f_scale,
            ftol=tol,
            xtol=tol,
            gtol=tol,
            max_nfev=max_iterations,
            x_scale="jac",
            tr_solver="lsmr",
        )
        X = unpack(sol.x)
        X[:, 2] = np.remainder(X[:, 2] + np.pi, 2 * np.pi) - np.pi
        self._poses = [tuple(map(float, p)) for p in X]
        if D:
            self.direction = math.remainder(float(sol.x[-1]), 2 * math.pi)
        cost1 = 0.5 * float(np.sum(fun(sol.x) ** 2))
        return OptimizeResult(cost0, cost1, int(sol.nfev), bool(sol.success))
