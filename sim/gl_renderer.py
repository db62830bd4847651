"""The camera's own OpenGL renderer: pybullet's visual shapes drawn with moderngl on a
headless EGL context (Mesa llvmpipe without a GPU), one pass for colour, depth and body ids.

Why: pybullet's EGL plugin renders a 4096 x 4096 shadow map on every frame whatever the
image size, and the TinyRenderer rasterises on one core; both cost some 25 ms a frame.
Here a 320 x 240 frame of the house costs what its pixels and triangles cost (one to three
milliseconds on llvmpipe), reading the bodies' poses from pybullet included. Links whose
bounding sphere is out of view are not drawn.

What it draws: every body of the client, as ``getVisualShapeData`` describes it (boxes,
cylinders, spheres, capsules, planes, OBJ and STL meshes, each with its local frame, scale
and colour), at the link poses pybullet has now; textures from an OBJ's material
(``map_Kd``) and the labels of sim/textures.py (see :func:`sim.gl_meshes.texture_for_mesh`),
or any registered with :meth:`GLRenderer.register_texture`. Bodies added, removed or
recoloured are picked up at the next frame (the visuals of movable bodies are compared
every frame; those of fixed bodies when the set of bodies changes, or on :meth:`refresh`).

How it looks: pybullet's shading, ``colour = texel * (a + (1 - a) i)``, ``i = 0.5 + 0.5 n.l``
(0.7 i on faces turned from the light), ``a = 0.5``, the light's direction as given
(pybullet's default otherwise) and its background colour; plus a mild white highlight
(Blinn-Phong) on movable bodies. What it leaves out, on purpose: pybullet's EGL plugin
draws boxes and cylinders with normals smoothed across their edges (a wall or the floor
shades in gradients, far darker than its colour) and shadows from its shadow map, acne
included; here faces are flat, bodies of revolution round, and nothing casts a shadow.
Depth comes back as the OpenGL depth buffer of the same projection matrix, so
:meth:`sim.sensors.CameraModel.linearize` reads it unchanged.

The context belongs to the thread that made it; each call makes it current and releases it,
so one renderer may be used from any one thread at a time.
"""

from __future__ import annotations

import logging
import os
import time
from ctypes.util import find_library
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from common.quiet_pybullet import pybullet as p

from . import gl_meshes

if TYPE_CHECKING:  # an optional dependency: imported where a context is made
    import moderngl

log = logging.getLogger("sim.renderer")

#: pybullet's EGL renderer: the light's direction when none is given (its converter's
#: default), the ambient share of the shading, the weight of the shadow term (pybullet
#: darkens faces turned from the light by it), the clear colour
DEFAULT_LIGHT = (-5.0, -40.0, 200.0)
AMBIENT = 0.5
SHADOW_INTENSITY = 0.3
BACKGROUND = (0.7, 0.7, 0.8)
#: a highlight (Blinn-Phong, white light) on movable bodies (the objects, the robot):
#: strength and exponent. pybullet does not report a shape's specular colour; the scene
#: gives objects 0.1-0.2 and its floor, walls and furniture none or 0.05, so fixed bodies
#: get none
SPECULAR = 0.12
SHININESS = 40.0

_VERTEX = """
#version 330
uniform mat4 u_view;
uniform mat4 u_proj;
uniform sampler2D u_xf;          // per link: 3 texels, the rows of its 3x4 world transform
in vec3 in_pos;
in vec3 in_normal;
in vec2 in_uv;
in vec4 in_color;
in float in_slot;                // the link's row in u_xf
in float in_spec;                // the highlight's strength
in float in_body;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_color;
flat out float v_spec;
flat out float v_body;
void main() {
    int i = int(in_slot + 0.5);
    vec4 r0 = texelFetch(u_xf, ivec2(0, i), 0);
    vec4 r1 = texelFetch(u_xf, ivec2(1, i), 0);
    vec4 r2 = texelFetch(u_xf, ivec2(2, i), 0);
    vec4 p = vec4(in_pos, 1.0);
    vec3 w = vec3(dot(r0, p), dot(r1, p), dot(r2, p));
    v_world = w;
    v_normal = vec3(dot(r0.xyz, in_normal), dot(r1.xyz, in_normal), dot(r2.xyz, in_normal));
    v_uv = in_uv;
    v_color = in_color;
    v_spec = in_spec;
    v_body = in_body;
    gl_Position = u_proj * (u_view * vec4(w, 1.0));
}
"""

