"""Segmentation: a frame's pixels turned into object segments (:class:`_Segment`): regions
of one colour, cut where the depth steps, joined over labels, each measured in the map
frame (its base, width profile and the sides that may be out of view)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from . import axis_fit
from .camera import RGBDFrame
from .perception_colour import colour_labels

MIN_PIXELS = 40  # smaller segments are ignored
MAX_RANGE = 4.0  # [m] farther segments are ignored
MAX_UNKNOWN_SIZE = (0.35, 0.60)  # [m] width, height: larger coloured things are structure
OCCLUSION_JUMP = 0.03  # [m] (and 4 % of the range) depth step that separates two objects
DEPTH_NOISE = 0.001  # [m] RMS a true cylinder's surface may deviate from the fitted one
# with exact depth (the rendering's own error is ~0.3 mm)
OCCLUDER_LOOK = 3  # [px] how far beyond a segment's edge an occluder is looked for
LABEL_GAP = 0.10  # [m] a printed label this tall may split an object's colour in two
FOOT_ROWS = 8  # [px] below a segment, where an occluder hiding its foot is looked for
BELOW_ROWS = (3, 4, 5)  # [px] below a segment's lowest pixels, where its surface is looked
#                         for going on down (a label below it) rather than meeting a support


def _occlusion_cuts(lab: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Pixels on the far side of a depth step between two pixels of the same colour."""
    D = np.where(np.isfinite(depth), depth, np.inf)
    cut = np.zeros(lab.shape, bool)
    for axis in (0, 1):
        a = D[:-1, :] if axis == 0 else D[:, :-1]
        b = D[1:, :] if axis == 0 else D[:, 1:]
        la = lab[:-1, :] if axis == 0 else lab[:, :-1]
        lb = lab[1:, :] if axis == 0 else lab[:, 1:]
        with np.errstate(invalid="ignore"):
            jump = (la == lb) & (la > 0) & (np.abs(a - b) > np.maximum(OCCLUSION_JUMP, 0.04 * np.minimum(a, b)))
        if axis == 0:
            cut[1:, :] |= jump & (b > a)
            cut[:-1, :] |= jump & (a > b)
        else:
            cut[:, 1:] |= jump & (b > a)
            cut[:, :-1] |= jump & (a > b)
    return cut


def backproject(frame: RGBDFrame) -> np.ndarray:
    """Map-frame points (H, W, 3) of every pixel (NaN where there is no depth)."""
    k = frame.intrinsics
    h, w = frame.depth.shape
    z = frame.depth.astype(np.float64)
    u = (np.arange(w) - k.cx) / k.fx
    v = (np.arange(h) - k.cy) / k.fy
    cam = np.stack([u[None, :] * z, v[:, None] * z, z], axis=-1)
    R, t = frame.T_map_cam[:3, :3], frame.T_map_cam[:3, 3]
    return cam @ R.T + t


