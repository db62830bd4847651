"""How good is a built map: align it to the truth, then precision and recall of occupied cells.

The truth is the simulator's occupancy at the lidar's height (:func:`truth_grid`). A built
map is in its own frame (the robot's start), so it is first aligned: a search over x, y and
yaw that maximises the overlap of its occupied cells with the truth's, coarse to fine
(correlative matching: for each yaw, one FFT correlation gives every translation at once;
the best few are refined at full resolution, then polished continuously). Then

* precision: the built occupied cells within ``tolerance`` (10 cm) of a true occupied cell;
* recall: the true occupied cells a lidar can see (those next to free space: the faces of
  walls and furniture, not their insides) within ``tolerance`` of a built occupied cell.

All lengths in metres, angles in radians (degrees only where printed).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .gridmap import OCCUPIED_MIN, GridMap

TOLERANCE = 0.10  # [m] a cell counts as matched within this distance
COARSE_RES = 0.20  # [m] the first search's cell size
COARSE_YAW = math.radians(2.0)
CANDIDATES = 8  # coarse peaks refined at full resolution


@dataclass
class Alignment:
    """The built map's frame in the truth's frame: p_truth = R(yaw) p_built + (x, y)."""

    x: float
    y: float
    yaw: float
    overlap: float  # mean similarity of the built occupied cells (1: all on true ones)

    def apply(self, pts: np.ndarray) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return pts @ np.array([[c, s], [-s, c]]) + (self.x, self.y)

    def inverse_apply(self, pts: np.ndarray) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return (pts - (self.x, self.y)) @ np.array([[c, -s], [s, c]])


@dataclass
class MapScore:
    precision: float
    recall: float
    alignment: Alignment
    built_occupied: int  # cells
    true_faces: int  # cells
    tolerance: float

    def as_dict(self) -> dict:
        d = asdict(self)
        d["alignment"]["yaw_deg"] = math.degrees(self.alignment.yaw)
        return d


def truth_grid(world, seed: int = 0, height: float | None = None, locations=None, resolution: float = 0.05) -> GridMap:
    """The simulator's occupancy of ``world`` sliced at ``height`` [m] (default: the lidar's)."""
    from .description import load_world
    from .gridmap import build_grid, lidar_height

    spec = load_world(world, seed, locations)
    return build_grid(spec, resolution, lidar_height() if height is None else height)


def occupied_points(gm: GridMap, mask: np.ndarray | None = None) -> np.ndarray:
    """Centres [m] (N x 2) of the occupied cells (value >= 65) of ``gm``, or of ``mask``."""
    m = gm.data >= OCCUPIED_MIN if mask is None else mask
    r, c = np.nonzero(m)
    return np.column_stack([gm.origin[0] + (c + 0.5) * gm.resolution, gm.origin[1] + (r + 0.5) * gm.resolution])


def visible_faces(gm: GridMap) -> np.ndarray:
    """True occupied cells next to (8-neighbour) a free cell: what a lidar can see."""
    import cv2

    occ, free = gm.data == 100, gm.data == 0
    near_free = cv2.dilate(free.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    return occ & near_free


class DistanceField:
    """Distance [m] from any point to the nearest cell of ``mask`` (a grid of ``res`` with
    ``origin``), bilinear between cell centres; ``cap`` beyond the grid."""

    def __init__(self, mask: np.ndarray, res: float, origin, cap: float = 1.0):
        import cv2

        pad = int(math.ceil(cap / res))
        m = np.pad(mask.astype(bool), pad)
        if m.any():
            d = cv2.distanceTransform((~m).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * res
        else:
            d = np.full(m.shape, cap, np.float32)
        self.d = np.minimum(d, cap).astype(np.float64)
        self.res, self.cap = res, cap
        self.origin = (origin[0] - pad * res, origin[1] - pad * res)

    def __call__(self, pts: np.ndarray) -> np.ndarray:
        u = (pts[:, 0] - self.origin[0]) / self.res - 0.5
        v = (pts[:, 1] - self.origin[1]) / self.res - 0.5
        h, w = self.d.shape
        inside = (u >= 0) & (v >= 0) & (u <= w - 1) & (v <= h - 1)
        u, v = np.clip(u, 0, w - 1.000001), np.clip(v, 0, h - 1.000001)
        c0, r0 = u.astype(int), v.astype(int)
        fu, fv = u - c0, v - r0
        d = self.d
        out = (d[r0, c0] * (1 - fu) + d[r0, c0 + 1] * fu) * (1 - fv) + (
            d[r0 + 1, c0] * (1 - fu) + d[r0 + 1, c0 + 1] * fu
        ) * fv
        return np.where(inside, out, self.cap)


def _coarse(mask: np.ndarray, f: int) -> np.ndarray:
    """Max-pool ``mask`` by ``f`` cells (a coarse cell is occupied if any of its cells is)."""
    h, w = mask.shape
    H, W = -(-h // f), -(-w // f)
    m = np.zeros((H * f, W * f), bool)
    m[:h, :w] = mask
    return np.asarray(m.reshape(H, f, W, f).any(axis=(1, 3)))  # an array (numpy's stubs allow a scalar)


def _similarity(mask: np.ndarray, res: float, sigma: float) -> np.ndarray:
    """exp(-d²/2σ²) of the distance d to ``mask``'s cells: 1 on them, falling off around."""
    import cv2

    if not mask.any():
        return np.zeros(mask.shape)
    d = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * res
    return np.exp(-0.5 * (d / sigma) ** 2)


