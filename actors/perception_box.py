"""Shape scoring for boxes (cartons): resting on any face (a rectangle fitted to the top
view, flat faces of the right lengths) or leaning (a plane face fitted in 3-D); and the
centre of a box-like footprint of unknown size."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import categories

from .perception_colour import Appearance
from .perception_fit import FIT_POINTS, LYING_TILT, UPRIGHT_TILT, _confidence
from .perception_segments import _Segment

GRAZING = 0.3  # a face seen at less than ~17 degrees (sin) is not measured
FACE_STEP = 0.008  # [m] the shortest step along a face over which its direction is measured
GRAZING_SLACK = 0.10  # [m] a face seen at a grazing angle may look this much longer than
#                         the box's longest side (depth noise along the view); no more


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
    keep = (length > 0.3 * step) & (length < 3.0 * step)  # no depth jumps across an edge
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
        best: tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        for th in direction + np.radians(np.arange(-6.0, 6.01, 0.5)):
            e1 = np.array([math.cos(th), math.sin(th)])
            e2 = np.array([-e1[1], e1[0]])
            q = xy - xy.mean(axis=0)
            c1, c2 = q @ e1, q @ e2
            d = np.minimum(np.minimum(c1.max() - c1, c1 - c1.min()), np.minimum(c2.max() - c2, c2 - c2.min()))
            rms = float(np.sqrt(np.mean(d * d)))
            if best is None or rms < best[0]:
                best = (rms, e1, e2, c1, c2)
        assert best is not None  # the first of the 25 angles sets it
        rms, e1, e2, c1, c2 = best
        m1, m2 = 0.5 * (c1.max() + c1.min()), 0.5 * (c2.max() + c2.min())
        return _Rectangle(xy.mean(axis=0) + m1 * e1 + m2 * e2, e1, e2, float(np.ptp(c1)), float(np.ptp(c2)), rms)
    o = xy.mean(axis=0)
    q = xy - o
    th = np.radians(np.arange(0.0, 90.0, 1.0))
    c1 = q @ np.stack([np.cos(th), np.sin(th)])  # (N, A)
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


def _densest(c: np.ndarray, noise: float) -> float:
    """Where the values ``c`` [m] crowd most: a face seen squarely, from its points'
    coordinate along its normal. Not their nearest: that is the depth noise's extreme,
    nearer than the face (from 1.0-1.3 m it puts a carton's centre about 6 mm short;
    this, about 1 mm). The
    peak of their density (smoothed over the noise ``noise``), then the mean of the values
    within twice that of it: a few points of a face seen at a grazing angle, behind the
    one seen squarely, hardly move it."""
    if len(c) > FIT_POINTS:
        c = c[np.linspace(0, len(c) - 1, FIT_POINTS).astype(int)]
    grid = np.arange(c.min(), c.max() + 0.25 * noise, 0.25 * noise)
    density = np.exp(-0.5 * ((c[None, :] - grid[:, None]) / noise) ** 2).sum(axis=1)
    peak = float(grid[int(np.argmax(density))])
    return float(c[np.abs(c - peak) <= 2 * noise].mean())


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
    box = app.box
    assert box is not None  # called for a box's appearance only (_score: app.is_box)
    best: tuple[float, dict] = (0.0, {"reason": "body not visible"})
    for pose, sides, height in categories.Box(*box).rests():
        conf, ev = _score_box_resting(seg, sides, height)
        if conf > best[0] or "reason" in best[1]:
            best = (conf, {**ev, "pose": pose, "width": min(sides)} if "reason" not in ev else ev)
    if best[0] < 0.9:  # no resting face fits well: leaning?
        conf, ev = _score_box_tilted(seg, box)
        if conf > best[0]:
            best = (conf, ev)
    return best


def _box_tolerances(seg: _Segment) -> tuple[float, float, float]:
    """A box fit's tolerances [m]: on a face's length, on a height, and on the points'
    distance from the fitted faces (the depth noise, or a quarter pixel)."""
    px = seg.m_per_px
    return max(0.008, 1.6 * px), max(0.006, 1.5 * px), max(2 * seg.surface_tolerance, 0.25 * px)


FACE_BOW = 0.001  # [m] a flat face may seem to bow this much (edge pixels, the render
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
    for side, vals, lim, sgn in (
        ("left", lat_all, lat_all.max(), 1),
        ("right", lat_all, lat_all.min(), -1),
        ("top", z_all, z_all.max(), 1),
        ("bottom", z_all, z_all.min(), -1),
    ):
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
        open_ends.append(ends)  # [low end open, high end open]
    if all(any(e) for e in open_ends) or any(all(e) for e in open_ends):
        return 0.0, {"reason": "too little of it in view", "extents": ext}
    dims = [float(d) for d in box]
    best: tuple[float, tuple[int, int, int], list[float]] | None = None
    for i0, i1, i2 in ((0, 1, 2), (1, 0, 2), (0, 2, 1), (2, 0, 1), (1, 2, 0), (2, 1, 0)):
        true = [dims[i0], dims[i1]]
        errs = [ext[k] - true[k] if not any(open_ends[k]) else max(0.0, ext[k] - true[k]) for k in (0, 1)]
        e = math.sqrt(float(np.mean(np.square(errs))))
        if best is None or e < best[0]:
            best = (e, (i0, i1, i2), true)
    assert best is not None  # the first of the six assignments sets it
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
            if open_ends[k][1]:  # the low end is in view
                centre = centre + (float(s.min()) + 0.5 * true[k]) * a
            else:
                centre = centre + (float(s.max()) - 0.5 * true[k]) * a
    by_size = {assign[0]: axes[0], assign[1]: axes[1], assign[2]: n}  # assign: a permutation of 0, 1, 2
    box_axes = [by_size[k] for k in range(3)]
    up = box_axes[2] if box_axes[2][2] >= 0 else -box_axes[2]
    tilt = math.acos(min(1.0, abs(float(up[2]))))
    if not UPRIGHT_TILT < tilt < LYING_TILT:
        return 0.0, {"reason": "not leaning", "tilt": tilt}
    # its corners: the lowest on the support, nothing of it seen above the highest
    half = [0.5 * dims[k] * box_axes[k] for k in range(3)]
    corners = np.array(
        [centre + sx * half[0] + sy * half[1] + sz * half[2] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    )
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
                e_depth = e_depth if e_depth > 0 else 0.5 * e_depth  # seen at an angle: shorter
    # the face must be flat (a mug on its side is not): its edges left out, where the
    # points of a face beside it are as near its plane as the band that took its points
    trim = max(3 * tol_r, 0.004) + px
    s0, s1 = q @ axes[0], q @ axes[1]
    keep = (s0 > s0.min() + trim) & (s0 < s0.max() - trim) & (s1 > s1.min() + trim) & (s1 < s1.max() - trim)
    bow = _bow(s0[keep], s1[keep], off[on][keep])
    z = np.array([e_face / tol_w, max(rms / tol_r, bow), e_base / (2 * tol_h), e_top / tol_h, e_depth / tol_w])
    conf = _confidence(z)
    if any(seg.cut(k) for k in ("left", "right", "top", "bottom")):
        conf *= 0.85
    base_pt = centre - 0.5 * dims[2] * up
    # the side the fingers close across: the box's x or y axis the more level, across the lean
    across = np.cross(up, [0.0, 0.0, 1.0])
    width = dims[0] if abs(float(box_axes[0] @ across)) >= abs(float(box_axes[1] @ across)) else dims[1]
    return conf, {
        "pose": "tilted",
        "axis": centre[:2].copy(),
        "yaw": math.atan2(up[1], up[0]),
        "tilt": tilt,
        "axis_base": base_pt.tolist(),
        "axis_dir": up.tolist(),
        "width": width,
        "face_err": e_face,
        "rect_rms": rms,
        "bow": bow,
        "base_err": e_base,
        "top_err": e_top,
        "depth_err": e_depth,
        "extents": ext,
    }


def _whole_faces(seg: _Segment, side: np.ndarray, rect: _Rectangle) -> list[bool]:
    """Whether each face of ``rect`` (along e1, along e2) that the top-view points
    ``side`` lie on ends in view: it does not reach the segment's left or right side where
    the object may continue out of view (``may_continue``: the image border, or something
    nearer). A face reaches a side when its points come within two pixels of the
    segment's outermost point there, across the view."""
    perp = np.array([-seg.ray[1], seg.ray[0]])  # towards the image's left
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
        reaches_cut = (seg.may_continue("left") and f.max() >= lat.max() - near) or (
            seg.may_continue("right") and f.min() <= lat.min() + near
        )
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
    a, b = min(
        ends,
        key=lambda ab: float(
            np.linalg.norm(rect.c + ab[0] * rect.s1 * rect.e1 + ab[1] * rect.s2 * rect.e2 - seg.cam_xy)
        ),
    )
    corner = rect.c + a * rect.s1 * rect.e1 + b * rect.s2 * rect.e2
    lat_c = float((corner - seg.cam_xy) @ perp)
    margin = 1.5 * seg.m_per_px
    inner = (lat > lat.min() + margin) & (lat < lat.max() - margin)
    z = 0.0
    # the face along e1 runs from the corner by -2a s1 e1; the one along e2 by -2b s2 e2
    for i, (e, n, step) in enumerate(
        ((rect.e1, rect.e2, -2 * a * rect.s1 * rect.e1), (rect.e2, rect.e1, -2 * b * rect.s2 * rect.e2))
    ):
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
    # tangents over FACE_STEP at least: from near, a few pixels' step is within the depth
    # noise, and the direction comes out at random (from 0.33 m a face can come out 25
    # degrees off, and the fit is rejected)
    stride = max(3, math.ceil(FACE_STEP / px))
    rect = _rectangle_fit(side, _face_direction(seg.grid, lo, hi, stride))
    side_cut = seg.cut("left") or seg.cut("right")
    # A side's length is measured only on faces seen well: at a grazing angle a face is
    # a few scattered pixels. The faces along e1 face the camera by |ray . e2|.
    seen = [abs(float(seg.ray @ rect.e2)) >= GRAZING, abs(float(seg.ray @ rect.e1)) >= GRAZING]
    ext = [rect.s1 + px, rect.s2 + px]  # the points stop half a pixel short each side
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
        return ext[i] - true if whole[i] else max(0.0, ext[i] - true)  # cut: only shorter

    axes = [rect.e1, rect.e2]
    fits = []
    for x_is in (0, 1):  # the box's x side along e1, or along e2
        true = [bx, by] if x_is == 0 else [by, bx]
        errs = [err(i, true[i]) for i in (0, 1) if seen[i]]
        fits.append((math.sqrt(float(np.mean(np.square(errs)))), x_is, true))
    e_face, x_is, true = min(fits)
    # the centre: along a side measured, the middle of its extent; along one not seen,
    # half the box behind the face that is seen; along a face cut off, half its length
    # from its end in view
    centre = rect.c.copy()
    perp = np.array([-seg.ray[1], seg.ray[0]])  # towards the image's left
    for i in (0, 1):
        e = axes[i]
        if not seen[i]:  # the face seen squarely has normal +-axes[i]
            away = 1.0 if float(seg.ray @ e) > 0 else -1.0
            near = _densest(side @ e, seg.surface_tolerance)  # that face, nearest the camera
            centre = centre + (near + away * 0.5 * true[i] - float(rect.c @ e)) * e
        elif not whole[i]:
            # towards the cut (+e or -e): the side of the image that is cut off
            to_cut = 1.0 if (float(perp @ e) > 0) == seg.may_continue("left") else -1.0
            end = float(rect.c @ e) - to_cut * 0.5 * ext[i]  # the end in view
            centre = centre + (end + to_cut * 0.5 * true[i] - float(rect.c @ e)) * e
    x_axis = axes[x_is]
    one_face = not all(seen)
    e_h = seg.height - bz
    if seg.cut("top") or seg.occluded["top"]:
        e_h = max(0.0, e_h)  # part of it may be hidden: a lower bound
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
    return conf, {
        "face_err": e_face,
        "height_err": e_h,
        "rect_rms": rect.rms,
        "bow": bow,
        "faces": 1 if one_face else 2,
        "extents": ext,
        "seen": seen,
        "whole": whole,
        "axis": centre,
        "yaw": yaw,
    }