@dataclass
class _Segment:
    """Measurements of one coloured region (internal)."""

    colour: str
    pixels: int
    u: float  # centroid [px]
    v: float
    bbox: tuple[int, int, int, int]
    truncated: dict  # sides cut by the image border
    occluded: dict  # sides hidden by something nearer (right next to it)
    hidden: dict  # sides that may be hidden: something nearer is within
    #                           OCCLUDER_LOOK pixels (past pixels with no depth, or its
    #                           own pixels cut off by an occluder of its colour)
    pts: np.ndarray  # (N, 3) map-frame surface points
    hts: np.ndarray  # (N,) height above the base [m]
    base: float  # support height [m]
    top: float  # highest surface point [m]
    cam_xy: np.ndarray
    ray: np.ndarray  # unit horizontal viewing direction
    lateral: np.ndarray  # (N,) coordinate across the viewing direction [m]
    m_per_px: float  # metres per pixel at the segment
    range: float  # median horizontal distance camera -> surface [m]
    frame: RGBDFrame  # the frame it was measured in
    grid: np.ndarray  # (h, w, 3) map-frame points over the bounding box,
    # NaN outside the segment (image neighbours stay neighbours)
    in_structure: float = 0.0  # share of its pixels in a coloured region of furniture size
    #                                  (its surface going on without a depth step)
    saturation: float = 255.0  # median saturation of its pixels (0..255)
    continued: float = 0.0  # share of its surroundings that continue its surface
    #                                  in colour (measured when it is mostly in a coloured
    #                                  region of furniture size in the image: a patch of it)
    continues_below: bool = False  # its surface goes on straight down below it, in no
    #                                  category's colour: its lowest part is not its base

    @property
    def noise(self) -> float:
        """The depth noise [m] measured on the segment itself: the robust spread of the
        range's second difference between image neighbours (sigma * sqrt(6) for white
        noise; ~0 on any smooth surface), along rows or columns, whichever is smaller (one
        of them usually runs along a cylinder's axis, where the surface is straight)."""
        if not hasattr(self, "_noise"):
            r = np.linalg.norm(self.grid - self.frame.T_map_cam[:3, 3], axis=-1)
            est = []
            for d2 in (r[:, :-2] - 2 * r[:, 1:-1] + r[:, 2:], r[:-2, :] - 2 * r[1:-1, :] + r[2:, :]):
                d2 = d2[np.isfinite(d2)]
                if len(d2) >= 30:
                    est.append(1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6))
            self._noise = min(est) if est else 0.0
        return self._noise

    @property
    def surface_tolerance(self) -> float:
        """How far [m] its points may scatter about a fitted surface: DEPTH_NOISE, or the
        noise measured on it when larger (a real or noisy depth camera)."""
        return max(DEPTH_NOISE, 1.2 * self.noise)

    def axis_candidates(self) -> list[np.ndarray]:
        """Directions its surface normals avoid (a body of revolution's axis, see
        actors/axis_fit.py); computed once."""
        if not hasattr(self, "_axis_dirs"):
            pts, normals = self.normals()
            self._axis_dirs = axis_fit.axis_candidates(pts, normals) if len(pts) >= 20 else []
        return self._axis_dirs

    def normals(self) -> tuple[np.ndarray, np.ndarray]:
        """(points, unit surface normals) of the segment (axis_fit.surface_normals); once."""
        if not hasattr(self, "_normals"):
            self._normals = axis_fit.surface_normals(self.grid)
        return self._normals

    def cut(self, side: str) -> bool:
        """Part of the object is out of view on ``side`` (image border or occluder)."""
        return self.truncated.get(side, False) or self.occluded.get(side, False)

    def may_continue(self, side: str) -> bool:
        """Part of the object may be out of view on ``side``: cut, or something nearer is
        close by (a measurement that must be complete takes this reading of an edge; a
        lower bound, ``cut``)."""
        return self.cut(side) or self.hidden.get(side, False)

    @property
    def height(self) -> float:
        return self.top - self.base

    def band_widths(self, band: float) -> list[tuple[float, float]]:
        """(mid height, width) of the silhouette in height bands of ``band`` [m]."""
        out: list[tuple[float, float]] = []
        if self.height <= 0:
            return out
        n = max(1, int(math.ceil(self.height / band)))
        idx = np.clip((self.hts / band).astype(int), 0, n - 1)
        order = np.argsort(idx, kind="stable")
        idx_s, lat_s = idx[order], self.lateral[order]
        starts = np.searchsorted(idx_s, np.arange(n))
        ends = np.searchsorted(idx_s, np.arange(n), side="right")
        for i in range(n):
            if ends[i] - starts[i] >= 2:
                seg = lat_s[starts[i] : ends[i]]
                out.append(((i + 0.5) * band, float(seg.max() - seg.min()) + self.m_per_px))
        return out


