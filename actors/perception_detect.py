"""The detection pipeline: :func:`detect` (a frame's segments named by the best fitting
appearance, and located) and :func:`combine_sightings` (one estimate from several)."""

from __future__ import annotations

import math

import numpy as np

from .camera import RGBDFrame
from .perception_box import _box_centre, _score_box
from .perception_colour import SATURATION_SHARE, Appearance, registered_appearances
from .perception_fit import UPRIGHT_TILT
from .perception_round import _score_posed, _score_upright, fit_circle_fixed
from .perception_segments import MAX_UNKNOWN_SIZE, _Segment, _segments, backproject

PATCH_SHARE = 0.4  # a segment whose surroundings continue it in colour this much
#                         (or more) is a patch of something larger

UNKNOWN = "unknown"


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


def _base(seg: _Segment, app: Appearance | None, evidence: dict) -> float:
    """The height of an object's base [m]: the lowest part of it in view, or, for one
    standing or leaning with a label of another colour whose surface goes on below its
    colour, that label's top less the label's height above the base (a table's edge can
    hide a bottle's body below its label: taken at the label's top, the base would be
    14 cm too high, and the arm sent out of reach)."""
    if app is None or app.label is None or evidence.get("pose", "upright") == "lying" or not seg.continues_below:
        return seg.base
    return seg.base - app.label[1]  # (a leaning one's is a little less; its lean, seen so, is noise)


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
    out: list[dict] = []
    for seg in _segments(frame, P, list(apps.values())):
        if seg.continued > PATCH_SHARE:
            continue  # a patch of furniture, of any shape
        best, best_conf, evidence = None, 0.0, {}
        for candidate in apps.values():
            conf, ev = _score(seg, candidate)
            if conf > best_conf:
                best, best_conf, evidence = candidate, conf, ev
        app: Appearance | None  # the category's, None for an object of no known category
        if best is not None and best_conf >= best.min_confidence:
            category, conf, app = best.name, best_conf, best
        else:
            category, app = UNKNOWN, None
            conf = 1.0 - best_conf
        if app is not None:
            c, r = evidence["axis"], app.body_radius
        else:
            c, r = _axis(seg)
        widths = [wd for hm, wd in seg.band_widths(max(0.01, 1.6 * seg.m_per_px)) if app is None or hm < app.body_top]
        width = float(np.median(widths)) if widths else 2 * r
        if app is not None and (seg.cut("left") or seg.cut("right") or evidence.get("pose", "upright") != "upright"):
            width = evidence.get("width", 2 * r)  # partly out of view: the model's width
        if app is None and (width > MAX_UNKNOWN_SIZE[0] or seg.height > MAX_UNKNOWN_SIZE[1] or seg.in_structure > 0.5):
            continue  # a wall, furniture (or a patch of it)
        base = _base(seg, app, evidence)
        b = T_base_map @ np.array([c[0], c[1], base, 1.0])
        out.append(
            {
                "category": category,
                "x": float(c[0]),
                "y": float(c[1]),
                "z": float(base),
                "height": float(seg.top - base),
                "width": width,
                "distance": float(math.hypot(b[0], b[1])),
                "bearing": float(math.atan2(b[1], b[0])),
                "confidence": round(float(conf), 3),
                "pixel": [round(seg.u, 1), round(seg.v, 1)],
                "colour": seg.colour,
                "truncated": [k for k in ("left", "right", "top", "bottom") if seg.cut(k)],
                "stamp": frame.stamp,
                "frame": "map",
            }
        )
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


#: sightings that see at least this share of the most an object was seen of (its height)
#: tell its base's height
BASE_SEEN = 0.8


def base_height(sightings: list[dict]) -> float:
    """The height [m] of the base of an object seen in ``sightings`` (of one object): the
    median ``z`` of those that show most of its height. Perception puts the base at the
    lowest part in view, so from near, looking down on a table, it is the object's top."""
    most = max(float(s.get("height") or 0.0) for s in sightings)
    return float(np.median([s["z"] for s in sightings if float(s.get("height") or 0.0) >= BASE_SEEN * most]))


def combine_sightings(
    sightings: list[dict], looks: int, gate: float = 0.08, near: tuple[float, float] | None = None, within: float = 0.3
) -> dict | None:
    """One estimate from several detections of possibly several objects.

    Detections are grouped by position (within ``gate`` [m] of a group's median); the group
    seen most often (then the nearest) wins. Its position is the median after dropping
    sightings more than max(2 cm, 3 MAD) from the first median; its category the majority.
    With ``near`` (x, y [m]), only detections within ``within`` [m] of it count: what is
    at a place, not the nearest or most seen object anywhere in view.
    """
    if near is not None:
        sightings = [d for d in sightings if math.hypot(d["x"] - near[0], d["y"] - near[1]) <= within]
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
    m[2] = base_height(kept_c)
    last = max(kept_c, key=lambda s: s["stamp"])
    est = dict(last)
    est.update(
        {
            "category": category,
            "x": float(m[0]),
            "y": float(m[1]),
            "z": float(m[2]),
            "height": float(np.median([s["height"] for s in kept_c])),
            "width": float(np.median([s["width"] for s in kept_c])),
            "confidence": round(float(np.median([s["confidence"] for s in kept_c])) * len(kept_c) / max(looks, 1), 3),
            "sightings": len(kept_c),
            "looks": looks,
            "spread": float(np.max(np.hypot(*(xyz[:, :2] - m[:2]).T))) if len(kept_c) > 1 else 0.0,
        }
    )
    return est
