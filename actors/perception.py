"""Perception: find cans, bottles and other objects in RGB-D frames with OpenCV.

Pipeline (one frame, :func:`detect`; ``docs/perception.md`` explains each step):

1. **Colour**: every saturated pixel gets a named colour of :data:`PALETTE` (by hue).
2. **Segments**: connected regions of one colour; where two regions of the same colour
   overlap in the image, the depth jump between them cuts the farther one off.
3. **Geometry**: each segment's pixels are back-projected with the depth and the
   intrinsics and put into the map frame with the camera pose of the frame. The support
   height (the floor) comes from the pixels just below the segment; heights are measured
   from it. The object's metric width profile is measured in height bands, across the
   viewing direction.
4. **Category**: an :class:`Appearance` (colour + profile of radius against height) whose
   colour matches is checked against the measured width profile, the height the model
   would show in this image (projected from the fitted axis: the image border may hide a
   bottle's neck), and the fit of a cylinder of its body radius to the body's surface
   points (a flat face or a poor fit rejects it). The best match above
   ``min_confidence`` names the segment; otherwise it is ``unknown`` (a distractor).
5. **Position**: the object's vertical axis is the centre of the circle of the known body
   radius fitted (least squares, robust) to the visible surface points of the body: the
   visible-surface centroid lies a few cm in front of the axis, the fit does not.
   ``z`` is the base (the support height).

Actors (``Perception`` SubSystem; the camera streams are in ``actors/camera.py``):
``object_glance``, ``find_object``, ``pic_find``, ``get_found``, ``measure_distance``
(stream), ``measure_center`` (stream). Detections are plain dicts (see :func:`detect`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterator

import cv2
import numpy as np

import categories
from bt_engine import ActorbtError, SubSystem, actor

from . import axis_fit
from .camera import Camera, RGBDFrame

# ----------------------------------------------------------------------------- appearance
#: Named colours by OpenCV hue (0..180). A pixel has a colour when saturated enough.
PALETTE: dict[str, tuple[tuple[int, int], ...]] = {
    "red": ((0, 8), (165, 181)),
    "orange": ((8, 22),),
    "yellow": ((22, 35),),
    "green": ((35, 85),),
    "cyan": ((85, 100),),
    "blue": ((100, 130),),
    "purple": ((130, 165),),
}
MIN_SATURATION = 80     # HSV S (0..255): floor, walls and shadows are below ~40
MIN_VALUE = 20          # HSV V (0..255): darker pixels have no reliable hue

MIN_PIXELS = 40         # smaller segments are ignored
MAX_RANGE = 4.0         # [m] farther segments are ignored
MAX_UNKNOWN_SIZE = (0.35, 0.60)   # [m] width, height: larger coloured things are structure
OCCLUSION_JUMP = 0.03   # [m] (and 4 % of the range) depth step that separates two objects
FIT_POINTS = 400        # surface points used to fit an axis (an even subsample)
MIN_VISIBLE_WIDTH = 0.5 # fraction of its body an object cut by the image border or an
                        # occluder must show to be classified (a sliver fits any cylinder)
GRAZING = 0.3           # a face seen at less than ~17 degrees (sin) is not measured
DEPTH_NOISE = 0.001     # [m] RMS a true cylinder's surface may deviate from the fitted one
                        # with exact depth (the rendering's own error is ~0.3 mm)
SATURATION_SHARE = 0.55 # a category's segments keep this share of its saturation or more
#                         (light and shade change the value more; brown furniture whose
#                         hue drifts into a category's keeps about 0.45 of its saturation)
PATCH_SHARE = 0.4       # a segment whose surroundings continue it in colour this much
#                         (or more) is a patch of something larger
OCCLUDER_LOOK = 3       # [px] how far beyond a segment's edge an occluder is looked for
GRAZING_SLACK = 0.10    # [m] a face seen at a grazing angle may look this much longer than
#                         the box's longest side (depth noise along the view); no more
LABEL_GAP = 0.10        # [m] a printed label this tall may split an object's colour in two
UPRIGHT_TILT = math.radians(12)   # an axis nearer the vertical than this is standing
LYING_TILT = math.radians(65)     # ... farther than this, lying; between them, leaning


class PerceptionError(ActorbtError):
    """A perception request could not be served (no camera frames, bad category)."""


@dataclass(frozen=True)
class Appearance:
    """How a category looks: a colour, and either a body of revolution standing upright
    (``sections``) or a box (``box``: its x, y, z sizes [m]).

    ``sections`` go bottom-up: ``(top height above the base [m], radius [m])``; the first
    section is the body whose radius is fitted to find the axis. A can is one section; a
    wine bottle is body, shoulder and neck.
    """
    name: str
    colour: str
    sections: tuple[tuple[float, float], ...] = ()
    min_confidence: float = 0.3
    description: str = ""
    box: tuple[float, float, float] | None = None
    hue: int | None = None      # its OpenCV hue (0..180): pixels within HUE_WINDOW count
                                # as its colour, across a palette boundary
    saturation: int | None = None   # its saturation (0..255): a segment far less saturated
                                    # (SATURATION_SHARE) is something else of its hue

    @property
    def is_box(self) -> bool:
        return self.box is not None

    @property
    def height(self) -> float:
        return self.box[2] if self.box else self.sections[-1][0]

    @property
    def body_radius(self) -> float:
        """The body's radius; for a box, half its narrower side."""
        return 0.5 * min(self.box[:2]) if self.box else self.sections[0][1]

    @property
    def body_top(self) -> float:
        return self.box[2] if self.box else self.sections[0][0]

    def radii_at(self, hs: np.ndarray) -> np.ndarray:
        """:meth:`radius_at` for an array of heights."""
        tops = np.array([t for t, _ in self.sections])
        radii = np.array([r for _, r in self.sections] + [0.0])
        return radii[np.searchsorted(tops, hs, side="left")]

    def radius_at(self, h: float) -> float:
        """Radius at height ``h`` above the base (0 above the top)."""
        for top, r in self.sections:
            if h <= top:
                return r
        return 0.0


def _hsv_of(rgba) -> tuple[int, int, int]:
    """OpenCV's hue (0..180), saturation and value (0..255) of a colour given as rgb(a)
    in 0..1; PerceptionError for a colour with no clear hue (white, grey, black)."""
    px = np.uint8([[[round(255 * float(c)) for c in reversed(tuple(rgba)[:3])]]])   # BGR
    h, sat, val = (int(v) for v in cv2.cvtColor(px, cv2.COLOR_BGR2HSV)[0, 0])
    if sat < MIN_SATURATION or val < MIN_VALUE:
        raise PerceptionError(f"colour {tuple(rgba)} has no clear hue (saturation {sat}, value {val}): "
                              "perception finds objects by a saturated colour")
    return h, sat, val


def hue_of(rgba) -> int:
    """The OpenCV hue (0..180) of a colour given as rgb(a) in 0..1; PerceptionError for a
    colour with no clear hue (white, grey, black)."""
    return _hsv_of(rgba)[0]


def palette_colour(rgba) -> str:
    """The :data:`PALETTE` name of a colour given as rgb(a) in 0..1, as the camera would
    see its hue; PerceptionError for a colour with no clear hue (white, grey, black)."""
    h = hue_of(rgba)
    for name, ranges in PALETTE.items():
        if any(lo <= h < hi for lo, hi in ranges):
            return name
    raise PerceptionError(f"colour {tuple(rgba)} (hue {h}) is in no palette range")


def appearance_of(category: categories.Category) -> Appearance:
    """A category's appearance: the palette colour of its rgba and its shape."""
    shape = category.shape
    hue, sat, _ = _hsv_of(category.rgba)
    common = dict(name=category.name, colour=palette_colour(category.rgba), hue=hue, saturation=sat,
                  min_confidence=category.min_confidence, description=category.description)
    if isinstance(shape, categories.Box):
        return Appearance(box=(shape.x, shape.y, shape.z), **common)
    return Appearance(sections=tuple(shape.sections), **common)


def registered_appearances() -> dict[str, Appearance]:
    """Every registered category's appearance, read now (a category registered later is
    seen by the next call)."""
    return {c.name: appearance_of(c) for c in categories.all_categories()}


UNKNOWN = "unknown"


# ----------------------------------------------------------------------------- geometry
HUE_WINDOW = 7          # OpenCV hue units (2 degrees each) either side of a category's hue