def _measure(
    colour: str, comp: np.ndarray, x0: int, y0: int, P: np.ndarray, depth: np.ndarray, lab: np.ndarray, frame: RGBDFrame
) -> _Segment | None:
    h, w = lab.shape
    ys, xs = np.nonzero(comp)
    ys = ys + y0
    xs = xs + x0
    pts = P[ys, xs]
    ok = np.isfinite(pts).all(axis=1)
    if ok.sum() < MIN_PIXELS // 2:
        return None
    pts = pts[ok]
    low = np.full(w, -1, np.int64)
    np.maximum.at(low, xs, ys)
    cols = np.nonzero(low >= 0)[0]
    m_per_px = float(np.median(depth[ys, xs][ok])) / frame.intrinsics.fx
    base, foot_hidden = _support(low, cols, P, lab, depth, float(np.min(pts[:, 2])))
    cam_xy = frame.T_map_cam[:2, 3]
    rel = pts[:, :2] - cam_xy
    mean = rel.mean(axis=0)
    ray = mean / (np.hypot(*mean) or 1.0)
    perp = np.array([-ray[1], ray[0]])
    lateral = rel @ perp
    rng = float(np.median(rel @ ray))
    x1, y1 = int(xs.max()) + 1, int(ys.max()) + 1
    bx0, by0 = int(xs.min()), int(ys.min())
    trunc = {"left": bx0 <= 0, "right": x1 >= w, "top": by0 <= 0, "bottom": y1 >= h}
    occluded = _occluded_sides(xs, ys, depth, P, base)
    hidden = _occluded_sides(xs, ys, depth, P, base, OCCLUDER_LOOK)
    return _Segment(
        colour=colour,
        pixels=int(len(xs)),
        u=float(xs.mean()),
        v=float(ys.mean()),
        bbox=(bx0, by0, x1, y1),
        truncated=trunc,
        occluded=occluded,
        hidden=hidden,
        pts=pts,
        hts=pts[:, 2] - base,
        base=base,
        top=float(pts[:, 2].max()),
        cam_xy=cam_xy,
        ray=ray,
        lateral=lateral,
        m_per_px=m_per_px,
        range=rng,
        frame=frame,
        grid=_segment_grid(comp, x0, y0, P),
        continues_below=not foot_hidden and _continues_below(low, cols, P, lab, cam_xy, m_per_px),
    )


def _support(
    low: np.ndarray, cols: np.ndarray, P: np.ndarray, lab: np.ndarray, depth: np.ndarray, zmin: float
) -> tuple[float, bool]:
    """The height [m] of what a segment stands on, and whether its foot is hidden.

    The uncoloured pixels 2..4 rows below its lowest pixel in each of ``cols`` (``low``)
    are its support where their median height is within 3 cm below the segment's lowest
    point ``zmin`` (the floor's edge pixels blur it). Else, where the first pixels with a
    depth within FOOT_ROWS below it are nearer by an occlusion jump (in half the columns
    or more), something in front hides its foot: the base is taken at that occluder's top,
    the edge of the table it stands on seen from below (a camera 9 cm above the floor sees
    a bottle on a 0.25 m bench over the bench's edge: without this its base would be put
    at the first visible pixels, 15 cm too high, and the grasp would close on its neck).
    Else ``zmin``, the lowest part in view."""
    h = lab.shape[0]
    below = []
    for dy in (2, 3, 4):
        yy = low[cols] + dy
        inside = yy < h
        cx, cy = cols[inside], yy[inside]
        zz = P[cy, cx, 2]
        below.append(zz[(lab[cy, cx] == 0) & np.isfinite(zz)])
    sup = np.concatenate(below)
    if len(sup) >= 3:
        s = float(np.median(sup))
        if zmin - 0.03 <= s <= zmin + 0.005:
            return s, False
    d_low = depth[low[cols], cols]
    tops = []
    for c, r, d in zip(cols, low[cols], d_low):
        for dy in range(1, FOOT_ROWS + 1):
            if r + dy >= h:
                break
            q = depth[r + dy, c]
            if not np.isfinite(q):
                continue
            if q < d - max(OCCLUSION_JUMP, 0.04 * q):
                tops.append(float(P[r + dy, c, 2]))
                break
            if q < d - 0.5 * OCCLUSION_JUMP:
                break  # nearer, gradually: the floor in front of it
    if len(tops) >= max(2, 0.5 * len(cols)):
        top = float(np.median(tops))
        if top < zmin:
            return top, True
    return zmin, False


