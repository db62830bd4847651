"""Triangles for the GL camera renderer (sim/gl_renderer.py): pybullet's visual shapes as
triangle soups, and the images their textures come from.

A mesh here is ``(positions, normals, uvs)``: float32 arrays [n, 3], [n, 3], [n, 2], three
rows a triangle, counter-clockwise seen from outside, in the shape's own frame (pybullet's
conventions: a box's ``dimensions`` are its full extents, a cylinder's and a capsule's are
``(length, radius)`` along z, a sphere's ``(radius, ...)``, a mesh's its scale).

Meshes from files (Wavefront OBJ, STL) are parsed once per process and kept; an OBJ's
texture is its material's ``map_Kd`` (as pybullet's loader takes it). The labelled bodies
of sim/textures.py get their texture from pybullet's ``changeVisualShape`` instead, which
pybullet does not report back: their OBJ names the PNG in its first comment line (see
:func:`texture_for_mesh`).
"""

from __future__ import annotations

import functools
import math
import os
import re
import struct
from pathlib import Path

import numpy as np


#: facets around a cylinder or a capsule (pybullet's own renderers use 32; these carry
#: smooth normals, so the shading is that of a round body), and around a sphere
SEGMENTS = 48
SPHERE_SEGMENTS = 24


def _tri(pos, nrm, uv):
    return (
        np.ascontiguousarray(pos, np.float32),
        np.ascontiguousarray(nrm, np.float32),
        np.ascontiguousarray(uv, np.float32),
    )


def _quads(corners, normals, uvs):
    """Quads [q, 4, 3] (counter-clockwise from outside) -> triangles (0 1 2, 0 2 3)."""
    order = [0, 1, 2, 0, 2, 3]
    return (corners[:, order].reshape(-1, 3), normals[:, order].reshape(-1, 3), uvs[:, order].reshape(-1, 2))


def box(half) -> tuple:
    """A box of half extents ``half`` (hx, hy, hz), flat normals, each face's uv 0..1."""
    hx, hy, hz = (float(h) for h in half)
    faces = []
    # (normal, the face's u axis, its v axis): corners centre +- u +- v
    for normal, u_axis, v_axis in (
        ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
        ((-1, 0, 0), (0, -1, 0), (0, 0, 1)),
        ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
    ):
        faces.append((np.array(normal, float), np.array(u_axis, float), np.array(v_axis, float)))
    h = np.array([hx, hy, hz])
    corners, normals, uvs = [], [], []
    for n, u, v in faces:
        c = n * h
        du, dv = u * h, v * h
        corners.append([c - du - dv, c + du - dv, c + du + dv, c - du + dv])
        normals.append([n] * 4)
        uvs.append([(0, 0), (1, 0), (1, 1), (0, 1)])
    return _tri(*_quads(np.array(corners), np.array(normals), np.array(uvs, float)))


def _revolve(profile, segments=SEGMENTS):
    """A body of revolution about z. ``profile``: [(r, z, nr, nz, v)] from the bottom up
    (nr, nz: the surface normal in the r-z plane; v: texture v). Adjacent rows are joined
    by a band of quads."""
    a = np.linspace(0.0, 2 * math.pi, segments + 1)
    ca, sa = np.cos(a), np.sin(a)
    pos, nrm, uv = [], [], []
    for (r0, z0, nr0, nz0, v0), (r1, z1, nr1, nz1, v1) in zip(profile, profile[1:]):
        if r0 == r1 == 0 or (r0 == r1 and z0 == z1):
            continue
        for j in range(segments):
            k = j + 1
            p00 = (r0 * ca[j], r0 * sa[j], z0)
            p01 = (r0 * ca[k], r0 * sa[k], z0)
            p11 = (r1 * ca[k], r1 * sa[k], z1)
            p10 = (r1 * ca[j], r1 * sa[j], z1)
            n00 = (nr0 * ca[j], nr0 * sa[j], nz0)
            n01 = (nr0 * ca[k], nr0 * sa[k], nz0)
            n11 = (nr1 * ca[k], nr1 * sa[k], nz1)
            n10 = (nr1 * ca[j], nr1 * sa[j], nz1)
            u0, u1 = j / segments, k / segments
            quad = [(p00, n00, (u0, v0)), (p01, n01, (u1, v0)), (p11, n11, (u1, v1)), (p10, n10, (u0, v1))]
            # a row on the axis makes a fan of triangles, not quads
            corners = (0, 2, 3) if r0 == 0 else (0, 1, 2) if r1 == 0 else (0, 1, 2, 0, 2, 3)
            for i in corners:
                pos.append(quad[i][0])
                nrm.append(quad[i][1])
                uv.append(quad[i][2])
    return _tri(pos, nrm, uv)