def _hue_lut(appearances=()) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Hue -> palette index, twice: the palette's own ranges, and those ranges widened to
    HUE_WINDOW around each appearance's hue (colour jitter and white balance move a hue
    across a palette boundary: a yellow carton near orange). And hue -> the saturation a
    pixel needs for the widened colour: in a widened part, the share SATURATION_SHARE of
    the appearance's own (brown furniture has hues near a yellow carton's but half its
    saturation; taken for yellow, a wardrobe merges with a carton leaning on it). Returns
    (widened, palette, saturation floor, names)."""
    names = list(PALETTE)
    palette = np.zeros(256, np.uint8)
    for i, name in enumerate(names, 1):
        for lo, hi in PALETTE[name]:
            palette[lo:min(hi, 256)] = i
    widened = palette.copy()
    floor = np.full(256, MIN_SATURATION, np.int32)
    for app in appearances:
        if app.hue is not None and app.colour in names:
            k = names.index(app.colour) + 1
            hues = np.arange(app.hue - HUE_WINDOW, app.hue + HUE_WINDOW + 1) % 180
            widened[hues] = k
            if app.saturation is not None:
                moved = hues[palette[hues] != k]
                floor[moved] = np.maximum(floor[moved], int(SATURATION_SHARE * app.saturation))
    return widened, palette, floor, names


def colour_labels(bgr: np.ndarray, appearances=(), hsv: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """Per-pixel palette index (0 = no colour) and the palette's names (index - 1);
    ``appearances`` widen their colours' ranges around their hues for pixels saturated
    as they are (see _hue_lut); a duller pixel keeps the palette's colour.
    ``hsv``: the image in HSV, when the caller has it already."""
    if hsv is None:
        hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    widened, palette, floor, names = _hue_lut(appearances)
    hue, sat = hsv[:, :, 0], hsv[:, :, 1]
    lab = np.where(sat >= floor[hue], widened[hue], palette[hue])
    lab[(sat < MIN_SATURATION) | (hsv[:, :, 2] < MIN_VALUE)] = 0
    return lab, names


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


def fit_circle_fixed(xy: np.ndarray, r: float, c0: np.ndarray, iters: int = 12) -> tuple[np.ndarray, float]:
    """Centre of the circle of radius ``r`` through 2-D points ``xy`` (Gauss-Newton from
    ``c0``, Huber-weighted); returns (centre, RMS residual [m])."""
    if len(xy) > FIT_POINTS:                 # an even subsample (points come row by row)
        xy = xy[np.linspace(0, len(xy) - 1, FIT_POINTS).astype(int)]
    c = np.asarray(c0, float).copy()
    for _ in range(iters):
        d = xy - c
        dist = np.hypot(d[:, 0], d[:, 1])
        dist = np.maximum(dist, 1e-9)
        e = dist - r
        J = -d / dist[:, None]
        k = 1.5 * max(1e-3, 1.4826 * float(np.median(np.abs(e - np.median(e)))))
        wts = np.where(np.abs(e) <= k, 1.0, k / np.maximum(np.abs(e), 1e-12))
        A = (J * wts[:, None]).T @ J
        g = (J * wts[:, None]).T @ e
        try:
            step = np.linalg.solve(A + 1e-9 * np.eye(2), -g)
        except np.linalg.LinAlgError:
            break
        c += step
        if np.hypot(*step) < 1e-6:
            break
    e = np.hypot(*(xy - c).T) - r
    return c, float(np.sqrt(np.mean(e * e)))


@dataclass
class _Segment:
    """Measurements of one coloured region (internal)."""
    colour: str
    pixels: int
    u: float                  # centroid [px]
    v: float
    bbox: tuple[int, int, int, int]
    truncated: dict           # sides cut by the image border
    occluded: dict            # sides hidden by something nearer (right next to it)
    hidden: dict              # sides that may be hidden: something nearer is within
    #                           OCCLUDER_LOOK pixels (past pixels with no depth, or its
    #                           own pixels cut off by an occluder of its colour)
    pts: np.ndarray           # (N, 3) map-frame surface points
    hts: np.ndarray           # (N,) height above the base [m]
    base: float               # support height [m]
    top: float                # highest surface point [m]
    cam_xy: np.ndarray
    ray: np.ndarray           # unit horizontal viewing direction
    lateral: np.ndarray       # (N,) coordinate across the viewing direction [m]
    m_per_px: float           # metres per pixel at the segment
    range: float              # median horizontal distance camera -> surface [m]
    frame: RGBDFrame | None = None
    grid: np.ndarray | None = None   # (h, w, 3) map-frame points over the bounding box,
                                     # NaN outside the segment (image neighbours stay neighbours)
    in_structure: float = 0.0        # share of its pixels in a coloured region of furniture size
    saturation: float = 255.0        # median saturation of its pixels (0..255)
    continued: float = 0.0           # share of its surroundings that continue its surface
    #                                  in colour (measured when in_structure: a patch of it)

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
        out = []
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
                seg = lat_s[starts[i]:ends[i]]
                out.append(((i + 0.5) * band, float(seg.max() - seg.min()) + self.m_per_px))
        return out


def _measure(colour: str, comp: np.ndarray, x0: int, y0: int, P: np.ndarray, depth: np.ndarray,
             lab: np.ndarray, frame: RGBDFrame) -> _Segment | None:
    h, w = lab.shape
    ys, xs = np.nonzero(comp)
    ys = ys + y0
    xs = xs + x0
    pts = P[ys, xs]
    ok = np.isfinite(pts).all(axis=1)
    if ok.sum() < MIN_PIXELS // 2:
        return None
    pts = pts[ok]
    # the support: pixels 2..4 rows below the lowest pixel of each column, not coloured
    low = np.full(w, -1, np.int64)
    np.maximum.at(low, xs, ys)
    cols = np.nonzero(low >= 0)[0]
    sup = []
    for dy in (2, 3, 4):
        yy = low[cols] + dy
        inside = yy < h
        cx, cy = cols[inside], yy[inside]
        zz = P[cy, cx, 2]
        sup.append(zz[(lab[cy, cx] == 0) & np.isfinite(zz)])
    sup = np.concatenate(sup)
    zmin = float(np.min(pts[:, 2]))
    base = zmin
    if len(sup) >= 3:
        s = float(np.median(sup))
        if zmin - 0.03 <= s <= zmin + 0.005:
            base = s
    cam_xy = frame.T_map_cam[:2, 3]
    rel = pts[:, :2] - cam_xy
    mean = rel.mean(axis=0)
    ray = mean / (np.hypot(*mean) or 1.0)
    perp = np.array([-ray[1], ray[0]])
    lateral = rel @ perp
    rng = float(np.median(rel @ ray))
    m_per_px = float(np.median(depth[ys, xs][ok])) / frame.intrinsics.fx
    x1, y1 = int(xs.max()) + 1, int(ys.max()) + 1
    bx0, by0 = int(xs.min()), int(ys.min())
    trunc = {"left": bx0 <= 0, "right": x1 >= w, "top": by0 <= 0, "bottom": y1 >= h}
    occluded = _occluded_sides(xs, ys, depth, P, base)
    hidden = _occluded_sides(xs, ys, depth, P, base, OCCLUDER_LOOK)
    return _Segment(colour=colour, pixels=int(len(xs)), u=float(xs.mean()), v=float(ys.mean()),
                    bbox=(bx0, by0, x1, y1), truncated=trunc, occluded=occluded, hidden=hidden, pts=pts,
                    hts=pts[:, 2] - base, base=base, top=float(pts[:, 2].max()), cam_xy=cam_xy,
                    ray=ray, lateral=lateral,
                    m_per_px=m_per_px, range=rng, frame=frame, grid=_segment_grid(comp, x0, y0, P))


def _segment_grid(comp: np.ndarray, x0: int, y0: int, P: np.ndarray) -> np.ndarray:
    """The segment's points laid out as in the image (NaN off the segment)."""
    h, w = comp.shape
    grid = P[y0:y0 + h, x0:x0 + w].copy()
    grid[~comp.astype(bool)] = np.nan
    return grid


def _occluded_sides(xs: np.ndarray, ys: np.ndarray, depth: np.ndarray, P: np.ndarray,
                    base: float, look: int = 1) -> dict[str, bool]:
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
            d_next = np.fmin(d_next, depth[ny, nx][keep])        # (NaN: no depth, skipped)
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
            out.append((x0, y0, cc[y0:y0 + bh, x0:x0 + bw] == j))
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
        m[y0:y0 + roi.shape[0], x0:x0 + roi.shape[1]] = roi
        pts = P[m]
        pts = pts[np.isfinite(pts).all(axis=1)]
        full.append(m)
        samples.append(pts[np.linspace(0, len(pts) - 1, min(len(pts), 150)).astype(int)] if len(pts) else pts)
    out = mask.copy()
    joined = set()
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
                fill = ((inside > 0) & ~union & (lab == 0) & (depth > d.min() - 0.05) & (depth < d.max() + 0.05)
                        & (P[:, :, 2] > lo_z + 0.01))
            merged = union | fill
            if len(_components(merged)) == 1 and int(fill.sum()) > 0:
                out |= merged
                joined.update((i, j))
    return out