def _correlate(sim: np.ndarray, origin, res: float, pts: np.ndarray, yaw: float):
    """Overlap (mean similarity) of ``pts`` rotated by ``yaw`` for every translation on the
    ``res`` lattice: returns (scores [Hs+Hb, Ws+Wb], translation of index (0, 0) [m], res).
    Index k wraps: k >= size/2-ish stands for a negative shift (see :func:`_shift`)."""
    c, s = math.cos(yaw), math.sin(yaw)
    q = pts @ np.array([[c, s], [-s, c]])
    qmin = q.min(axis=0)
    idx = np.rint((q - qmin) / res).astype(int)
    hb, wb = idx[:, 1].max() + 1, idx[:, 0].max() + 1
    hs, ws = sim.shape
    shape = (hs + hb, ws + wb)
    b = np.bincount(idx[:, 1] * shape[1] + idx[:, 0], minlength=shape[0] * shape[1]).reshape(shape).astype(float)
    a = np.zeros(shape)
    a[:hs, :ws] = sim
    # C[k] = sum_n B[n] S[n + k]: the built cell n lands on truth cell n + k
    corr = np.fft.irfft2(np.fft.rfft2(a) * np.conj(np.fft.rfft2(b)), s=shape) / len(pts)
    t0 = (origin[0] + 0.5 * res - qmin[0], origin[1] + 0.5 * res - qmin[1])
    return corr, t0, hb, wb


def _shift(k: int, size: int, built: int) -> int:
    """The signed shift of wrapped correlation index ``k`` (shifts down to -(built-1))."""
    return k - size if k > size - built else k


def _peaks(corr, t0, res, hb, wb, yaw, n, window=None):
    """The ``n`` best (score, x, y, yaw) of a correlation, at least 0.5 m apart; within
    ``window`` ((x, y), radius) when given."""
    H, W = corr.shape
    rows = np.array([_shift(k, H, hb) for k in range(H)])
    cols = np.array([_shift(k, W, wb) for k in range(W)])
    X = t0[0] + cols[None, :] * res
    Y = t0[1] + rows[:, None] * res
    c = corr.copy()
    if window is not None:
        (wx, wy), rad = window
        c[np.hypot(X - wx, Y - wy) > rad] = -np.inf
    out = []
    for _ in range(n):
        i = int(np.argmax(c))
        r, k = divmod(i, W)
        if not np.isfinite(c[r, k]):
            break
        x, y = float(X[0, k]), float(Y[r, 0])
        out.append((float(c[r, k]), x, y, yaw))
        c[np.hypot(X - x, Y - y) < 0.5] = -np.inf
    return out