def cylinder(length: float, radius: float, segments=SEGMENTS) -> tuple:
    """A cylinder along z, centred, with flat caps."""
    h = length / 2
    return _revolve(
        [
            (0.0, -h, 0, -1, 0.0),
            (radius, -h, 0, -1, 0.0),
            (radius, -h, 1, 0, 0.0),
            (radius, h, 1, 0, 1.0),
            (radius, h, 0, 1, 1.0),
            (0.0, h, 0, 1, 1.0),
        ],
        segments,
    )


def sphere(radius: float, segments=SPHERE_SEGMENTS, z_offset=0.0, lo=-90.0, hi=90.0) -> tuple:
    """A sphere (or the band of it between latitudes ``lo`` and ``hi`` degrees)."""
    rows = max(2, int(round(segments / 2 * (hi - lo) / 180)))
    prof = []
    for i in range(rows + 1):
        lat = math.radians(lo + (hi - lo) * i / rows)
        c, s = math.cos(lat), math.sin(lat)
        prof.append((radius * c, z_offset + radius * s, c, s, (lat / math.pi) + 0.5))
    return _revolve(prof, segments)


def capsule(length: float, radius: float, segments=SEGMENTS) -> tuple:
    """A cylinder of ``length`` between two half spheres, along z."""
    h = length / 2
    parts = [
        sphere(radius, segments, -h, -90, 0),
        cylinder_side(length, radius, segments),
        sphere(radius, segments, h, 0, 90),
    ]
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))


def cylinder_side(length, radius, segments=SEGMENTS):
    h = length / 2
    return _revolve([(radius, -h, 1, 0, 0.0), (radius, h, 1, 0, 1.0)], segments)


def plane(size: float = 100.0) -> tuple:
    """pybullet's GEOM_PLANE: z = 0 facing up, drawn ``size`` metres wide."""
    s = size / 2
    c = np.array([[[-s, -s, 0], [s, -s, 0], [s, s, 0], [-s, s, 0]]], float)
    n = np.array([[[0, 0, 1]] * 4], float)
    uv = np.array([[(0, 0), (size, 0), (size, size), (0, size)]], float)
    return _tri(*_quads(c, n, uv))


# ----------------------------------------------------------------------------- files
def _flat_normals(pos):
    t = pos.reshape(-1, 3, 3)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(ln > 0, n / np.maximum(ln, 1e-30), np.array([0.0, 0.0, 1.0]))
    return np.repeat(n, 3, axis=0)


def _parse_mtl(path: Path) -> dict[str, Path]:
    """material name -> its map_Kd path (only materials with one)."""
    out: dict[str, Path] = {}
    name: str | None = None
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return out
    for line in text.splitlines():
        parts = line.strip().split(None, 1)
        if not parts:
            continue
        if parts[0] == "newmtl" and len(parts) > 1:
            name = parts[1].strip()
        elif parts[0] == "map_Kd" and len(parts) > 1 and name is not None:
            # options (-s, -o...) come before the file name: take the last token
            out[name] = path.parent / parts[1].split()[-1]
    return out


def _load_obj(path: Path):
    """(positions, normals, uvs, texture path or None) of a Wavefront OBJ."""
    vs, vts, vns = [], [], []
    tri_v, tri_t, tri_n = [], [], []
    mtl, texture = {}, None
    text = path.read_text(errors="replace")
    for line in text.splitlines():
        if not line or line[0] == "#":
            continue
        parts = line.split()
        if not parts:
            continue
        tag = parts[0]
        if tag == "v":
            vs.append([float(x) for x in parts[1:4]])
        elif tag == "vt":
            vts.append([float(x) for x in parts[1:3]] + [0.0] * (2 - len(parts[1:3])))
        elif tag == "vn":
            vns.append([float(x) for x in parts[1:4]])
        elif tag == "f":
            corners = []
            for c in parts[1:]:
                ids = c.split("/")
                vi = int(ids[0])
                ti = int(ids[1]) if len(ids) > 1 and ids[1] else 0
                ni = int(ids[2]) if len(ids) > 2 and ids[2] else 0
                # 1-based; negative counts back from the latest
                corners.append(
                    (
                        vi - 1 if vi > 0 else len(vs) + vi,
                        (ti - 1 if ti > 0 else len(vts) + ti) if ti else -1,
                        (ni - 1 if ni > 0 else len(vns) + ni) if ni else -1,
                    )
                )
            for k in range(1, len(corners) - 1):
                for corner in (corners[0], corners[k], corners[k + 1]):
                    tri_v.append(corner[0])
                    tri_t.append(corner[1])
                    tri_n.append(corner[2])
        elif tag == "mtllib" and len(parts) > 1:
            mtl.update(_parse_mtl(path.parent / line.split(None, 1)[1].strip()))
        elif tag == "usemtl" and len(parts) > 1 and texture is None:
            texture = mtl.get(parts[1])
    if not tri_v:
        z = np.zeros((0, 3), np.float32)
        return z, z, np.zeros((0, 2), np.float32), None
    V = np.asarray(vs, np.float64)
    pos = V[np.asarray(tri_v)]
    t_idx, n_idx = np.asarray(tri_t), np.asarray(tri_n)
    if vts:
        T = np.vstack([np.asarray(vts, np.float64), [[0.0, 0.0]]])  # -1: the zero row
        uv = T[t_idx]
    else:
        uv = np.zeros((len(pos), 2))
    normals = _flat_normals(pos)
    if vns:
        N = np.asarray(vns, np.float64)
        has = n_idx >= 0
        normals[has] = N[n_idx[has]]
    if texture is None and mtl:
        texture = next(iter(mtl.values()))
    return pos, normals, uv, texture


