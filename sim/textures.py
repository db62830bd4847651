"""Textured bodies for worlds that draw labels (``appearance: {labels: true}``): a
category's printed :class:`categories.Label` as a procedural texture on a mesh of its shape.

pybullet's primitive cylinders carry no usable UV coordinates, so a labelled object's
*visual* is a mesh written here as an OBJ with UVs (its collision shape stays the
primitives). The texture's ``v`` runs up the side (0 at the base, ``SIDE_V`` at the top);
the rows above ``CAP_V`` are plain body colour for the caps and the shoulders, which map
there. ``u`` runs once around the body.

Files go to a cache folder (``ACTORBT_SIM_CACHE`` or the temp folder), named by a hash of
their content, so the same texture or mesh is written once.
"""

from __future__ import annotations

import colorsys
import hashlib
import math
import os
import tempfile
import zlib
from pathlib import Path

import numpy as np

SIDE_V = 0.90  # the side wall spans v 0..SIDE_V
CAP_V = 0.95  # caps and shoulders sample the texture here (body colour)
TEX_W, TEX_H = 256, 256
SEGMENTS = 48  # facets around a body of revolution


def cache_dir() -> Path:
    d = Path(os.environ.get("ACTORBT_SIM_CACHE") or Path(tempfile.gettempdir()) / f"actorbt_sim_{os.getuid()}")
    d.mkdir(parents=True, exist_ok=True)
    return d


def _write_once(data: bytes, suffix: str) -> Path:
    path = cache_dir() / (hashlib.sha1(data).hexdigest()[:20] + suffix)
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)
    return path


def png_bytes(img: np.ndarray) -> bytes:
    """An RGB uint8 image [h, w, 3] as PNG bytes (no imaging library needed)."""
    img = np.ascontiguousarray(img, dtype=np.uint8)
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[r].tobytes() for r in range(h))

    def chunk(tag, data):
        c = tag + data
        return len(data).to_bytes(4, "big") + c + zlib.crc32(c).to_bytes(4, "big")

    head = w.to_bytes(4, "big") + h.to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")


def _u8(rgba) -> np.ndarray:
    return np.clip(np.round(np.asarray(rgba[:3], dtype=float) * 255), 0, 255).astype(np.uint8)


