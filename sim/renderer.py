"""Camera rendering: the sim's own OpenGL renderer (sim/gl_renderer.py, moderngl on a
headless EGL context) when it runs, pybullet's EGL plugin when that loads, the TinyRenderer
otherwise.

``ACTORBT_SIM_RENDERER=gl|egl|tiny`` asks for one (it falls back as above when that one
cannot run); ``ACTORBT_SIM_NO_EGL=1`` means ``tiny`` (no EGL at all).
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import queue
import sys
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from common.quiet_pybullet import pybullet as p

if TYPE_CHECKING:
    from .gl_renderer import GLRenderer

log = logging.getLogger("sim.renderer")

#: the renderers, best first
RENDERERS = ("gl", "egl", "tiny")
_warned: set[str] = set()


def requested_renderer() -> str | None:
    """The renderer the environment asks for (``ACTORBT_SIM_RENDERER``), None: the best."""
    name = os.environ.get("ACTORBT_SIM_RENDERER", "").strip().lower()
    if name:
        if name not in RENDERERS:
            raise ValueError(f"ACTORBT_SIM_RENDERER={name!r}: one of {', '.join(RENDERERS)}")
        return name
    if os.environ.get("ACTORBT_SIM_NO_EGL") == "1":
        return "tiny"
    return None


@contextlib.contextmanager
def _quiet_stdout():
    """The EGL plugin chats from C on fds 1 and 2; keep the CLI's output clean."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved:
            os.close(fd)


class Renderer:
    """Renders RGB + depth buffer for one pybullet client.

    ``name`` is "gl" (sim/gl_renderer.py: the world's visual shapes drawn with moderngl on a
    headless EGL context, Mesa llvmpipe when there is no GPU; about a millisecond a frame),
    "egl" (pybullet's EGL plugin: some 25 ms a frame, most of it a shadow map it draws
    whatever the image) or "tiny" (pybullet's software TinyRenderer, as slow). ``why``
    says why a better one was not taken ("" when the best runs).

    Made before the world's bodies: the EGL plugin only sees shapes created after it loads
    (the GL renderer reads them at each frame and has no such need)."""

    def __init__(self, cid: int, prefer_egl: bool = True, prefer: str | None = None):
        self.cid = cid
        self.name = "tiny"
        self.plugin = -1
        self.gl: GLRenderer | None = None
        self.why_not_egl = "not requested"
        self._sizes_seen: set[tuple[int, int]] = set()  # (width, height) rendered so far
        wanted = prefer or requested_renderer()
        if wanted is not None and wanted not in RENDERERS:
            raise ValueError(f"renderer {wanted!r}: one of {', '.join(RENDERERS)}")
        order = list(RENDERERS[RENDERERS.index(wanted) :]) if wanted else list(RENDERERS)
        if not prefer_egl and "egl" in order:
            order.remove("egl")
        reasons = []
        if wanted and wanted != "gl":
            reasons.append(f"{wanted} asked for")
        for name in order:
            if name == "gl":
                why = self._try_gl()
            elif name == "egl":
                self._try_egl()
                why = self.why_not_egl
            else:
                self.name, why = "tiny", ""
            if not why:
                break
            reasons.append(f"{name}: {why}")
        self.why = "; ".join(reasons)
        if self.name != (wanted or "gl") and self.why not in _warned:
            _warned.add(self.why)
            log.warning("camera renderer: %s (%s)", self.name, self.why)
        else:
            log.info("camera renderer: %s%s", self.name, f" ({self.why})" if self.why else "")

    def _try_gl(self) -> str:
        """ "" when the GL renderer runs here (it draws a frame to prove it), else why not."""
        try:
            from .gl_renderer import GLRenderer

            gl = GLRenderer(self.cid)
        except Exception as e:  # no moderngl, no EGL, no OpenGL 3.3
            return str(e) or type(e).__name__
        try:
            view = p.computeViewMatrix([0, 0, 1], [1, 0, 1], [0, 0, 1])
            proj = p.computeProjectionMatrixFOV(60, 1.0, 0.05, 10.0)
            rgb, depth = gl.render(4, 4, view, proj)
            ok = rgb.shape == (4, 4, 3) and depth.shape == (4, 4)
        except Exception as e:  # pragma: no cover - depends on the machine
            gl.close()
            return f"GL render failed: {e}"
        if not ok:  # pragma: no cover
            gl.close()
            return "GL render returned nothing"
        self.gl, self.name = gl, "gl"
        return ""

    def _try_egl(self):
        self.why_not_egl = ""
        spec = importlib.util.find_spec("eglRenderer")
        if spec is None or not spec.origin:
            self.why_not_egl = "pybullet's eglRenderer module is not installed"
            return
        with _quiet_stdout():
            plugin = p.loadPlugin(spec.origin, "_eglRendererPlugin", physicsClientId=self.cid)
        if plugin < 0:
            self.why_not_egl = "eglRenderer plugin failed to load (libegl1/libegl-mesa0 missing?)"
            return
        self.plugin = plugin
        # prove it renders: a 2x2 frame must come back
        try:
            with _quiet_stdout():
                w, h, rgb, _, _ = p.getCameraImage(
                    4,
                    4,
                    renderer=p.ER_BULLET_HARDWARE_OPENGL,
                    flags=p.ER_NO_SEGMENTATION_MASK,
                    physicsClientId=self.cid,
                )
            ok = (w, h) == (4, 4) and np.asarray(rgb).size == 64
        except Exception as e:  # pragma: no cover - depends on the machine
            ok, self.why_not_egl = False, f"EGL render failed: {e}"
        if not ok:
            self.close()
            self.why_not_egl = getattr(self, "why_not_egl", "") or "EGL render returned nothing"
            return
        # no shadows: cheaper, and the same look as the TinyRenderer fallback
        p.configureDebugVisualizer(p.COV_ENABLE_SHADOWS, 0, physicsClientId=self.cid)
        self.name = "egl"
        self.why_not_egl = ""

    def render(self, width, height, view, projection, light_direction=None):
        """-> (rgb uint8 [h, w, 3], depth buffer float32 [h, w] in 0..1). ``light_direction``
        (towards the light, world frame): None leaves pybullet's default light."""
        if self.gl is not None:
            try:
                return self.gl.render(width, height, view, projection, light_direction=light_direction)
            except Exception:
                # the EGL plugin cannot come now (it misses the shapes made before it)
                log.exception("camera renderer: gl failed; the TinyRenderer from now on")
                self._close_gl()
                self.name = "tiny"
                self.why = "gl failed while rendering"
        renderer = p.ER_BULLET_HARDWARE_OPENGL if self.name == "egl" else p.ER_TINY_RENDERER
        first = (width, height) not in self._sizes_seen  # the plugin chats on a new size
        self._sizes_seen.add((width, height))
        light = {} if light_direction is None else {"lightDirection": list(light_direction)}
        with _quiet_stdout() if first and self.name == "egl" else contextlib.nullcontext():
            _, _, rgba, depth, _ = p.getCameraImage(
                width,
                height,
                view,
                projection,
                renderer=renderer,
                flags=p.ER_NO_SEGMENTATION_MASK,
                shadow=0,
                physicsClientId=self.cid,
                **light,
            )
        rgba = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
        depth = np.asarray(depth, dtype=np.float32).reshape(height, width)
        return np.ascontiguousarray(rgba[:, :, :3]), depth

    def _close_gl(self):
        gl, self.gl = self.gl, None
        if gl is not None:
            try:
                gl.close()
            except Exception:  # pragma: no cover - a context already gone
                log.debug("closing the GL renderer", exc_info=True)

    def close(self):
        self._close_gl()
        if self.plugin >= 0:
            try:
                with _quiet_stdout():
                    p.unloadPlugin(self.plugin, physicsClientId=self.cid)
            except p.error:
                pass
            self.plugin = -1