def _structure(lab: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Pixels of coloured regions (of any colours together, before depth cuts) larger than
    MAX_UNKNOWN_SIZE: furniture and walls. Light and noise break a brown bench into
    small patches of two hues; none of them is an object."""
    big = np.zeros(lab.shape, bool)
    for x0, y0, roi in _components(lab > 0):
        pts = P[y0:y0 + roi.shape[0], x0:x0 + roi.shape[1]][roi]
        pts = pts[np.isfinite(pts).all(axis=1)]
        if len(pts) < MIN_PIXELS:
            continue
        lo, hi = np.percentile(pts, (2, 98), axis=0)
        if max(hi[0] - lo[0], hi[1] - lo[1]) > MAX_UNKNOWN_SIZE[0] or hi[2] - lo[2] > MAX_UNKNOWN_SIZE[1]:
            big[y0:y0 + roi.shape[0], x0:x0 + roi.shape[1]] |= roi
    return big


def _continued_share(roi: np.ndarray, x0: int, y0: int, lab: np.ndarray, depth: np.ndarray,
                     pad: int = 2) -> float:
    """Share of the pixels just around a segment that are coloured and continue its
    surface without a depth step: high for a patch of something larger (light breaks a
    table into patches of two hues, one of them a category's), low for an object, which
    stands out against the floor or in front of what is behind it."""
    h, w = lab.shape
    bh, bw = roi.shape
    Y0, X0, Y1, X1 = max(0, y0 - pad), max(0, x0 - pad), min(h, y0 + bh + pad), min(w, x0 + bw + pad)
    inside = np.zeros((Y1 - Y0, X1 - X0), np.uint8)
    inside[y0 - Y0:y0 - Y0 + bh, x0 - X0:x0 - X0 + bw] = roi
    kernel = np.ones((2 * pad + 1, 2 * pad + 1), np.uint8)
    ring = (cv2.dilate(inside, kernel) > 0) & (inside == 0)
    if not ring.any():
        return 0.0
    d = depth[Y0:Y1, X0:X1]
    own = np.where((inside > 0) & np.isfinite(d), d, np.nan).astype(np.float32)
    near_max = cv2.dilate(np.nan_to_num(own, nan=0.0), kernel)         # its depths nearby
    near_min = cv2.erode(np.nan_to_num(own, nan=np.inf), kernel)
    tol = np.maximum(0.02, 0.03 * d)
    with np.errstate(invalid="ignore"):
        same = (d >= near_min - tol) & (d <= near_max + tol)
    return float(((lab[Y0:Y1, X0:X1] > 0) & same)[ring].mean())


def _segments(frame: RGBDFrame, P: np.ndarray, appearances=()) -> list[_Segment]:
    hsv = cv2.cvtColor(frame.bgr, cv2.COLOR_BGR2HSV)
    lab, names = colour_labels(frame.bgr, appearances, hsv)
    cut = _occlusion_cuts(lab, frame.depth)
    structure = _structure(lab, P)
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
            d = frame.depth[y0:y0 + bh, x0:x0 + bw]
            if holes.any() and np.isfinite(d[roi]).any():   # (no depth at all: nothing to fill)
                dm = float(np.nanmedian(d[roi]))
                roi = roi | (holes & (np.abs(d - dm) < 0.1))
            seg = _measure(name, roi, x0, y0, P, frame.depth, lab, frame)
            if seg is not None and seg.range <= MAX_RANGE:
                seg.in_structure = float(structure[y0:y0 + bh, x0:x0 + bw][roi].mean())
                own = roi & (lab[y0:y0 + bh, x0:x0 + bw] == i)    # not a label it was bridged over
                seg.saturation = float(np.median(saturation[y0:y0 + bh, x0:x0 + bw][own])) if own.any() else 0.0
                if seg.in_structure > 0.5:
                    seg.continued = _continued_share(roi, x0, y0, lab, frame.depth)
                out.append(seg)
    return out


# ----------------------------------------------------------------------------- classify
def _score(seg: _Segment, app: Appearance) -> tuple[float, dict]:
    """Confidence in [0, 1] that ``seg`` is ``app``, and the evidence."""
    if app.saturation is not None and seg.saturation < SATURATION_SHARE * app.saturation:
        return 0.0, {"reason": "colour too dull"}
    if app.is_box:
        return _score_box(seg, app)
    if seg.colour != app.colour:
        return 0.0, {"reason": "colour"}
    conf, ev = _score_upright(seg, app)
    ev["pose"] = "upright"
    for direction in seg.axis_candidates():
        if math.acos(min(1.0, abs(float(direction[2])))) > UPRIGHT_TILT:
            c, e = _score_posed(seg, app, direction)
            if e.get("pose") != "upright" and c > conf:
                conf, ev = c, e
    return conf, ev


def _score_upright(seg: _Segment, app: Appearance) -> tuple[float, dict]:
    """_score for a body of revolution standing on its base (the axis vertical)."""
    px = seg.m_per_px
    band = max(0.01, 1.6 * px)
    rho = seg.range + app.body_radius
    tangent = math.sqrt(max(0.0, 1.0 - (app.body_radius / max(rho, 1e-3)) ** 2))
    tol_w = max(0.008, 1.6 * px)
    tol_h = max(0.006, 1.5 * px)
    widths = seg.band_widths(band)
    side_cut = seg.cut("left") or seg.cut("right")
    # width profile: measured band widths against the appearance's diameter at that height
    errs = []
    for hmid, wm in widths:
        if hmid < band or hmid > seg.height - band:   # bottom rim and top rim bands are partial
            continue
        we = 2 * app.radius_at(hmid) * tangent
        if side_cut:
            errs.append(max(0.0, wm - we))           # a cut segment is only narrower
        else:
            errs.append(wm - we)
    if len(errs) < 2:
        return 0.0, {"reason": "too few height bands"}
    if side_cut:
        body_w = [wm for hmid, wm in widths if band <= hmid <= min(app.body_top, seg.height - band)]
        if not body_w or float(np.median(body_w)) < MIN_VISIBLE_WIDTH * 2 * app.body_radius * tangent:
            return 0.0, {"reason": "too little of it in view"}
    e_prof = float(np.sqrt(np.mean(np.square(errs))))
    # body: a cylinder of the body radius must fit the body's surface, and a plane must not
    body = seg.pts[(seg.hts > 0.1 * app.body_top) & (seg.hts < 0.9 * app.body_top), :2]
    if len(body) < 10:
        return 0.0, {"reason": "body not visible"}
    c0 = body.mean(axis=0) + app.body_radius * seg.ray
    axis, rms = fit_circle_fixed(body, app.body_radius, c0)
    flat = math.sqrt(max(0.0, float(np.linalg.eigvalsh(np.cov(body.T))[0])))
    if flat < 2 * DEPTH_NOISE:
        return 0.0, {"reason": "flat", "line_rms": flat}
    # height: the model, standing on the axis, is projected into the image: its highest
    # point inside the image is the height that must be seen (a bottle at the left border
    # may show its body but not its neck). Behind an occluder the seen height is only a
    # lower bound.
    top = _visible_top(seg, app, axis)
    if seg.occluded["top"] or seg.occluded["left"] or seg.occluded["right"]:
        e_h = max(0.0, seg.height - top)
    else:
        e_h = seg.height - top
    tol_r = seg.surface_tolerance
    z = np.array([e_prof / tol_w, e_h / tol_h, rms / tol_r])
    conf = _confidence(z)
    if seg.cut("top") or side_cut:
        conf *= 0.85                                 # part of the evidence is out of view
    return conf, {"profile_err": e_prof, "height_err": e_h, "cylinder_rms": rms, "line_rms": flat,
                  "axis": axis}


def _score_posed(seg: _Segment, app: Appearance, direction: np.ndarray) -> tuple[float, dict]:
    """_score for a body of revolution in any pose: its axis is fitted in 3-D (see
    actors/axis_fit.py; from ``direction``), the points' distance from it is checked
    against the radius profile (base at either end: the better fit says which end is the
    base, _profile_fit), and the visible
    length against the height. Evidence: ``pose`` (upright, tilted, lying), ``axis`` (x, y
    of the body's centre), ``yaw`` (lying: the axis's direction modulo pi; tilted: the
    direction it leans to), ``axis_base`` and ``axis_dir`` (3-D)."""
    cam = seg.frame.T_map_cam[:3, 3]
    fit = axis_fit.fit_axis(*seg.normals(), app.body_radius, cam, direction)
    if fit is None:
        return 0.0, {"reason": "body not visible"}
    tol_r = seg.surface_tolerance
    tol_h = max(0.01, 2.0 * seg.m_per_px)
    cut = seg.cut("left") or seg.cut("right") or seg.cut("top") or seg.cut("bottom")
    best = _profile_fit(seg, app, fit)
    if best is not None and len(best[4]) >= 15:      # refit on the body alone (not a neck)
        fit = axis_fit.refine_axis(best[4], app.body_radius, fit.point, fit.direction)
        best = _profile_fit(seg, app, fit)
    if best is not None:
        d = fit.direction
        tilt = math.acos(min(1.0, abs(float(d[2]))))
        if LYING_TILT >= tilt and d[2] * best[1] < 0:
            # standing or leaning, a body stands on its base: the lower end (the profile
            # of a can fits either way; a bottle upside down is not one leaning)
            best = _profile_fit(seg, app, fit, signs=(-best[1],))
    if best is None:
        return 0.0, {"reason": "too little of its side in view"}
    rms, sign, lo, hi, _ = best
    d = fit.direction
    up = d * sign                            # from the base to the top
    base_pt = fit.point + (lo if sign > 0 else hi) * d
    length = hi - lo
    e_len = length - app.height
    if cut or seg.occluded["top"]:
        e_len = max(0.0, e_len)              # part of it out of view: only shorter
    e_rise = _rise_error(seg, app, base_pt, up)
    z = np.array([rms / tol_r, e_len / tol_h, e_rise / tol_h])
    conf = _confidence(z)
    if cut:
        conf *= 0.85
    tilt = math.acos(min(1.0, abs(float(d[2]))))
    pose = "upright" if tilt < UPRIGHT_TILT else "lying" if tilt > LYING_TILT else "tilted"
    centre = base_pt + 0.5 * app.body_top * up
    if pose == "lying":
        yaw = math.atan2(d[1], d[0])
        yaw = yaw - math.pi if yaw > math.pi / 2 else yaw + math.pi if yaw <= -math.pi / 2 else yaw
    else:
        yaw = math.atan2(up[1], up[0])
    return conf, {"pose": pose, "axis": centre[:2].copy(), "yaw": yaw, "tilt": tilt,
                  "axis_base": base_pt.tolist(), "axis_dir": up.tolist(), "profile_rms": rms,
                  "length_err": e_len, "rise_err": e_rise}


def _rise_error(seg: _Segment, app: Appearance, base_pt: np.ndarray, up: np.ndarray) -> float:
    """How much taller [m] the segment stands above its support than the body would, posed
    by its fitted axis (base point ``base_pt``, direction ``up``): from its lowest rim to
    its highest (a lying can rises 2 r). A lower segment counts only when its top is in
    view. An axis fits a flat box's long side as well as a lying can's; its rise does not
    (a 4 cm box is no 6.6 cm can)."""
    across = math.sqrt(max(0.0, 1.0 - float(up[2]) ** 2))     # a rim's vertical half-extent per radius
    rims = [(base_pt, app.body_radius), (base_pt + app.body_top * up, app.body_radius),
            (base_pt + app.height * up, app.radius_at(app.height - 1e-3))]
    low = min(float(c[2]) - r * across for c, r in rims[:2])
    high = max(float(c[2]) + r * across for c, r in rims)
    e = (seg.top - seg.base) - (high - low)
    if seg.cut("top") or seg.occluded["top"]:
        e = max(0.0, e)
    return e


def _profile_fit(seg: _Segment, app: Appearance, fit: axis_fit.AxisFit, signs=(1.0, -1.0)):
    """How well the side's distances from ``fit``'s axis follow ``app``'s radius profile,
    with the base at the low end of the points along the axis or at the high end: the
    better as (trimmed RMS [m], +1 or -1: the base at the low or high end, low and high
    ends along the axis from fit.point [m], the body's points); None when too few.
    ``signs``: the ends tried (+1: the low end the base, -1: the high end)."""
    d = fit.direction
    lo, hi = (float(v) for v in np.percentile((seg.pts - fit.point) @ d, (0.5, 99.5)))
    s_side = (fit.side - fit.point) @ d
    radial = np.linalg.norm((fit.side - fit.point) - np.outer(s_side, d), axis=1)
    best = None
    for sign in signs:
        h = s_side - lo if sign > 0 else hi - s_side
        inner = (h > 0.01) & (h < app.height - 0.01)
        if inner.sum() < 10:
            continue
        e = radial[inner] - app.radii_at(h[inner])
        # trimmed: the worst 15 % (a rim, a label's edge, stray pixels) do not count
        e2 = np.sort(e * e)[:max(1, int(0.85 * len(e)))]
        rms = float(np.sqrt(np.mean(e2)))
        if best is None or rms < best[0]:
            best = (rms, sign, lo, hi, fit.side[inner & (h < app.body_top - 0.005)])
    return best


def _visible_top(seg: _Segment, app: Appearance, axis: np.ndarray) -> float:
    """Highest point of ``app`` standing at ``axis`` that projects into the image [m]."""
    frame = seg.frame
    k = frame.intrinsics
    T = np.linalg.inv(frame.T_map_cam)
    hs = np.concatenate([np.arange(0.0, top, 0.002).tolist() + [top - 1e-4] for top, _ in app.sections])
    rs = np.array([app.radius_at(h) for h in hs])
    ang = np.linspace(0, 2 * math.pi, 16, endpoint=False)
    X = axis[0] + rs[:, None] * np.cos(ang)[None, :]
    Y = axis[1] + rs[:, None] * np.sin(ang)[None, :]
    Z = np.broadcast_to((seg.base + hs)[:, None], X.shape)
    pc = np.einsum("ij,...j->...i", T[:3, :3], np.stack([X, Y, Z], axis=-1)) + T[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = k.fx * pc[..., 0] / pc[..., 2] + k.cx
        v = k.fy * pc[..., 1] / pc[..., 2] + k.cy
    inside = (pc[..., 2] > 0) & (u >= 0) & (u <= k.width - 1) & (v >= 0) & (v <= k.height - 1)
    seen = inside.any(axis=1)
    return float(hs[seen].max()) if seen.any() else 0.0


def _axis(seg: _Segment) -> tuple[np.ndarray, float]:
    """(x, y) of the vertical axis of an object of no known category, and its radius: a
    cylinder of the measured width when one fits, else a box (see ``_box_centre``)."""
    widths = [wd for _, wd in seg.band_widths(max(0.01, 1.6 * seg.m_per_px))]
    r = 0.5 * float(np.median(widths)) if widths else 0.03
    xy = seg.pts[:, :2]
    c0 = xy.mean(axis=0) + r * seg.ray
    c, rms = fit_circle_fixed(xy, r, c0)
    if rms > 2 * seg.surface_tolerance or not np.all(np.isfinite(c)) or np.hypot(*(c - c0)) > 2 * r:
        c = _box_centre(xy, seg.ray)
    return c, r


@dataclass
class _Rectangle:
    """A rectangle fitted to top-view points: centre ``c``, unit axes ``e1``, ``e2``,
    extents ``s1``, ``s2`` along them, and the RMS distance of the points to its sides."""
    c: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    s1: float
    s2: float
    rms: float


def _face_direction(grid: np.ndarray, lo: float, hi: float, stride: int = 3) -> float | None:
    """The direction [rad, modulo 90 degrees] of a box's vertical faces in the top view,
    from the surface's horizontal tangents: the difference of points ``stride`` pixels
    apart along the image rows, between heights ``lo`` and ``hi``. Every face of a box
    gives the same direction modulo 90 degrees, so the mean is taken of four times the
    angle. None when too few tangents."""
    a, b = grid[:, :-stride], grid[:, stride:]
    ok = np.isfinite(a).all(axis=-1) & np.isfinite(b).all(axis=-1)
    ok &= (a[..., 2] > lo) & (a[..., 2] < hi) & (b[..., 2] > lo) & (b[..., 2] < hi)
    t = (b - a)[ok][:, :2]
    if len(t) < 10:
        return None
    length = np.hypot(t[:, 0], t[:, 1])
    step = float(np.median(length))
    keep = (length > 0.3 * step) & (length < 3.0 * step)   # no depth jumps across an edge
    ang = 4 * np.arctan2(t[keep, 1], t[keep, 0])
    w = length[keep]
    return float(np.arctan2((w * np.sin(ang)).sum(), (w * np.cos(ang)).sum()) / 4)


def _rectangle_fit(xy: np.ndarray, direction: float | None = None) -> _Rectangle:
    """The rectangle around top-view points with sides along ``direction`` [rad, modulo
    90 degrees]; without one, the orientation whose sides the points hug most closely
    (the "closeness" criterion of L-shape fitting, in 1 degree steps). It spans the points."""
    if len(xy) > FIT_POINTS:
        xy = xy[np.linspace(0, len(xy) - 1, FIT_POINTS).astype(int)]
    if direction is not None:
        # refined within +-6 degrees: the sides that the points lie on most closely
        best = None
        for th in direction + np.radians(np.arange(-6.0, 6.01, 0.5)):
            e1 = np.array([math.cos(th), math.sin(th)])
            e2 = np.array([-e1[1], e1[0]])
            q = xy - xy.mean(axis=0)
            c1, c2 = q @ e1, q @ e2
            d = np.minimum(np.minimum(c1.max() - c1, c1 - c1.min()), np.minimum(c2.max() - c2, c2 - c2.min()))
            rms = float(np.sqrt(np.mean(d * d)))
            if best is None or rms < best[0]:
                best = (rms, e1, e2, c1, c2)
        rms, e1, e2, c1, c2 = best
        m1, m2 = 0.5 * (c1.max() + c1.min()), 0.5 * (c2.max() + c2.min())
        return _Rectangle(xy.mean(axis=0) + m1 * e1 + m2 * e2, e1, e2, float(np.ptp(c1)), float(np.ptp(c2)), rms)
    o = xy.mean(axis=0)
    q = xy - o
    th = np.radians(np.arange(0.0, 90.0, 1.0))
    c1 = q @ np.stack([np.cos(th), np.sin(th)])           # (N, A)
    c2 = q @ np.stack([-np.sin(th), np.cos(th)])
    d1 = np.minimum(c1.max(axis=0) - c1, c1 - c1.min(axis=0))
    d2 = np.minimum(c2.max(axis=0) - c2, c2 - c2.min(axis=0))
    score = (1.0 / np.maximum(np.minimum(d1, d2), 0.002)).sum(axis=0)
    k = int(np.argmax(score))
    e1 = np.array([math.cos(th[k]), math.sin(th[k])])
    e2 = np.array([-e1[1], e1[0]])
    m1 = 0.5 * (c1[:, k].max() + c1[:, k].min())
    m2 = 0.5 * (c2[:, k].max() + c2[:, k].min())
    rms = float(np.sqrt(np.mean(np.minimum(d1[:, k], d2[:, k]) ** 2)))
    return _Rectangle(o + m1 * e1 + m2 * e2, e1, e2, float(np.ptp(c1[:, k])), float(np.ptp(c2[:, k])), rms)


def _box_centre(xy: np.ndarray, ray: np.ndarray) -> np.ndarray:
    """Centre of a box-like footprint of unknown size from its visible faces (top view):
    the fitted rectangle's; when only one face shows (a thin rectangle) it is pushed back
    by half its width along the viewing direction: a square footprint is assumed."""
    r = _rectangle_fit(xy)
    long, short = max(r.s1, r.s2), min(r.s1, r.s2)
    if short < 0.35 * long:
        return r.c + 0.5 * (long - short) * ray
    return r.c


def _score_box(seg: _Segment, app: Appearance) -> tuple[float, dict]:
    """Confidence that ``seg`` is the box ``app`` resting on any face (``Box.rests``),
    and the evidence of the face that fits best, with its ``pose``."""
    if seg.colour != app.colour:
        return 0.0, {"reason": "colour"}
    best = (0.0, {"reason": "body not visible"})
    for pose, sides, height in categories.Box(*app.box).rests():
        conf, ev = _score_box_resting(seg, sides, height)
        if conf > best[0] or "reason" in best[1]:
            best = (conf, {**ev, "pose": pose, "width": min(sides)} if "reason" not in ev else ev)
    if best[0] < 0.9:                              # no resting face fits well: leaning?
        conf, ev = _score_box_tilted(seg, app.box)
        if conf > best[0]:
            best = (conf, ev)
    return best


MAX_ERROR = 2.0         # [tolerances] one measurement off by more rules a fit out: the
#                         mean square dilutes it (a lego brick 13 mm taller than a lying
#                         carton, its other sizes close, scored 0.34); at 2.5, 10 false
#                         detections in 528 bench views, at 2.0 6, one true view fewer


def _confidence(z: np.ndarray) -> float:
    """Confidence from measurement errors ``z`` in units of their tolerances: a Gaussian
    of their mean square, at most 0.1 when any is off by more than MAX_ERROR."""
    conf = float(math.exp(-0.5 * float(np.mean(z * z))))
    return min(conf, 0.1) if np.any(np.abs(z) > MAX_ERROR) else conf


def _box_tolerances(seg: _Segment) -> tuple[float, float, float]:
    """A box fit's tolerances [m]: on a face's length, on a height, and on the points'
    distance from the fitted faces (the depth noise, or a quarter pixel)."""
    px = seg.m_per_px
    return max(0.008, 1.6 * px), max(0.006, 1.5 * px), max(2 * seg.surface_tolerance, 0.25 * px)


FACE_BOW = 0.001        # [m] a flat face may seem to bow this much (edge pixels, the render
#                         mesh) on top of what its noise allows


def _bow(u: np.ndarray, v: np.ndarray, d: np.ndarray) -> float:
    """How far a face's points bow off a plane, in tolerances: ``d`` [m], their offset
    from it, is fitted as a quadratic in ``u`` and ``v`` (across the face); the larger
    sagitta over the points' span (a bow in the middle against the ends) is compared with
    FACE_BOW plus 1.5 its standard error (from the fit's residuals: the depth noise,
    averaged over the points). A box's face does not bow; a cylinder's side seen across
    its axis (a mug, upright or on its side) bows by r (1 - cos) towards the camera,
    which averaging finds below the noise of a single point."""
    if len(d) < 12:
        return 0.0
    u, v = u - u.mean(), v - v.mean()
    X = np.stack([np.ones_like(u), u, v, u * u - np.mean(u * u), v * v - np.mean(v * v)], axis=1)
    coef, *_ = np.linalg.lstsq(X, d, rcond=None)
    res = d - X @ coef
    var = float(res @ res) / (len(d) - 5)
    cov = np.linalg.pinv(X.T @ X) * var
    z = 0.0
    for k, span in ((3, float(np.ptp(u))), (4, float(np.ptp(v)))):
        s = (0.5 * span) ** 2
        z = max(z, abs(float(coef[k])) * s / (FACE_BOW + 1.5 * math.sqrt(max(0.0, float(cov[k, k]))) * s))
    return z


TILT_FACE_ANGLE = math.radians(20)  # a face's normals stay this close to its plane's


def _box_faces(seg: _Segment, max_faces: int = 2) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """The segment's dominant plane faces, most supported first: (centre, unit normal
    towards the camera, RMS of its points off the plane [m]). A face's normal is the one
    most of the surface normals agree with (within 15 degrees); its plane is fitted to the
    points whose normals lie within TILT_FACE_ANGLE of it."""
    pts, nrm = seg.normals()
    if len(pts) < 30:
        return []
    cam = seg.frame.T_map_cam[:3, 3]
    nrm = nrm * np.where(((cam - pts) * nrm).sum(axis=1) < 0, -1.0, 1.0)[:, None]
    free = np.ones(len(pts), bool)
    faces = []
    for _ in range(max_faces):
        idx = np.flatnonzero(free)
        if len(idx) < 30:
            break
        n = nrm[idx]
        sample = n[np.linspace(0, len(n) - 1, min(len(n), 200)).astype(int)]
        votes = (sample @ n.T > math.cos(math.radians(15))).sum(axis=1)
        n0 = sample[int(np.argmax(votes))]
        member = idx[n @ n0 > math.cos(TILT_FACE_ANGLE)]
        if len(member) < 30:
            break
        P = pts[member]
        c = P.mean(axis=0)
        w, v = np.linalg.eigh(np.cov(P.T))
        normal = v[:, 0] if float(v[:, 0] @ n0) > 0 else -v[:, 0]
        faces.append((c, normal, math.sqrt(max(0.0, float(w[0])))))
        free[member] = False
    return faces


def _score_box_tilted(seg: _Segment, box: tuple[float, float, float]) -> tuple[float, dict]:
    """Confidence that ``seg`` is the box of sizes ``box`` (x, y, z) leaning: its z axis
    between UPRIGHT_TILT and LYING_TILT from the vertical. Its largest visible face is
    fitted as a plane (_box_faces) and measured along its in-plane principal axes (a side
    that runs into a side of the segment where it may continue out of view is only a lower
    bound on its length); two of the box's sizes must fit them, the third lies behind the
    face (a second face seen beside it, perpendicular, must be that deep). The box's
    lowest corner must be on the support and nothing seen above its highest. Evidence as
    for a leaning body of revolution: ``pose`` tilted, ``axis`` (x, y of the box's centre),
    ``yaw`` (the direction it leans to), ``tilt``, ``axis_base`` (its bottom face's centre)
    and ``axis_dir`` (its z axis, base to top), ``width`` (its side across the lean)."""
    faces = _box_faces(seg)
    if not faces:
        return 0.0, {"reason": "no plane face"}
    px = seg.m_per_px
    tol_w, tol_h, tol_r = _box_tolerances(seg)
    cam = seg.frame.T_map_cam[:3, 3]
    c, n, _ = faces[0]
    view = c - cam
    view = view / np.linalg.norm(view)
    if abs(float(view @ n)) < GRAZING:
        return 0.0, {"reason": "face seen at a grazing angle"}
    # the face's points: every segment point on its plane
    off = (seg.pts - c) @ n
    on = np.abs(off) < max(3 * tol_r, 0.004)
    F = seg.pts[on]
    if len(F) < 30:
        return 0.0, {"reason": "body not visible"}
    rms = float(np.sqrt(np.mean(off[on] ** 2)))
    q = F - F.mean(axis=0)
    w, v = np.linalg.eigh(np.cov(q.T))
    axes = [v[:, 2], v[:, 1]]
    # which ends of the face may continue out of view
    perp = np.array([-seg.ray[1], seg.ray[0], 0.0])
    lat_all = seg.pts @ perp
    z_all = seg.pts[:, 2]
    near = 2.5 * px
    touches = []
    for side, vals, lim, sgn in (("left", lat_all, lat_all.max(), 1), ("right", lat_all, lat_all.min(), -1),
                                 ("top", z_all, z_all.max(), 1), ("bottom", z_all, z_all.min(), -1)):
        if seg.may_continue(side):
            touches.append((side, vals[on], lim, sgn))
    ext, mid, open_ends = [], [], []
    for a in axes:
        s = q @ a
        lo, hi = float(s.min()), float(s.max())
        ends = []
        for end_sel in (s <= lo + near, s >= hi - near):
            ends.append(any(bool(np.any(sgn * (vals[end_sel] - lim) >= -near)) for _, vals, lim, sgn in touches))
        ext.append(hi - lo + px)
        mid.append(0.5 * (lo + hi))
        open_ends.append(ends)            # [low end open, high end open]
    if all(any(e) for e in open_ends) or any(all(e) for e in open_ends):
        return 0.0, {"reason": "too little of it in view", "extents": ext}
    dims = [float(d) for d in box]
    best = None
    for i0, i1, i2 in ((0, 1, 2), (1, 0, 2), (0, 2, 1), (2, 0, 1), (1, 2, 0), (2, 1, 0)):
        true = [dims[i0], dims[i1]]
        errs = [ext[k] - true[k] if not any(open_ends[k]) else max(0.0, ext[k] - true[k]) for k in (0, 1)]
        e = math.sqrt(float(np.mean(np.square(errs))))
        if best is None or e < best[0]:
            best = (e, (i0, i1, i2), true)
    e_face, assign, true = best
    # the box's centre: along each face axis the middle of its extent, or half its size
    # from the end in view; behind the face half the third size
    centre = F.mean(axis=0) - 0.5 * dims[assign[2]] * n
    for k in (0, 1):
        a = axes[k]
        if not any(open_ends[k]):
            centre = centre + mid[k] * a
        else:
            s = q @ a
            if open_ends[k][1]:                         # the low end is in view
                centre = centre + (float(s.min()) + 0.5 * true[k]) * a
            else:
                centre = centre + (float(s.max()) - 0.5 * true[k]) * a
    box_axes = [None, None, None]
    box_axes[assign[0]], box_axes[assign[1]], box_axes[assign[2]] = axes[0], axes[1], n
    up = box_axes[2] if box_axes[2][2] >= 0 else -box_axes[2]
    tilt = math.acos(min(1.0, abs(float(up[2]))))
    if not UPRIGHT_TILT < tilt < LYING_TILT:
        return 0.0, {"reason": "not leaning", "tilt": tilt}
    # its corners: the lowest on the support, nothing of it seen above the highest
    half = [0.5 * dims[k] * box_axes[k] for k in range(3)]
    corners = np.array([centre + sx * half[0] + sy * half[1] + sz * half[2]
                        for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    e_base = float(corners[:, 2].min()) - seg.base
    e_top = max(0.0, seg.top - float(corners[:, 2].max()))
    # a second face beside it: perpendicular, as deep as the third size
    e_depth = 0.0
    if len(faces) > 1:
        c2, n2, _ = faces[1]
        v2 = (c2 - cam) / np.linalg.norm(c2 - cam)
        if abs(float(n2 @ n)) < math.sin(math.radians(15)) and abs(float(v2 @ n2)) >= GRAZING:
            off2 = (seg.pts - c2) @ n2
            on2 = (np.abs(off2) < max(3 * tol_r, 0.004)) & ~on
            if on2.sum() >= 30:
                d2 = (seg.pts[on2] - F.mean(axis=0)) @ -n
                e_depth = float(np.ptp(d2)) + px - dims[assign[2]]
                e_depth = e_depth if e_depth > 0 else 0.5 * e_depth   # seen at an angle: shorter
    # the face must be flat (a mug on its side is not): its edges left out, where the
    # points of a face beside it are as near its plane as the band that took its points
    trim = max(3 * tol_r, 0.004) + px
    s0, s1 = q @ axes[0], q @ axes[1]
    keep = ((s0 > s0.min() + trim) & (s0 < s0.max() - trim) & (s1 > s1.min() + trim) & (s1 < s1.max() - trim))
    bow = _bow(s0[keep], s1[keep], off[on][keep])
    z = np.array([e_face / tol_w, max(rms / tol_r, bow), e_base / (2 * tol_h), e_top / tol_h, e_depth / tol_w])
    conf = _confidence(z)
    if any(seg.cut(k) for k in ("left", "right", "top", "bottom")):
        conf *= 0.85
    base_pt = centre - 0.5 * dims[2] * up
    # the side the fingers close across: the box's x or y axis the more level, across the lean
    across = np.cross(up, [0.0, 0.0, 1.0])
    width = dims[0] if abs(float(box_axes[0] @ across)) >= abs(float(box_axes[1] @ across)) else dims[1]
    return conf, {"pose": "tilted", "axis": centre[:2].copy(), "yaw": math.atan2(up[1], up[0]), "tilt": tilt,
                  "axis_base": base_pt.tolist(), "axis_dir": up.tolist(), "width": width,
                  "face_err": e_face, "rect_rms": rms, "bow": bow, "base_err": e_base, "top_err": e_top,
                  "depth_err": e_depth, "extents": ext}


def _whole_faces(seg: _Segment, side: np.ndarray, rect: _Rectangle) -> list[bool]:
    """Whether each face of ``rect`` (along e1, along e2) that the top-view points
    ``side`` lie on ends in view: it does not reach the segment's left or right side where
    the object may continue out of view (``may_continue``: the image border, or something
    nearer). A face reaches a side when its points come within two pixels of the
    segment's outermost point there, across the view."""
    perp = np.array([-seg.ray[1], seg.ray[0]])     # towards the image's left
    lat = (side - seg.cam_xy) @ perp
    q = side - rect.c
    a1, a2 = q @ rect.e1, q @ rect.e2
    on_e1 = np.abs(np.abs(a2) - 0.5 * rect.s2) <= np.abs(np.abs(a1) - 0.5 * rect.s1)
    near = 2 * seg.m_per_px
    out = []
    for face in (on_e1, ~on_e1):
        if not face.any():
            out.append(False)
            continue
        f = lat[face]
        reaches_cut = ((seg.may_continue("left") and f.max() >= lat.max() - near)
                       or (seg.may_continue("right") and f.min() <= lat.min() + near))
        out.append(not reaches_cut)
    return out


def _resting_bow(seg: _Segment, pts: np.ndarray, rect: _Rectangle, seen: list[bool]) -> float:
    """_bow of a standing box's faces that are seen well, from its side points ``pts``
    (3-D). In the view each face lies to one side of the rectangle's corner nearest the
    camera, so the points are split there (across the view: depth noise hardly moves
    them); a pixel and a half at the corner and at the outer edges is left out."""
    perp = np.array([-seg.ray[1], seg.ray[0]])
    lat = (pts[:, :2] - seg.cam_xy) @ perp
    ends = [(a, b) for a in (-0.5, 0.5) for b in (-0.5, 0.5)]
    a, b = min(ends, key=lambda ab: float(np.linalg.norm(
        rect.c + ab[0] * rect.s1 * rect.e1 + ab[1] * rect.s2 * rect.e2 - seg.cam_xy)))
    corner = rect.c + a * rect.s1 * rect.e1 + b * rect.s2 * rect.e2
    lat_c = float((corner - seg.cam_xy) @ perp)
    margin = 1.5 * seg.m_per_px
    inner = (lat > lat.min() + margin) & (lat < lat.max() - margin)
    z = 0.0
    # the face along e1 runs from the corner by -2a s1 e1; the one along e2 by -2b s2 e2
    for i, (e, n, step) in enumerate(((rect.e1, rect.e2, -2 * a * rect.s1 * rect.e1),
                                      (rect.e2, rect.e1, -2 * b * rect.s2 * rect.e2))):
        if not seen[i]:
            continue
        away = 1.0 if float(step @ perp) > 0 else -1.0
        on = inner & (away * (lat - lat_c) > margin)
        z = max(z, _bow(pts[on, :2] @ e, pts[on, 2], pts[on, :2] @ n))
    return z


def _score_box_resting(seg: _Segment, sides: tuple[float, float], bz: float) -> tuple[float, dict]:
    """Confidence that ``seg`` is a box whose top-view sides are ``sides`` and whose height
    is ``bz``, from its measured dimensions: its height above the support, and the lengths
    of the faces seen from above (one face: its length is either side; two: both). Returns
    the evidence with the box's centre (``axis``) and ``yaw``, the map-frame direction of
    its first side in (-pi/2, pi/2]."""
    bx, by = sides
    px = seg.m_per_px
    tol_w, tol_h, tol_r = _box_tolerances(seg)
    # the sides, from the points above the bottom rim (the floor's edge pixels blur it)
    lo, hi = seg.base + 0.15 * bz, seg.base + 0.85 * bz
    side3 = seg.pts[(seg.pts[:, 2] > lo) & (seg.pts[:, 2] < hi)]
    side = side3[:, :2]
    if len(side) < 10:
        return 0.0, {"reason": "body not visible"}
    rect = _rectangle_fit(side, _face_direction(seg.grid, lo, hi))
    side_cut = seg.cut("left") or seg.cut("right")
    # A side's length is measured only on faces seen well: at a grazing angle a face is
    # a few scattered pixels. The faces along e1 face the camera by |ray . e2|.
    seen = [abs(float(seg.ray @ rect.e2)) >= GRAZING, abs(float(seg.ray @ rect.e1)) >= GRAZING]
    ext = [rect.s1 + px, rect.s2 + px]             # the points stop half a pixel short each side
    # ... but a face seen at a grazing angle still spans its points: one far longer than
    # the box's longest side is part of something larger (a pallet's side seen edge-on)
    if any(not seen[i] and ext[i] > max(bx, by) + GRAZING_SLACK for i in (0, 1)):
        return 0.0, {"reason": "a face longer than the box", "extents": ext}
    # A face that runs into a side where the box may go on out of view (the image border,
    # or something nearer next to it) is only a lower bound on its length; one that ends
    # in view at both ends is measured. A box none of whose faces seen ends in view may
    # be anything longer (the corner of a pallet at the image border or beside a desk):
    # too little of it is in view to tell.
    open_side = seg.may_continue("left") or seg.may_continue("right")
    whole = _whole_faces(seg, side, rect) if open_side else [True, True]
    if not any(seen[i] and whole[i] for i in (0, 1)):
        return 0.0, {"reason": "too little of it in view", "extents": ext}

    def err(i: int, true: float) -> float:
        return ext[i] - true if whole[i] else max(0.0, ext[i] - true)   # cut: only shorter

    axes = [rect.e1, rect.e2]
    fits = []
    for x_is in (0, 1):                            # the box's x side along e1, or along e2
        true = [bx, by] if x_is == 0 else [by, bx]
        errs = [err(i, true[i]) for i in (0, 1) if seen[i]]
        fits.append((math.sqrt(float(np.mean(np.square(errs)))), x_is, true))
    e_face, x_is, true = min(fits)
    # the centre: along a side measured, the middle of its extent; along one not seen,
    # half the box behind the face that is seen; along a face cut off, half its length
    # from its end in view
    centre = rect.c.copy()
    perp = np.array([-seg.ray[1], seg.ray[0]])     # towards the image's left
    for i in (0, 1):
        e = axes[i]
        if not seen[i]:                            # the face seen squarely has normal +-axes[i]
            away = 1.0 if float(seg.ray @ e) > 0 else -1.0
            near = float(rect.c @ e) - away * 0.5 * ext[i]          # that face, nearest the camera
            centre = centre + (near + away * 0.5 * true[i] - float(rect.c @ e)) * e
        elif not whole[i]:
            # towards the cut (+e or -e): the side of the image that is cut off
            to_cut = 1.0 if (float(perp @ e) > 0) == seg.may_continue("left") else -1.0
            end = float(rect.c @ e) - to_cut * 0.5 * ext[i]         # the end in view
            centre = centre + (end + to_cut * 0.5 * true[i] - float(rect.c @ e)) * e
    x_axis = axes[x_is]
    one_face = not all(seen)
    e_h = seg.height - bz
    if seg.cut("top") or seg.occluded["top"]:
        e_h = max(0.0, e_h)                           # part of it may be hidden: a lower bound
    # the points on the rectangle's sides: each within the noise, and the faces flat
    # (averaged over many points: a mug's side hugs a rectangle within the noise far off)
    bow = _resting_bow(seg, side3, rect, seen)
    z = np.array([e_face / tol_w, e_h / tol_h, max(rect.rms / tol_r, bow)])
    conf = _confidence(z)
    if seg.cut("top") or side_cut:
        conf *= 0.85
    yaw = math.atan2(x_axis[1], x_axis[0])
    if yaw <= -math.pi / 2:
        yaw += math.pi
    elif yaw > math.pi / 2:
        yaw -= math.pi
    return conf, {"face_err": e_face, "height_err": e_h, "rect_rms": rect.rms, "bow": bow, "faces": 1 if one_face else 2,
                  "extents": ext, "seen": seen, "whole": whole, "axis": centre, "yaw": yaw}


def detect(frame: RGBDFrame, appearances: dict[str, Appearance] | None = None) -> list[dict]:
    """Every object in one RGB-D frame, nearest first.

    Each detection is a dict:
      category    ``can``, ``bottle``, ... or ``unknown``
      x, y        the object's vertical axis in the map frame [m]
      z           its base (the support height) in the map frame [m]
      height      visible height above the base [m] (a lower bound when ``truncated``)
      width       body width [m]
      distance    horizontal distance from the robot base to the axis [m]
      bearing     direction of the axis in the robot's frame [rad], positive left
      confidence  in [0, 1]
      pixel       [u, v] centroid of the object's pixels
      colour, truncated (sides cut by the image border or hidden behind something
      nearer), stamp [s], frame ("map")
      pose        a known category: ``upright``, ``lying`` or ``tilted``
      yaw         a box: the map-frame direction of its x side (lying: its long side)
                  [rad], in (-pi/2, pi/2], x, y its centre; a lying body of revolution:
                  its axis's direction; a leaning one: the direction it leans to
      axis_base, axis_dir, tilt_deg   a body of revolution fitted in 3-D: the axis
                  point at its base, the unit axis from base to top, its tilt [deg]
      width       (lying box) the side the hand closes across from above [m]
    """
    apps = registered_appearances() if appearances is None else appearances
    P = backproject(frame)
    T_base_map = np.linalg.inv(frame.T_map_base)
    out = []
    for seg in _segments(frame, P, list(apps.values())):
        if seg.continued > PATCH_SHARE:
            continue                                   # a patch of furniture, of any shape
        best, best_conf, evidence = None, 0.0, {}
        for app in apps.values():
            conf, ev = _score(seg, app)
            if conf > best_conf:
                best, best_conf, evidence = app, conf, ev
        if best is not None and best_conf >= best.min_confidence:
            category, conf, app = best.name, best_conf, best
        else:
            category, app = UNKNOWN, None
            conf = 1.0 - best_conf
        if app is not None:
            c, r = evidence["axis"], app.body_radius
        else:
            c, r = _axis(seg)
        widths = [wd for hm, wd in seg.band_widths(max(0.01, 1.6 * seg.m_per_px))
                  if app is None or hm < app.body_top]
        width = float(np.median(widths)) if widths else 2 * r
        if app is not None and (seg.cut("left") or seg.cut("right") or evidence.get("pose", "upright") != "upright"):
            width = evidence.get("width", 2 * r)       # partly out of view: the model's width
        if app is None and (width > MAX_UNKNOWN_SIZE[0] or seg.height > MAX_UNKNOWN_SIZE[1]
                            or seg.in_structure > 0.5):
            continue                                   # a wall, furniture (or a patch of it)
        b = T_base_map @ np.array([c[0], c[1], seg.base, 1.0])
        out.append({
            "category": category,
            "x": float(c[0]), "y": float(c[1]), "z": float(seg.base),
            "height": float(seg.height), "width": width,
            "distance": float(math.hypot(b[0], b[1])), "bearing": float(math.atan2(b[1], b[0])),
            "confidence": round(float(conf), 3),
            "pixel": [round(seg.u, 1), round(seg.v, 1)],
            "colour": seg.colour,
            "truncated": [k for k in ("left", "right", "top", "bottom") if seg.cut(k)],
            "stamp": frame.stamp, "frame": "map",
        })
        if app is not None:
            if evidence.get("yaw") is not None:
                out[-1]["yaw"] = float(evidence["yaw"])
            out[-1]["pose"] = evidence.get("pose", "upright")
            if "axis_dir" in evidence:
                out[-1]["axis_base"] = [float(v) for v in evidence["axis_base"]]
                out[-1]["axis_dir"] = [float(v) for v in evidence["axis_dir"]]
                out[-1]["tilt_deg"] = round(math.degrees(evidence["tilt"]), 1)
    out.sort(key=lambda d: d["distance"])
    return out


def _targets(dets: list[dict], category: str | None, apps: dict) -> list[dict]:
    if category is None:
        return [d for d in dets if d["category"] in apps]
    return [d for d in dets if d["category"] == category]


def combine_sightings(sightings: list[dict], looks: int, gate: float = 0.08) -> dict | None:
    """One estimate from several detections of possibly several objects.

    Detections are grouped by position (within ``gate`` [m] of a group's median); the group
    seen most often (then the nearest) wins. Its position is the median after dropping
    sightings more than max(2 cm, 3 MAD) from the first median; its category the majority.
    """
    if not sightings:
        return None
    groups: list[list[dict]] = []
    for d in sightings:
        for g in groups:
            if math.hypot(d["x"] - np.median([s["x"] for s in g]), d["y"] - np.median([s["y"] for s in g])) < gate:
                g.append(d)
                break
        else:
            groups.append([d])
    groups.sort(key=lambda g: (-len(g), float(np.median([s["distance"] for s in g]))))
    g = groups[0]
    xy = np.array([[s["x"], s["y"]] for s in g])
    med = np.median(xy, axis=0)
    dev = np.hypot(*(xy - med).T)
    mad = 1.4826 * float(np.median(dev))
    keep = dev <= max(0.02, 3 * mad)
    kept = [s for s, k in zip(g, keep) if k]
    cats = [s["category"] for s in kept]
    category = max(set(cats), key=cats.count)
    kept_c = [s for s in kept if s["category"] == category] or kept
    xyz = np.array([[s["x"], s["y"], s["z"]] for s in kept_c])
    m = np.median(xyz, axis=0)
    last = max(kept_c, key=lambda s: s["stamp"])
    est = dict(last)
    est.update({
        "category": category,
        "x": float(m[0]), "y": float(m[1]), "z": float(m[2]),
        "height": float(np.median([s["height"] for s in kept_c])),
        "width": float(np.median([s["width"] for s in kept_c])),
        "confidence": round(float(np.median([s["confidence"] for s in kept_c])) * len(kept_c) / max(looks, 1), 3),
        "sightings": len(kept_c), "looks": looks,
        "spread": float(np.max(np.hypot(*(xyz[:, :2] - m[:2]).T))) if len(kept_c) > 1 else 0.0,
    })
    return est


# ----------------------------------------------------------------------------- subsystem
GLANCE_TIMEOUT = 3.0    # [s] how long one look may wait for a frame


class Perception(SubSystem):
    """Object detection, classification and localisation on the robot's RGB-D camera.

    A ``camera`` child subsystem holds the camera's stream actors (``pic``, ``depth``,
    ``camera_info``, ``rgbd``). ``appearances`` maps category names to
    :class:`Appearance`; by default every registered category's, read at each look (so a
    category loaded later is recognised). Other keyword arguments go to
    :class:`actors.camera.Camera` (topics, map and base frames).
    """

    def __init__(self, appearances: dict[str, Appearance] | None = None, **camera: object) -> None:
        super().__init__()
        self.add_subsystem("camera", Camera, **camera)
        self.set_value("appearances", None if appearances is None else dict(appearances))

    def _apps(self) -> dict[str, Appearance]:
        fixed = self.get_value("appearances")
        return registered_appearances() if fixed is None else fixed

    def _check_category(self, category: str | None) -> None:
        if category is not None and category != UNKNOWN and category not in self._apps():
            raise PerceptionError(f"unknown category {category!r}; known: "
                                  f"{', '.join(sorted(self._apps()))}, {UNKNOWN}")

    def _frame(self) -> RGBDFrame:
        return self.run_actor_mode("rgbd", "timed", GLANCE_TIMEOUT)

    @actor(read_only=True)
    def object_glance(self) -> list[dict]:
        """One quick look: every object in the next RGB-D frame (targets and ``unknown``
        distractors), nearest first. See ``detect`` for the fields of a detection."""
        return detect(self._frame(), self._apps())

    @actor(read_only=True)
    def find_object(self, category: str | None = None) -> dict | None:
        """The nearest object of ``category`` (any known category when None) in the next
        RGB-D frame, or None: {category, x, y, z, height, width, distance, bearing,
        confidence, pixel, ...}; x, y is the object's axis and z its base, map frame [m].

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); None: any known category
        """
        self._check_category(category)
        found = _targets(detect(self._frame(), self._apps()), category, self._apps())
        return found[0] if found else None

    @actor(read_only=True)
    def pic_find(self, category: str | None = None, seconds: float = 10.0) -> dict | None:
        """Watch the camera for up to ``seconds`` until an object of ``category`` (any known
        category when None) is seen; the nearest such detection, or None on timeout.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); None: any known category
            seconds: how long to watch at most [s]
        """
        self._check_category(category)
        ret = None
        with self.run_actor_mode("rgbd", "timed_iterator", seconds) as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if found:
                    ret = found[0]
                    break
        return ret

    @actor(read_only=True)
    def get_found(self, category: str | None = None, looks: int = 5) -> dict | None:
        """A reliable estimate from ``looks`` consecutive frames: sightings are grouped by
        position, outliers dropped, and the median kept. Adds ``sightings``, ``looks`` and
        ``spread`` [m] to the detection fields; None when nothing was seen.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); None: any known category
            looks: how many consecutive camera frames to combine
        """
        self._check_category(category)
        looks = max(1, int(looks))
        sightings: list[dict] = []
        n = 0
        with self.run_actor_mode("rgbd", "timed_iterator", GLANCE_TIMEOUT + looks * 0.5) as frames:
            for frame in frames:
                sightings += _targets(detect(frame, self._apps()), category, self._apps())
                n += 1
                if n >= looks:
                    break
        if n == 0:
            raise PerceptionError("no camera frames")
        return combine_sightings(sightings, n)

    @actor(read_only=True)
    def measure_distance(self, category: str | None = None) -> Iterator[dict | None]:
        """Per frame, the range and bearing to the nearest target (for visual servoing):
        {distance [m], bearing [rad, + left], x, y, category, stamp}, or None when no
        target is in view.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); None: any known category
        """
        self._check_category(category)
        with self.run_actor_mode("rgbd", "iterator") as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if not found:
                    yield None
                    continue
                d = found[0]
                yield {"distance": d["distance"], "bearing": d["bearing"], "x": d["x"], "y": d["y"],
                       "category": d["category"], "stamp": d["stamp"]}

    @actor(read_only=True)
    def measure_center(self, category: str | None = None) -> Iterator[dict | None]:
        """Per frame, where the nearest target is in the image: {dx, dy} its pixel offset
        from the principal point normalised by half the image size (-1 left/top .. +1
        right/bottom), pixel, category, stamp; None when no target is in view.

        Args:
            category: the object category to look for (can, bottle, or unknown: an
                object of no known category); None: any known category
        """
        self._check_category(category)
        with self.run_actor_mode("rgbd", "iterator") as frames:
            for frame in frames:
                found = _targets(detect(frame, self._apps()), category, self._apps())
                if not found:
                    yield None
                    continue
                d, k = found[0], frame.intrinsics
                u, v = d["pixel"]
                yield {"dx": (u - k.cx) / (k.width / 2), "dy": (v - k.cy) / (k.height / 2),
                       "pixel": d["pixel"], "category": d["category"], "stamp": d["stamp"]}