_FRAGMENT = """
#version 330
uniform sampler2D u_tex;
uniform vec3 u_light;            // towards the light
uniform vec3 u_cam;
uniform float u_ambient;
uniform float u_shadow;
uniform float u_shininess;
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_color;
flat in float v_spec;
flat in float v_body;
layout(location = 0) out vec4 f_color;
layout(location = 1) out float f_body;
void main() {
    vec4 texel = v_color * texture(u_tex, v_uv);
    vec3 L = normalize(u_light);
    vec3 N = normalize(v_normal);
    float nl = dot(N, L);
    float intensity = 0.5 + 0.5 * clamp(nl, -1.0, 1.0);
    float lit = intensity < 0.5 ? 0.0 : 1.0;
    intensity = (1.0 - u_shadow) * intensity + u_shadow * intensity * lit;
    float spec = 0.0;
    if (nl > 0.0) {
        vec3 to_cam = normalize(u_cam - v_world);
        spec = pow(max(0.0, dot(N, normalize(L + to_cam))), u_shininess) * v_spec;
    }
    float cf = intensity * (1.0 - u_ambient) + u_ambient;
    f_color = vec4(texel.rgb * cf + spec, texel.a);
    f_body = v_body;
}
"""

#: floats per vertex: position 3, normal 3, uv 2, colour 4, link slot 1, highlight 1, body 1
_STRIDE = 15


class GLUnavailable(RuntimeError):
    """The GL renderer cannot run here (no moderngl, no EGL, no OpenGL 3.3)."""


def create_context():
    """A headless OpenGL 3.3 context on EGL (moderngl standalone)."""
    try:
        import moderngl
    except ImportError as e:
        raise GLUnavailable(f"moderngl is not installed ({e})") from None
    # glcontext's settings, passed on as keywords. moderngl's stub types each ``**settings``
    # value as a dict (it means the whole mapping); glcontext takes strings, ints, ...
    settings: dict[str, Any] = {"backend": "egl"}
    if not os.environ.get("GLCONTEXT_LINUX_LIBGL") and find_library("GL") is None:
        # no libGL.so.1 (Debian's libgl1): the GL entry points come through
        # eglGetProcAddress anyway, glcontext only wants a library to open
        egl = find_library("EGL")
        if egl:
            settings["libgl"] = egl
    try:
        ctx = moderngl.create_standalone_context(require=330, **settings)
    except Exception as e:  # glcontext raises plain Exceptions
        raise GLUnavailable(f"no EGL OpenGL 3.3 context: {e}") from None
    return ctx


_available: list = []


def available() -> bool:
    """Whether a GL renderer can run in this process (tried once, then remembered)."""
    if not _available:
        try:
            ctx = create_context()
        except GLUnavailable as e:
            log.info("GL renderer unavailable: %s", e)
            _available.append(False)
        else:
            ctx.release()
            _available.append(True)
    return _available[0]


@dataclass
class _Shape:
    """One visual shape, its triangles in the frame whose pose is read each frame (a
    base's inertial frame, a link's link frame)."""

    body: int
    link: int
    pos: np.ndarray
    normal: np.ndarray
    uv: np.ndarray
    rgba: tuple
    texture: str | None


@dataclass
class _Batch:
    """The triangles of one texture: ``runs`` [k, 3] = (link slot, first vertex, count)."""

    texture: str | None
    transparent: bool
    vbo: moderngl.Buffer
    vao: moderngl.VertexArray
    runs: np.ndarray


def _quat_matrix(q) -> np.ndarray:
    """Rotation matrices [n, 3, 3] of quaternions [n, 4] (x, y, z, w)."""
    q = np.asarray(q, np.float64).reshape(-1, 4)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    n = x * x + y * y + z * z + w * w
    s = np.where(n > 0, 2.0 / np.where(n > 0, n, 1.0), 0.0)
    R = np.empty((len(q), 3, 3))
    R[:, 0, 0] = 1 - s * (y * y + z * z)
    R[:, 0, 1] = s * (x * y - z * w)
    R[:, 0, 2] = s * (x * z + y * w)
    R[:, 1, 0] = s * (x * y + z * w)
    R[:, 1, 1] = 1 - s * (x * x + z * z)
    R[:, 1, 2] = s * (y * z - x * w)
    R[:, 2, 0] = s * (x * z - y * w)
    R[:, 2, 1] = s * (y * z + x * w)
    R[:, 2, 2] = 1 - s * (x * x + y * y)
    return R