#: a call handed to the GL thread: fn, args, kwargs, a box for (ok, its result or exception),
#: an event set once the box is filled
_Call = tuple[Callable[..., object], tuple[object, ...], dict[str, object], list[tuple[bool, object]], threading.Event]


class GLThread:
    """A thread that owns a world's OpenGL (EGL) context.

    EGL contexts are current on one thread only, and the EGL plugin registers visual shapes
    with OpenGL as they are created: so loading the plugin, creating anything visible and
    rendering must all happen on the same thread. Physics steps may run elsewhere (callers
    wait for their call, so pybullet is never used by two threads at once)."""

    def __init__(self, name="actorbt-sim-gl"):
        self._q: queue.SimpleQueue[_Call | None] = queue.SimpleQueue()  # None: stop
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def _run(self):
        while True:
            item = self._q.get()
            if item is None:
                return
            fn, args, kwargs, box, done = item
            try:
                box.append((True, fn(*args, **kwargs)))
            except BaseException as e:  # handed to the caller
                box.append((False, e))
            done.set()

    def call(self, fn, *args, **kwargs):
        if threading.current_thread() is self._thread:
            return fn(*args, **kwargs)
        if not self._thread.is_alive():
            raise RuntimeError("the simulator's GL thread has stopped")
        box: list = []
        done = threading.Event()
        self._q.put((fn, args, kwargs, box, done))
        done.wait()
        ok, value = box[0]
        if not ok:
            raise value
        return value

    def stop(self):
        if self._thread.is_alive():
            self._q.put(None)
            if threading.current_thread() is not self._thread:
                self._thread.join(timeout=5.0)