def print_mask(width: int, height: int, coverage: float, key: str) -> np.ndarray:
    """Bool [height, width]: print marks covering ``coverage`` of a label band, laid out as
    a logo block and lines of lettering (the same ``key`` gives the same marks)."""
    if coverage <= 0 or width < 1 or height < 1:
        return np.zeros((height, width), bool)
    rng = np.random.default_rng(zlib.crc32(key.encode()))
    score = rng.uniform(0.0, 0.05, (height, width))  # breaks ties
    # lettering: rows of glyph cells separated by gaps
    line_h = max(3, height // 6)
    glyph_w = max(2, line_h // 2)
    for top in range(0, height, line_h + max(1, line_h // 2)):
        x = int(rng.integers(0, glyph_w))
        while x < width:
            w = int(rng.integers(max(1, glyph_w // 2), glyph_w + 1))
            if rng.random() < 0.8:
                score[top : top + line_h, x : x + w] += rng.uniform(0.3, 0.6)
            x += w + max(1, glyph_w // 3) + (glyph_w if rng.random() < 0.15 else 0)  # spaces
    # a logo: a bold ellipse, about a third of the print
    yy, xx = np.mgrid[0:height, 0:width]
    area = max(coverage / 3, 0.02) * width * height
    ry = 0.4 * height
    rx = min(area / (math.pi * ry), 0.2 * width)
    cx = width * rng.uniform(0.15, 0.85)
    e = ((xx - cx) / rx) ** 2 + ((yy - height / 2) / ry) ** 2
    score[e <= 1] += 0.9
    # exactly ``coverage`` of the band: the highest scores
    thr = np.quantile(score, 1.0 - coverage)
    return score > thr if coverage < 1 else np.ones_like(score, bool)


def label_texture(body_rgba, label, height: float, key: str) -> np.ndarray:
    """RGB uint8 [TEX_H, TEX_W, 3]: the body colour with ``label`` (a categories.Label or
    None) around it, laid out as the meshes of this module map it."""
    img = np.empty((TEX_H, TEX_W, 3), np.uint8)
    img[:] = _u8(body_rgba)
    if label is not None:
        # image row 0 is the top of the texture (v = 1)
        def row(v):
            return int(round((1.0 - v) * TEX_H))

        r0 = row(SIDE_V * min(label.top, height) / height)
        r1 = row(SIDE_V * label.bottom / height)
        if r1 > r0:
            band = img[r0:r1]
            band[:] = _u8(label.rgba)
            band[print_mask(TEX_W, r1 - r0, label.coverage, key)] = _u8(label.print_rgba)
    return img


def texture_file(img: np.ndarray) -> Path:
    return _write_once(png_bytes(img), ".png")


# ----------------------------------------------------------------------------- meshes
Vec3 = tuple[float, float, float]  # a vertex or a normal
UV = tuple[float, float]
Corner = tuple[int, int, int]  # a face corner: (vertex, uv, normal) indices from 0


def _obj_text(vs: list[Vec3], vts: list[UV], vns: list[Vec3], faces: list[list[Corner]], tag: str = "") -> bytes:
    out = ["# actorbt sim: a labelled body (sim/textures.py)" + (f" for {tag}" if tag else "")]
    out += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vs]
    out += [f"vt {u:.6f} {v:.6f}" for u, v in vts]
    out += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vns]
    out += ["f " + " ".join(f"{a + 1}/{b + 1}/{c + 1}" for a, b, c in f) for f in faces]
    return ("\n".join(out) + "\n").encode()


def revolution_obj(sections, segments: int = SEGMENTS, tag: str = "") -> Path:
    """OBJ of a body of revolution (``sections``: bottom-up ``(top, radius)`` as in
    categories.Revolution), its frame at the centre of its bounding box, with UVs.
    ``tag`` makes the file its own (pybullet shares a mesh file's visual shape, and with it
    the texture, between the bodies that load it)."""
    height = sections[-1][0]
    z0 = -height / 2
    vs: list[Vec3] = []
    vts: list[UV] = []
    vns: list[Vec3] = []
    faces: list[list[Corner]] = []
    cap_vt = len(vts)
    vts.append((0.5, CAP_V))
    up, down = len(vns), len(vns) + 1
    vns += [(0, 0, 1), (0, 0, -1)]
    ring_n = len(vns)
    for j in range(segments):
        a = 2 * math.pi * j / segments
        vns.append((math.cos(a), math.sin(a), 0.0))

    def ring(r, z):
        start = len(vs)
        for j in range(segments):
            a = 2 * math.pi * j / segments
            vs.append((r * math.cos(a), r * math.sin(a), z))
        return start

    def disc(r_out, r_in, z, normal):
        """A flat ring (r_in 0: a full disc) at z, facing ``normal`` (up or down)."""
        o = ring(r_out, z)
        if r_in > 0:
            i = ring(r_in, z)
        else:
            i = len(vs)
            vs.append((0.0, 0.0, z))
        for j in range(segments):
            k = (j + 1) % segments
            a, b = o + j, o + k
            if r_in > 0:
                c, d = i + k, i + j
                quad = [a, b, c, d] if normal == up else [d, c, b, a]
                faces.append([(v, cap_vt, normal) for v in quad])
            else:
                tri = [a, b, i] if normal == up else [i, b, a]
                faces.append([(v, cap_vt, normal) for v in tri])

    bottom, prev_r = 0.0, None
    for n, (top, r) in enumerate(sections):
        if prev_r is None:
            disc(r, 0.0, z0, down)
        elif prev_r != r:
            # the step between sections faces up where the body narrows
            disc(max(prev_r, r), min(prev_r, r), z0 + bottom, up if r < prev_r else down)
        lo, hi = ring(r, z0 + bottom), ring(r, z0 + top)
        vt0 = len(vts)
        for j in range(segments + 1):
            vts.append((j / segments, SIDE_V * bottom / height))
            vts.append((j / segments, SIDE_V * top / height))
        for j in range(segments):
            k = (j + 1) % segments
            faces.append(
                [
                    (lo + j, vt0 + 2 * j, ring_n + j),
                    (lo + k, vt0 + 2 * (j + 1), ring_n + k),
                    (hi + k, vt0 + 2 * (j + 1) + 1, ring_n + k),
                    (hi + j, vt0 + 2 * j + 1, ring_n + j),
                ]
            )
        bottom, prev_r = top, r
    disc(sections[-1][1], 0.0, z0 + height, up)
    return _write_once(_obj_text(vs, vts, vns, faces, tag), ".obj")


def box_obj(sx: float, sy: float, sz: float, tag: str = "") -> Path:
    """OBJ of a box, its frame at its centre; the texture's u wraps once around the four
    sides (as on a body of revolution), top and bottom sample the body colour."""
    hx, hy, hz = sx / 2, sy / 2, sz / 2
    corners = [(hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]  # counter-clockwise from +x
    perim = 2 * (sx + sy)
    vs: list[Vec3] = []
    vts: list[UV] = []
    vns: list[Vec3] = []
    faces: list[list[Corner]] = []
    u = 0.0
    for i in range(4):
        (x0, y0), (x1, y1) = corners[i], corners[(i + 1) % 4]
        length = math.hypot(x1 - x0, y1 - y0)
        nx, ny = (y1 - y0) / length, -(x1 - x0) / length
        vn = len(vns)
        vns.append((nx, ny, 0.0))
        v = len(vs)
        vs += [(x0, y0, -hz), (x1, y1, -hz), (x1, y1, hz), (x0, y0, hz)]
        t = len(vts)
        u1 = u + length / perim
        vts += [(u, 0.0), (u1, 0.0), (u1, SIDE_V), (u, SIDE_V)]
        faces.append([(v + k, t + k, vn) for k in range(4)])
        u = u1
    cap = len(vts)
    vts.append((0.5, CAP_V))
    up, down = len(vns), len(vns) + 1
    vns += [(0, 0, 1), (0, 0, -1)]
    top, bot = len(vs), len(vs) + 4
    vs += [(x, y, hz) for x, y in corners] + [(x, y, -hz) for x, y in corners]
    faces.append([(top + k, cap, up) for k in range(4)])
    faces.append([(bot + k, cap, down) for k in (3, 2, 1, 0)])
    return _write_once(_obj_text(vs, vts, vns, faces, tag), ".obj")


def shape_obj(shape, tag: str = "") -> Path:
    """The mesh of a categories shape (Revolution or Box); see ``revolution_obj`` for
    ``tag``."""
    if getattr(shape, "kind", "") == "box":
        return box_obj(shape.x, shape.y, shape.z, tag)
    return revolution_obj(shape.sections, tag=tag)


# ----------------------------------------------------------------------------- colour
def jitter_rgba(rgba, rng, hue: float = 0.0, value: float = 0.0, saturation: float = 0.0):
    """``rgba`` with its hue turned by up to ``hue`` (fraction of the circle), its
    brightness and saturation scaled by up to ``value`` and ``saturation``, all drawn from
    ``rng``; alpha kept."""
    r, g, b = (float(c) for c in rgba[:3])
    h, s, v = colorsys.rgb_to_hsv(r, g, b)
    h = (h + rng.uniform(-hue, hue)) % 1.0 if hue else h
    s = min(1.0, max(0.0, s * (1 + rng.uniform(-saturation, saturation)))) if saturation else s
    v = min(1.0, max(0.0, v * (1 + rng.uniform(-value, value)))) if value else v
    out = colorsys.hsv_to_rgb(h, s, v)
    return tuple(float(c) for c in out) + (float(rgba[3]) if len(rgba) > 3 else 1.0,)