def _geometry(v):
    """(positions, normals, uvs, texture) of one getVisualShapeData row in its local frame
    (before the visual frame), None for a shape that has nothing to draw."""
    geom, dims, fname = v[2], v[3], v[4]
    if geom == p.GEOM_BOX:
        return (*gl_meshes.box([d / 2 for d in dims]), None)
    if geom == p.GEOM_CYLINDER:
        return (*gl_meshes.cylinder(dims[0], dims[1]), None)
    if geom == p.GEOM_CAPSULE:
        return (*gl_meshes.capsule(dims[0], dims[1]), None)
    if geom == p.GEOM_SPHERE:
        return (*gl_meshes.sphere(dims[0]), None)
    if geom == p.GEOM_PLANE:
        return (*gl_meshes.plane(), None)
    if geom == p.GEOM_MESH:
        path = fname.decode() if isinstance(fname, bytes) else str(fname)
        if not path or not os.path.exists(path):
            log.warning("GL renderer: body %d: mesh %r not found; not drawn", v[0], path)
            return None
        pos, nrm, uv, tex = gl_meshes.mesh_file(path, dims)
        return pos, nrm, uv, gl_meshes.texture_for_mesh(path) or tex
    return None


class GLRenderer:
    """Draws one pybullet client's bodies with moderngl. ``render`` takes pybullet's view
    and projection matrices (column-major 16-tuples, as ``computeViewMatrix`` and
    ``computeProjectionMatrixFOV`` give them) and returns what ``getCameraImage`` would:
    rgb uint8 [h, w, 3] and the depth buffer float32 [h, w] in 0..1."""

    name = "gl"

    def __init__(self, cid: int, ctx=None):
        self.cid = cid
        self.ctx = ctx if ctx is not None else create_context()
        self._own_ctx = ctx is None
        self._textures_by_id: dict[tuple, str] = {}
        self._bodies: dict[int, dict] = {}  # body -> static, visuals, inertial, shapes
        self._dirty = True
        self._batches: list[_Batch] = []
        self._slots: list[tuple[int, int]] = []  # (body, link) of each row of u_xf
        self._fbo: moderngl.Framebuffer | None = None
        self._fbo_parts: tuple[moderngl.Renderbuffer, ...] = ()  # its colour, body id and depth buffers
        self._fbo_size: tuple[int, int] | None = None
        self._gl_textures: dict[str, moderngl.Texture] = {}
        self._xf: moderngl.Texture | None = None  # the link transforms (u_xf), made by _rebuild
        self.frames = 0
        #: seconds spent: reading pybullet (bodies, poses), issuing the draws, waiting for
        #: the pixels (llvmpipe draws then)
        self.timing = {"scene": 0.0, "draw": 0.0, "read": 0.0}
        with self.ctx:
            self._prog = self.ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
            self._white: moderngl.Texture = self.ctx.texture((1, 1), 4, bytes([255, 255, 255, 255]))
            self._prog["u_tex"].value = 0
            self._prog["u_xf"].value = 1
            self._prog["u_ambient"].value = AMBIENT
            self._prog["u_shadow"].value = SHADOW_INTENSITY
            self._prog["u_shininess"].value = SHININESS

    # ------------------------------------------------------------------ scene
    def register_texture(self, body: int, path: str, link: int | None = None):
        """Draw ``body``'s visuals (on ``link``; None: all its links) with the image at
        ``path``: what a ``changeVisualShape(textureUniqueId=...)`` gave it, which
        pybullet does not report back."""
        self._textures_by_id[(body, link)] = str(path)
        self.refresh()

    def refresh(self):
        """Read every body's visuals again at the next frame."""
        self._bodies.clear()
        self._dirty = True

    def _sync_bodies(self):
        """Pick up added, removed and changed bodies; rebuild the vertex buffers if any."""
        cid = self.cid
        ids = [p.getBodyUniqueId(i, physicsClientId=cid) for i in range(p.getNumBodies(physicsClientId=cid))]
        known = self._bodies
        changed_set = set(ids) != set(known)
        if changed_set:
            for b in [b for b in known if b not in set(ids)]:
                del known[b]
        for b in ids:
            info = known.get(b)
            if info is not None and info["static"] and not changed_set:
                continue  # fixed bodies: read again when the set of bodies changes
            visuals = p.getVisualShapeData(b, physicsClientId=cid)
            if info is None or info["visuals"] != visuals:
                nj = p.getNumJoints(b, physicsClientId=cid)
                dyn = p.getDynamicsInfo(b, -1, physicsClientId=cid)
                info = known[b] = {"static": nj == 0 and dyn[0] == 0, "visuals": visuals, "inertial": (dyn[3], dyn[4])}
                info["shapes"] = [s for s in (self._shape(v, info) for v in visuals) if s is not None]
                self._dirty = True
        if self._dirty or changed_set:
            self._rebuild()

    def _shape(self, v, info) -> _Shape | None:
        body, link = v[0], v[1]
        g = _geometry(v)
        if g is None or len(g[0]) == 0:
            return None
        pos, nrm, uv, tex = g
        tex = self._textures_by_id.get((body, link), self._textures_by_id.get((body, None), tex))
        # the visual frame is given in the link's frame; a link's pose comes as its link
        # frame, the base's as its inertial frame: put the base's triangles in that one
        R = _quat_matrix(v[6])[0]
        t = np.asarray(v[5], np.float64)
        if link < 0:
            ipos, iorn = info["inertial"]
            Ri = _quat_matrix(iorn)[0]
            R, t = Ri.T @ R, Ri.T @ (t - np.asarray(ipos, np.float64))
        pos = (pos.astype(np.float64) @ R.T + t).astype(np.float32)
        nrm = (nrm.astype(np.float64) @ R.T).astype(np.float32)
        return _Shape(body, link, pos, nrm, uv, tuple(float(c) for c in v[7]), tex)

    def _rebuild(self):
        """One vertex buffer per texture (and per opaque / see-through); within it each
        link's triangles in one run, so a link out of view is skipped."""
        shapes = [s for info in self._bodies.values() for s in info["shapes"]]
        self._slots = sorted({(s.body, s.link) for s in shapes})
        slot_of = {k: i for i, k in enumerate(self._slots)}
        # a bounding sphere per link, in its frame
        centre = np.zeros((max(1, len(self._slots)), 3))
        radius = np.zeros(max(1, len(self._slots)))
        by_slot: dict[int, list] = {}
        for s in shapes:
            by_slot.setdefault(slot_of[(s.body, s.link)], []).append(s.pos)
        for i, parts in by_slot.items():
            pts = np.concatenate(parts).astype(np.float64)
            lo, hi = pts.min(0), pts.max(0)
            centre[i] = (lo + hi) / 2
            radius[i] = np.sqrt(((pts - centre[i]) ** 2).sum(1).max())
        self._centre, self._radius = centre, radius
        groups: dict[tuple, list] = {}
        for s in shapes:
            groups.setdefault((s.rgba[3] < 1.0, s.texture or ""), []).append(s)
        ctx = self.ctx
        for b in self._batches:
            b.vao.release()
            b.vbo.release()
        self._batches = []
        for (transparent, tex), group in sorted(groups.items()):
            group.sort(key=lambda s: slot_of[(s.body, s.link)])
            n = sum(len(s.pos) for s in group)
            data = np.empty((n, _STRIDE), np.float32)
            runs: list[list[int]] = []  # [slot, first, count]
            k = 0
            for s in group:
                m, slot = len(s.pos), slot_of[(s.body, s.link)]
                data[k : k + m, 0:3] = s.pos
                data[k : k + m, 3:6] = s.normal
                data[k : k + m, 6:8] = s.uv
                data[k : k + m, 8:12] = s.rgba
                data[k : k + m, 12] = slot
                data[k : k + m, 13] = 0.0 if self._bodies[s.body]["static"] else SPECULAR
                data[k : k + m, 14] = s.body + 1
                if runs and runs[-1][0] == slot:
                    runs[-1][2] += m
                else:
                    runs.append([slot, k, m])
                k += m
            vbo = ctx.buffer(data.tobytes())
            vao = ctx.vertex_array(
                self._prog,
                [
                    (
                        vbo,
                        "3f 3f 2f 4f 1f 1f 1f",
                        "in_pos",
                        "in_normal",
                        "in_uv",
                        "in_color",
                        "in_slot",
                        "in_spec",
                        "in_body",
                    )
                ],
            )
            self._batches.append(_Batch(tex or None, transparent, vbo, vao, np.array(runs, np.int64).reshape(-1, 3)))
        if self._xf is not None:
            self._xf.release()
        self._xf = ctx.texture((3, max(1, len(self._slots))), 4, dtype="f4")
        self._xf_data = np.zeros((max(1, len(self._slots)), 3, 4), np.float32)
        self._dirty = False

    def _update_poses(self):
        """The world transform of every link slot: a base's inertial frame (what
        ``getBasePositionAndOrientation`` gives), a link's link frame. -> (R [n, 3, 3],
        t [n, 3])."""
        cid = self.cid
        slots = self._slots
        pos = np.zeros((max(1, len(slots)), 3))
        quat = np.zeros((max(1, len(slots)), 4))
        quat[:, 3] = 1.0
        by_body: dict[int, list] = {}
        for i, (b, link) in enumerate(slots):
            by_body.setdefault(b, []).append((i, link))
        for b, items in by_body.items():
            links = [(i, link) for i, link in items if link >= 0]
            for i, link in items:
                if link < 0:
                    bp, bq = p.getBasePositionAndOrientation(b, physicsClientId=cid)
                    pos[i], quat[i] = bp, bq
            if links:
                states = p.getLinkStates(
                    b, [link for _, link in links], computeForwardKinematics=1, physicsClientId=cid
                )
                for (i, _), st in zip(links, states):
                    pos[i], quat[i] = st[4], st[5]  # the URDF link frame
        R = _quat_matrix(quat)
        xf = self._xf_data
        xf[:, :, :3] = R
        xf[:, :, 3] = pos
        assert self._xf is not None  # made by _rebuild, which _sync_bodies runs first (_dirty starts True)
        self._xf.write(xf.tobytes())
        return R, pos

    # ------------------------------------------------------------------ drawing
    def _framebuffer(self, width: int, height: int) -> moderngl.Framebuffer:
        if self._fbo_size != (width, height):
            if self._fbo is not None:
                for a in self._fbo_parts:
                    a.release()
                self._fbo.release()
            ctx = self.ctx
            color = ctx.renderbuffer((width, height), 4)
            body = ctx.renderbuffer((width, height), 1, dtype="f4")
            depth = ctx.depth_renderbuffer((width, height))
            self._fbo = ctx.framebuffer(color_attachments=[color, body], depth_attachment=depth)
            self._fbo_parts = (color, body, depth)
            self._fbo_size = (width, height)
        assert self._fbo is not None  # made above for this size, if not at an earlier call
        return self._fbo

    def _texture(self, path: str | None) -> moderngl.Texture:
        if path is None:
            return self._white
        tex = self._gl_textures.get(path)
        if tex is None:
            try:
                img = gl_meshes.image(path)
            except Exception as e:  # a broken file: draw the colour alone
                log.warning("GL renderer: texture %s unreadable (%s); colour only", path, e)
                tex = self._white
            else:
                # GL's first row is v = 0, an image's first row its top (v = 1)
                img = np.ascontiguousarray(img[::-1])
                tex = self.ctx.texture((img.shape[1], img.shape[0]), 4, img.tobytes())
                tex.build_mipmaps()
                tex.repeat_x = tex.repeat_y = True
            self._gl_textures[path] = tex
        return tex

    def _visible(self, R, t, clip):
        """Link slots whose bounding sphere meets the view frustum (``clip``: P V, row-major)."""
        c = np.einsum("nij,nj->ni", R, self._centre) + t
        planes = np.stack(
            [
                clip[3] + clip[0],
                clip[3] - clip[0],
                clip[3] + clip[1],
                clip[3] - clip[1],
                clip[3] + clip[2],
                clip[3] - clip[2],
            ]
        )
        norm = np.linalg.norm(planes[:, :3], axis=1)
        dist = c @ planes[:, :3].T + planes[:, 3]
        return (dist >= -self._radius[:, None] * norm).all(axis=1)

    def render(self, width, height, view, projection, light_direction=None, segmentation=False):
        """-> (rgb uint8 [h, w, 3], depth buffer float32 [h, w] in 0..1), and the body
        ids int32 [h, w] (-1: nothing) as a third item when ``segmentation``."""
        with self.ctx:
            t0 = time.perf_counter()
            self._sync_bodies()
            R, t = self._update_poses()
            V = np.asarray(view, np.float32).reshape(4, 4)  # column-major, as GL takes it
            Pj = np.asarray(projection, np.float32).reshape(4, 4)
            Vm = V.T.astype(np.float64)  # row-major world -> eye
            visible = self._visible(R, t, Pj.T.astype(np.float64) @ Vm)
            t1 = time.perf_counter()
            ctx = self.ctx
            fbo = self._framebuffer(width, height)
            fbo.use()
            ctx.viewport = (0, 0, width, height)
            fbo.clear(*BACKGROUND, 1.0, depth=1.0)
            prog = self._prog
            prog["u_view"].write(V.tobytes())
            prog["u_proj"].write(Pj.tobytes())
            light = DEFAULT_LIGHT if light_direction is None else light_direction
            prog["u_light"].value = tuple(float(x) for x in light)
            prog["u_cam"].value = tuple(float(x) for x in -Vm[:3, :3].T @ Vm[:3, 3])
            assert self._xf is not None  # made by _rebuild (see _update_poses)
            self._xf.use(location=1)
            ctx.enable(ctx.DEPTH_TEST)
            # back faces are culled, as pybullet does: a camera inside a body sees out
            ctx.enable(ctx.CULL_FACE)
            for batch in self._batches:
                runs = batch.runs[visible[batch.runs[:, 0]]]
                if not len(runs):
                    continue
                if batch.transparent:
                    ctx.enable(ctx.BLEND)
                    ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA
                    ctx.depth_mask = False
                self._texture(batch.texture).use(location=0)
                # runs next to each other in the buffer: one draw
                first, end = int(runs[0, 1]), int(runs[0, 1] + runs[0, 2])
                for _, f, n in runs[1:].tolist():
                    if f != end:
                        batch.vao.render(vertices=end - first, first=first)
                        first = f
                    end = f + n
                batch.vao.render(vertices=end - first, first=first)
            ctx.depth_mask = True
            ctx.disable(ctx.BLEND)
            t2 = time.perf_counter()
            rgb = np.frombuffer(fbo.read(components=3, attachment=0), np.uint8).reshape(height, width, 3)
            depth = np.frombuffer(fbo.read(components=1, attachment=-1, dtype="f4"), np.float32).reshape(height, width)
            # GL's rows run bottom-up
            out: list[np.ndarray] = [np.ascontiguousarray(rgb[::-1]), np.ascontiguousarray(depth[::-1])]
            if segmentation:
                ids = np.frombuffer(fbo.read(components=1, attachment=1, dtype="f4"), np.float32).reshape(
                    height, width
                )[::-1]
                # where nothing was drawn the depth buffer keeps its clear value
                out.append(np.where(out[1] >= 1.0, -1, np.rint(ids).astype(np.int32) - 1))
            t3 = time.perf_counter()
        self.frames += 1
        self.timing["scene"] += t1 - t0
        self.timing["draw"] += t2 - t1
        self.timing["read"] += t3 - t2
        return tuple(out)

    def close(self):
        ctx, self.ctx = self.ctx, None
        if ctx is None:
            return
        try:
            with ctx:
                for b in self._batches:
                    b.vao.release()
                    b.vbo.release()
                for t in self._gl_textures.values():
                    if t is not self._white:
                        t.release()
                if self._fbo is not None:
                    self._fbo.release()
                    for a in self._fbo_parts:
                        a.release()
                if self._xf is not None:
                    self._xf.release()
                self._prog.release()
        finally:
            self._batches = []
            self._gl_textures = {}
            if self._own_ctx:
                ctx.release()