def align(built: np.ndarray, truth_occ: np.ndarray, res: float, origin) -> Alignment:
    """The pose of the built map's frame in the truth's that lays the built occupied
    points ``built`` (N x 2, [m]) on the truth's occupied cells ``truth_occ`` (a mask of
    the grid ``res``, ``origin``). Any offset, any yaw."""
    if len(built) == 0 or not truth_occ.any():
        return Alignment(0.0, 0.0, 0.0, 0.0)
    f = max(1, int(round(COARSE_RES / res)))
    cres = res * f
    csim = _similarity(_coarse(truth_occ, f), cres, cres)
    cands = []
    for yaw in np.arange(-math.pi, math.pi, COARSE_YAW):
        corr, t0, hb, wb = _correlate(csim, origin, cres, built, yaw)
        cands += _peaks(corr, t0, cres, hb, wb, float(yaw), 2)
    cands.sort(reverse=True)
    chosen: list[tuple[float, float, float, float]] = []  # (score, x, y, yaw)
    for cand in cands:  # the best few, distinct in yaw or place
        if all(
            abs(_wrap(cand[3] - o[3])) > math.radians(5) or math.hypot(cand[1] - o[1], cand[2] - o[2]) > 0.5
            for o in chosen
        ):
            chosen.append(cand)
        if len(chosen) == CANDIDATES:
            break
    fsim = _similarity(truth_occ, res, res)
    field = DistanceField(truth_occ, res, origin)
    refined = []
    for _, x, y, yaw in chosen:
        fine = []
        for dyaw in np.arange(-1.5, 1.51, 0.5):  # the coarse step is 2°; the polish does the rest
            yy = yaw + math.radians(dyaw)
            corr, t0, hb, wb = _correlate(fsim, origin, res, built, yy)
            fine += _peaks(corr, t0, res, hb, wb, yy, 1, window=((x, y), 2 * cres))
        if fine:
            refined.append(max(fine))
    refined.sort(reverse=True)
    best = None
    for _, x, y, yaw in refined[:3]:
        a = _polish(Alignment(x, y, _wrap(yaw), 0.0), built, field, res)
        if best is None or a.overlap > best.overlap:
            best = a
    return best or Alignment(0.0, 0.0, 0.0, 0.0)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _polish(a: Alignment, pts, field: DistanceField, res: float) -> Alignment:
    """Pattern search on the continuous overlap (Gaussian of the distance, σ = half a cell)."""
    sigma = res / 2

    def overlap(x, y, yaw):
        d = field(Alignment(x, y, yaw, 0).apply(pts))
        return float(np.mean(np.exp(-0.5 * (d / sigma) ** 2)))

    x, y, yaw = a.x, a.y, a.yaw
    best = overlap(x, y, yaw)
    step, ystep = res / 2, math.radians(0.25)
    while step > res / 40:
        moved = False
        for dx, dy, dw in ((step, 0, 0), (-step, 0, 0), (0, step, 0), (0, -step, 0), (0, 0, ystep), (0, 0, -ystep)):
            v = overlap(x + dx, y + dy, yaw + dw)
            if v > best + 1e-12:
                best, x, y, yaw, moved = v, x + dx, y + dy, yaw + dw, True
                break
        if not moved:
            step, ystep = step / 2, ystep / 2
    return Alignment(x, y, _wrap(yaw), best)


def score_maps(
    built: GridMap, truth: GridMap, tolerance: float = TOLERANCE, alignment: Alignment | None = None
) -> MapScore:
    """Align ``built`` to ``truth`` (unless ``alignment`` is given) and score it."""
    pts = occupied_points(built)
    truth_occ = truth.data == 100
    if alignment is None:
        alignment = align(pts, truth_occ, truth.resolution, truth.origin)
    tfield = DistanceField(truth_occ, truth.resolution, truth.origin)
    eps = 1e-6
    precision = float(np.mean(tfield(alignment.apply(pts)) <= tolerance + eps)) if len(pts) else 0.0
    faces = occupied_points(truth, visible_faces(truth))
    bfield = DistanceField(built.data >= OCCUPIED_MIN, built.resolution, built.origin)
    recall = float(np.mean(bfield(alignment.inverse_apply(faces)) <= tolerance + eps)) if len(faces) else 0.0
    return MapScore(precision, recall, alignment, len(pts), len(faces), tolerance)


def overlay_image(built: GridMap, truth: GridMap, score: MapScore, scale: int = 3) -> np.ndarray:
    """An RGB picture (H x W x 3, uint8, north up) of the built map on the truth's cells:
    the truth's free floor white, its occupied cells grey; the built map's occupied cells
    (aligned) green where within the tolerance of a true one, red where not; the true wall
    faces no built cell came near, blue. ``scale`` pixels per cell."""
    h, w = truth.data.shape
    img = np.full((h, w, 3), 205, np.uint8)  # unknown: grey
    img[truth.data == 0] = 255
    img[truth.data == 100] = 150
    res, (ox, oy) = truth.resolution, truth.origin
    faces = occupied_points(truth, visible_faces(truth))
    bfield = DistanceField(built.data >= OCCUPIED_MIN, built.resolution, built.origin)
    missed = faces[bfield(score.alignment.inverse_apply(faces)) > score.tolerance + 1e-6]
    pts = score.alignment.apply(occupied_points(built))
    tfield = DistanceField(truth.data == 100, res, truth.origin)
    good = tfield(pts) <= score.tolerance + 1e-6
    for sel, rgb in ((missed, (40, 90, 230)), (pts[good], (30, 160, 60)), (pts[~good], (220, 40, 40))):
        if not len(sel):
            continue
        c = np.floor((sel[:, 0] - ox) / res).astype(int)
        r = np.floor((sel[:, 1] - oy) / res).astype(int)
        ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        img[r[ok], c[ok]] = rgb
    img = img[::-1]  # row 0 is the lowest y
    return np.repeat(np.repeat(img, scale, axis=0), scale, axis=1)