def _continues_below(
    low: np.ndarray, cols: np.ndarray, P: np.ndarray, lab: np.ndarray, cam_xy: np.ndarray, m_per_px: float
) -> bool:
    """Does the surface go on straight down below a segment (``low``: its lowest pixel's
    row in each of ``cols``), in no category's colour? A pixel BELOW_ROWS rows lower is
    then about as many pixel heights lower and no nearer; on a support it is at the same
    height and nearer (the floor: 23..35 cm nearer 3..5 rows below a bottle at 1.6 m, the
    camera 9 cm high). So a bottle on a table, seen across it from the low camera, shows
    its cream label under the green above it: the green ends at the label's top."""
    h = lab.shape[0]
    rz, rh = [], []
    for dy in BELOW_ROWS:
        inside = low[cols] + dy < h
        c, r = cols[inside], low[cols][inside]
        q, b = P[r + dy, c], P[r, c]
        ok = (lab[r + dy, c] == 0) & np.isfinite(q).all(axis=1) & np.isfinite(b).all(axis=1)
        if not ok.any():
            continue
        step = dy * m_per_px
        rz.append((q[ok, 2] - b[ok, 2]) / step)
        rh.append((np.hypot(*(q[ok, :2] - cam_xy).T) - np.hypot(*(b[ok, :2] - cam_xy).T)) / step)
    if not rz or sum(len(v) for v in rz) < 0.5 * len(BELOW_ROWS) * len(cols):
        return False
    return bool(np.median(np.concatenate(rz)) < -0.5 and np.median(np.abs(np.concatenate(rh))) < 0.5)


def _segment_grid(comp: np.ndarray, x0: int, y0: int, P: np.ndarray) -> np.ndarray:
    """The segment's points laid out as in the image (NaN off the segment)."""
    h, w = comp.shape
    grid = P[y0 : y0 + h, x0 : x0 + w].copy()
    grid[~comp.astype(bool)] = np.nan
    return grid


def _occluded_sides(
    xs: np.ndarray, ys: np.ndarray, depth: np.ndarray, P: np.ndarray, base: float, look: int = 1
) -> dict[str, bool]:
    """Sides (left, right, top) along which something nearer hides part of the segment:
    on at least a quarter of the rows (columns), the nearest of the ``look`` pixels beyond
    the outermost one is nearer by more than OCCLUSION_JUMP. Rows within 2 cm of the base
    are skipped (the floor in front of the base is nearer there)."""
    h, w = depth.shape
    out = {}
    for side in ("left", "right", "top"):
        if side == "top":
            key, other, step, lim = xs, ys, -1, 0
        else:
            key, other = ys, xs
            step, lim = (-1, 0) if side == "left" else (1, w - 1)
        k0 = int(key.min())
        edge = np.full(int(key.max()) - k0 + 1, -1 if step > 0 else 1 << 30, np.int64)
        (np.maximum if step > 0 else np.minimum).at(edge, key - k0, other)
        ks = np.arange(len(edge)) + k0
        inside = (edge >= 0) & (edge < (1 << 30)) & (edge != lim)
        ks, edge = ks[inside], edge[inside]
        ex, ey = (ks, edge) if side == "top" else (edge, ks)
        keep = P[ey, ex, 2] - base > 0.02
        if keep.sum() < 3:
            out[side] = False
            continue
        d_edge = depth[ey, ex][keep]
        d_next = np.full(len(d_edge), np.inf)
        for k in range(1, look + 1):
            if side == "top":
                nx, ny = ks, np.maximum(edge - k, 0)
            else:
                nx, ny = np.clip(edge + k * step, 0, w - 1), ks
            d_next = np.fmin(d_next, depth[ny, nx][keep])  # (NaN: no depth, skipped)
        with np.errstate(invalid="ignore"):
            nearer = np.isfinite(d_next) & (d_next < d_edge - OCCLUSION_JUMP)
        out[side] = bool(nearer.mean() >= 0.25)
    return out


def _components(mask: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """(x0, y0, roi) of each 4-connected region of ``mask`` of MIN_PIXELS or more."""
    n, cc, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=4)
    out = []
    for j in range(1, n):
        x0, y0, bw, bh, area = (int(a) for a in stats[j])
        if area >= MIN_PIXELS:
            out.append((x0, y0, cc[y0 : y0 + bh, x0 : x0 + bw] == j))
    return out