def _load_stl(path: Path):
    data = path.read_bytes()
    pos = None
    if len(data) >= 84:
        n = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * n == len(data):
            rec = np.frombuffer(
                data, np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=n, offset=84
            )
            pos = rec["v"].reshape(-1, 3).astype(np.float64)
    if pos is None:  # ASCII
        pos = np.array(
            [
                [float(x) for x in m.groups()]
                for m in re.finditer(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data.decode(errors="replace"))
            ]
        )
        pos = pos.reshape(-1, 3)[: len(pos) // 3 * 3]
    return pos, _flat_normals(pos), np.zeros((len(pos), 2)), None


@functools.lru_cache(maxsize=64)
def _load_file(path: str, mtime: float):
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".obj":
        pos, nrm, uv, tex = _load_obj(p)
    elif suffix == ".stl":
        pos, nrm, uv, tex = _load_stl(p)
    else:
        raise ValueError(f"mesh format {suffix!r} is not supported by the GL renderer")
    return (*_tri(pos, nrm, uv), None if tex is None else str(tex))


def mesh_file(path: str, scale) -> tuple:
    """(positions, normals, uvs, texture path or None) of a mesh file at ``scale``."""
    pos, nrm, uv, tex = _load_file(path, os.path.getmtime(path))
    s = np.asarray(scale, np.float32)
    if np.allclose(s, 1.0):
        return pos, nrm, uv, tex
    pos = pos * s
    # normals transform with the inverse scale (then normalise)
    n = nrm / np.where(s == 0, 1.0, s)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    if np.prod(s) < 0:  # a mirroring scale turns the winding: turn it back
        order = np.arange(len(pos)).reshape(-1, 3)[:, ::-1].ravel()
        pos, n, uv = pos[order], n[order], uv[order]
    return pos.astype(np.float32), n.astype(np.float32), uv, tex


_TAG = re.compile(rb"^# actorbt sim: .*?(\S+\.png)\s*$")


def texture_for_mesh(path: str) -> str | None:
    """The texture sim/textures.py made for a labelled body's OBJ: the PNG its first line
    names (``# actorbt sim: a labelled body (sim/textures.py) for can_1 <sha>.png``), in
    the mesh's folder; None for any other file."""
    try:
        with open(path, "rb") as f:
            first = f.readline(400)
    except OSError:
        return None
    m = _TAG.match(first.rstrip(b"\r\n"))
    if not m:
        return None
    tex = Path(path).parent / m.group(1).decode()
    return str(tex) if tex.exists() else None


@functools.lru_cache(maxsize=64)
def _image(path: str, mtime: float) -> np.ndarray:
    try:
        from PIL import Image

        with Image.open(path) as im:
            return np.asarray(im.convert("RGBA"), np.uint8).copy()
    except ImportError:
        import cv2

        img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if img is None:
            raise OSError(f"cannot read {path}") from None
        if img.ndim == 2:
            img = np.stack([img] * 3, axis=-1)
        if img.shape[2] == 3:
            return np.dstack([img[:, :, ::-1], np.full(img.shape[:2], 255, np.uint8)])
        return img[:, :, [2, 1, 0, 3]].copy()


def image(path: str) -> np.ndarray:
    """RGBA uint8 [h, w, 4] of an image file, row 0 the image's top (cached)."""
    return _image(path, os.path.getmtime(path))
