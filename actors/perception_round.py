"""Shape scoring for bodies of revolution (cans, bottles): standing (width profile, a
circle of the body radius, the height in view) or in any pose (an axis fitted in 3-D)."""

from __future__ import annotations

import math

import numpy as np

from . import axis_fit
from .perception_colour import Appearance
from .perception_fit import FIT_POINTS, LYING_TILT, UPRIGHT_TILT, _confidence
from .perception_segments import DEPTH_NOISE, _Segment

MIN_VISIBLE_WIDTH = 0.5  # fraction of its body an object cut by the image border or an
# occluder must show to be classified (a sliver fits any cylinder)


def fit_circle_fixed(xy: np.ndarray, r: float, c0: np.ndarray, iters: int = 12) -> tuple[np.ndarray, float]:
    """Centre of the circle of radius ``r`` through 2-D points ``xy`` (Gauss-Newton from
    ``c0``, Huber-weighted); returns (centre, RMS residual [m])."""
    if len(xy) > FIT_POINTS:  # an even subsample (points come row by row)
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
        if hmid < band or hmid > seg.height - band:  # bottom rim and top rim bands are partial
            continue
        we = 2 * app.radius_at(hmid) * tangent
        if side_cut:
            errs.append(max(0.0, wm - we))  # a cut segment is only narrower
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
        conf *= 0.85  # part of the evidence is out of view
    return conf, {"profile_err": e_prof, "height_err": e_h, "cylinder_rms": rms, "line_rms": flat, "axis": axis}


def _score_posed(seg: _Segment, app: Appearance, direction: np.ndarray) -> tuple[float, dict]:
    """_score for a body of revolution in any pose: its axis is fitted in 3-D (see
    actors/axis_fit.py; from ``direction``), the points' distance from it is checked
    against the radius profile (base at either end: the better fit says which end is the
    base, _profile_fit), and the visible
    length against the height. Evidence: ``pose`` (upright, tilted, lying), ``axis`` (x, y
    of the body's centre), ``yaw`` (lying: the axis's direction modulo pi; tilted: the
    direction it leans to), ``axis_base`` and ``axis_dir`` (3-D).

    The axis is fitted as a cylinder of the body's radius, then on the body alone. A
    tapered body (a cup) fits no cylinder, and its first section is too little of it for
    the body-only fit: when the first section is under half the height and that fit is
    poor, the axis is fitted again to the whole profile, with the base at either end, and
    the best of the fits counts. (A can or a bottle, mostly body, never pays for it.)"""
    cam = seg.frame.T_map_cam[:3, 3]
    fit = axis_fit.fit_axis(*seg.normals(), app.body_radius, cam, direction)
    if fit is None:
        return 0.0, {"reason": "body not visible"}
    side = fit.side
    best = _profile_fit(seg, app, fit)
    if best is not None and len(best[4]) >= 15:  # refit on the body alone (not a neck)
        fit = axis_fit.refine_axis(best[4], app.body_radius, fit.point, fit.direction)
        best = _profile_fit(seg, app, fit)
    conf, evidence = _posed(seg, app, fit, best)
    if conf < PROFILE_REFIT_BELOW and app.body_top < 0.5 * app.height:
        for base_low in (True, False):
            refit = axis_fit.refine_profile_axis(side, app.radii_at, fit.point, fit.direction, base_low)
            c, e = _posed(seg, app, refit, _profile_fit(seg, app, refit))
            if c > conf:
                conf, evidence = c, e
    return conf, evidence


#: a posed body of revolution whose first section is under half its height, scoring less
#: than this on its cylinder fit, is fitted again to its whole radius profile
PROFILE_REFIT_BELOW = 0.5


def _posed(seg: _Segment, app: Appearance, fit: axis_fit.AxisFit, best) -> tuple[float, dict]:
    """_score_posed's score and evidence for one fitted axis and its _profile_fit."""
    tol_r = seg.surface_tolerance
    tol_h = max(0.01, 2.0 * seg.m_per_px)
    cut = seg.cut("left") or seg.cut("right") or seg.cut("top") or seg.cut("bottom")
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
    up = d * sign  # from the base to the top
    base_pt = fit.point + (lo if sign > 0 else hi) * d
    length = hi - lo
    e_len = length - app.height
    if cut or seg.occluded["top"]:
        e_len = max(0.0, e_len)  # part of it out of view: only shorter
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
    return conf, {
        "pose": pose,
        "axis": centre[:2].copy(),
        "yaw": yaw,
        "tilt": tilt,
        "axis_base": base_pt.tolist(),
        "axis_dir": up.tolist(),
        "profile_rms": rms,
        "length_err": e_len,
        "rise_err": e_rise,
    }


def _rise_error(seg: _Segment, app: Appearance, base_pt: np.ndarray, up: np.ndarray) -> float:
    """How much taller [m] the segment stands above its support than the body would, posed
    by its fitted axis (base point ``base_pt``, direction ``up``): from its lowest rim to
    its highest (a lying can rises 2 r). A lower segment counts only when its top is in
    view. An axis fits a flat box's long side as well as a lying can's; its rise does not
    (a 4 cm box is no 6.6 cm can)."""
    across = math.sqrt(max(0.0, 1.0 - float(up[2]) ** 2))  # a rim's vertical half-extent per radius
    rims = [
        (base_pt, app.body_radius),
        (base_pt + app.body_top * up, app.body_radius),
        (base_pt + app.height * up, app.radius_at(app.height - 1e-3)),
    ]
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
        e2 = np.sort(e * e)[: max(1, int(0.85 * len(e)))]
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