def _bridge_labels(mask: np.ndarray, lab: np.ndarray, depth: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``mask`` (one colour) with the uncoloured bands that split an object joined in: a
    printed label (a cream band round a bottle) leaves two regions of its colour. Two
    regions are joined when they are at most LABEL_GAP apart in space, and the pixels
    between them (inside their joint convex hull) are uncoloured, at their depth and above
    their lowest point (not the floor behind); only when that makes one region."""
    comps = _components(mask)
    if len(comps) < 2:
        return mask
    h, w = mask.shape
    full, samples = [], []
    for x0, y0, roi in comps:
        m = np.zeros((h, w), bool)
        m[y0 : y0 + roi.shape[0], x0 : x0 + roi.shape[1]] = roi
        pts = P[m]
        pts = pts[np.isfinite(pts).all(axis=1)]
        full.append(m)
        samples.append(pts[np.linspace(0, len(pts) - 1, min(len(pts), 150)).astype(int)] if len(pts) else pts)
    out = mask.copy()
    joined: set[int] = set()
    for i in range(len(comps)):
        for j in range(i + 1, len(comps)):
            if i in joined or j in joined or not len(samples[i]) or not len(samples[j]):
                continue
            a, b = samples[i], samples[j]
            gap = float(np.min(np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)))
            if gap > LABEL_GAP:
                continue
            union = full[i] | full[j]
            ys, xs = np.nonzero(union)
            hull = cv2.convexHull(np.stack([xs, ys], axis=1).astype(np.int32))
            inside = np.zeros((h, w), np.uint8)
            cv2.fillConvexPoly(inside, hull, 1)
            d = depth[union]
            d = d[np.isfinite(d)]
            lo_z = float(min(a[:, 2].min(), b[:, 2].min()))
            with np.errstate(invalid="ignore"):
                fill = (
                    (inside > 0)
                    & ~union
                    & (lab == 0)
                    & (depth > d.min() - 0.05)
                    & (depth < d.max() + 0.05)
                    & (P[:, :, 2] > lo_z + 0.01)
                )
            merged = union | fill
            if len(_components(merged)) == 1 and int(fill.sum()) > 0:
                out |= merged
                joined.update((i, j))
    return out


def _depth_steps(coloured: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Coloured pixels on either side of a depth step (OCCLUSION_JUMP) to a coloured
    neighbour, along rows, columns and diagonals: where one thing stands in front of
    another. Without them, an object before furniture of a similar colour is one region with
    it in the image, taken for a part of the furniture and not seen."""
    D = np.where(np.isfinite(depth), depth, np.inf)
    step = np.zeros(coloured.shape, bool)
    h, w = coloured.shape
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        a_sl = (slice(0, h - dy), slice(max(0, -dx), w - max(0, dx)))
        b_sl = (slice(dy, h), slice(max(0, dx), w - max(0, -dx)))
        a, b = D[a_sl], D[b_sl]
        with np.errstate(invalid="ignore"):
            far_apart = np.abs(a - b) > np.maximum(OCCLUSION_JUMP, 0.04 * np.minimum(a, b))
            jump = coloured[a_sl] & coloured[b_sl] & far_apart
        step[a_sl] |= jump
        step[b_sl] |= jump
    return step


def _structure(coloured: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Pixels of regions of ``coloured`` (of any colours together) larger than
    MAX_UNKNOWN_SIZE: furniture and walls. Light and noise break a brown bench into small
    patches of two hues; none of them is an object."""
    big = np.zeros(coloured.shape, bool)
    for x0, y0, roi in _components(coloured):
        pts = P[y0 : y0 + roi.shape[0], x0 : x0 + roi.shape[1]][roi]
        pts = pts[np.isfinite(pts).all(axis=1)]
        if len(pts) < MIN_PIXELS:
            continue
        lo, hi = np.percentile(pts, (2, 98), axis=0)
        if max(hi[0] - lo[0], hi[1] - lo[1]) > MAX_UNKNOWN_SIZE[0] or hi[2] - lo[2] > MAX_UNKNOWN_SIZE[1]:
            big[y0 : y0 + roi.shape[0], x0 : x0 + roi.shape[1]] |= roi
    return big


def _continued_share(roi: np.ndarray, x0: int, y0: int, lab: np.ndarray, depth: np.ndarray, pad: int = 2) -> float:
    """Share of the pixels just around a segment that are coloured and continue its
    surface without a depth step: high for a patch of something larger (light breaks a
    table into patches of two hues, one of them a category's), low for an object, which
    stands out against the floor or in front of what is behind it."""
    h, w = lab.shape
    bh, bw = roi.shape
    Y0, X0, Y1, X1 = max(0, y0 - pad), max(0, x0 - pad), min(h, y0 + bh + pad), min(w, x0 + bw + pad)
    inside = np.zeros((Y1 - Y0, X1 - X0), np.uint8)
    inside[y0 - Y0 : y0 - Y0 + bh, x0 - X0 : x0 - X0 + bw] = roi
    kernel = np.ones((2 * pad + 1, 2 * pad + 1), np.uint8)
    ring = (cv2.dilate(inside, kernel) > 0) & (inside == 0)
    if not ring.any():
        return 0.0
    d = depth[Y0:Y1, X0:X1]
    own = np.where((inside > 0) & np.isfinite(d), d, np.nan).astype(np.float32)
    near_max = cv2.dilate(np.nan_to_num(own, nan=0.0), kernel)  # its depths nearby
    near_min = cv2.erode(np.nan_to_num(own, nan=np.inf), kernel)
    tol = np.maximum(0.02, 0.03 * d)
    with np.errstate(invalid="ignore"):
        same = (d >= near_min - tol) & (d <= near_max + tol)
    return float(((lab[Y0:Y1, X0:X1] > 0) & same)[ring].mean())


def _segments(frame: RGBDFrame, P: np.ndarray, appearances=()) -> list[_Segment]:
    hsv = cv2.cvtColor(frame.bgr, cv2.COLOR_BGR2HSV)
    lab, names = colour_labels(frame.bgr, appearances, hsv)
    cut = _occlusion_cuts(lab, frame.depth)
    coloured = lab > 0
    flat = _structure(coloured, P)  # patches of furniture: see continued
    structure = _structure(coloured & ~_depth_steps(coloured, frame.depth), P)
    saturation = hsv[:, :, 1]
    out = []
    for i, name in enumerate(names, 1):
        m = (lab == i) & ~cut
        if int(m.sum()) < MIN_PIXELS:
            continue
        m = _bridge_labels(m, lab, frame.depth, P)
        for x0, y0, roi in _components(m):
            bh, bw = roi.shape
            # fill holes left by specular highlights, but only where the depth agrees
            contours, _ = cv2.findContours(roi.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            filled = np.zeros(roi.shape, np.uint8)
            cv2.drawContours(filled, contours, -1, 1, thickness=cv2.FILLED)
            holes = (filled > 0) & ~roi
            d = frame.depth[y0 : y0 + bh, x0 : x0 + bw]
            if holes.any() and np.isfinite(d[roi]).any():  # (no depth at all: nothing to fill)
                dm = float(np.nanmedian(d[roi]))
                roi = roi | (holes & (np.abs(d - dm) < 0.1))
            seg = _measure(name, roi, x0, y0, P, frame.depth, lab, frame)
            if seg is not None and seg.range <= MAX_RANGE:
                # structure: what it is one region with where the depth goes on; the
                # patch test looks at the regions of colour in the image (a patch of a
                # bench may be cut from the rest of it by a step in its surface)
                seg.in_structure = float(structure[y0 : y0 + bh, x0 : x0 + bw][roi].mean())
                own = roi & (lab[y0 : y0 + bh, x0 : x0 + bw] == i)  # not a label it was bridged over
                seg.saturation = float(np.median(saturation[y0 : y0 + bh, x0 : x0 + bw][own])) if own.any() else 0.0
                if float(flat[y0 : y0 + bh, x0 : x0 + bw][roi].mean()) > 0.5:
                    seg.continued = _continued_share(roi, x0, y0, lab, frame.depth)
                out.append(seg)
    return out
