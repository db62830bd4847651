"""The camera's own GL renderer (sim/gl_renderer.py): the same depth and colours as
pybullet's renderer, bodies drawn where they are now (moved, added, removed), labels
drawn from their textures, and the renderer choice falling back cleanly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim import SimWorld
from sim import gl_meshes
from sim import gl_renderer as glr
from sim import renderer as renderer_mod
from common.quiet_pybullet import pybullet as p
from sim.renderer import Renderer

pytestmark = pytest.mark.skipif(not glr.available(), reason="no moderngl / EGL OpenGL 3.3 here")


def _world(monkeypatch, renderer, world="open_floor", seed=0):
    monkeypatch.setenv("ACTORBT_SIM_RENDERER", renderer)
    sim = SimWorld(None, world, seed=seed)
    monkeypatch.delenv("ACTORBT_SIM_RENDERER")
    return sim


@pytest.fixture(scope="module")
def pair():
    """open_floor twice: drawn by the GL renderer and by pybullet's (EGL when it loads here,
    else the TinyRenderer), the can 0.6 m ahead of the robot in both."""
    mp = pytest.MonkeyPatch()
    new = _world(mp, "gl")
    old = _world(mp, "egl")
    for sim in (new, old):
        x, y, yaw = sim.robot_pose()
        sim.set_object_pose("can_1", x + 0.6 * math.cos(yaw), y + 0.6 * math.sin(yaw))
    yield new, old
    new.close()
    old.close()
    mp.undo()


def _view_at(sim, name, dist=0.5, ang=0.4, height=0.3):
    x, y, z = sim.object_pose(name)[:3]
    eye = [x + dist * math.cos(ang), y + dist * math.sin(ang), height]
    return p.computeViewMatrix(eye, [x, y, z], [0, 0, 1])


def _render(sim, view, segmentation=False):
    """(rgb, depth buffer) from the world's renderer; the GL renderer's body ids too with
    ``segmentation``."""
    cam = sim.camera
    light = sim.spec.lighting
    kw = {"light_direction": None if light is None else light.direction}
    if segmentation:
        return sim._gl_call(
            sim.renderer.gl.render, cam.width, cam.height, view, cam.projection(), segmentation=True, **kw
        )
    return sim._gl_call(sim.renderer.render, cam.width, cam.height, view, cam.projection(), **kw)


def test_the_gl_renderer_is_the_default_and_says_so(pair):
    new, old = pair
    assert new.renderer_name == "gl" and new.renderer.why == ""
    assert old.renderer_name in ("egl", "tiny")


def test_depth_matches_pybullets_renderer_within_millimetres(pair):
    new, old = pair
    for view in (_view_at(new, "can_1"), _view_at(new, "bottle_1", 0.8, 2.0), _view_at(new, "box_1", 1.2, -1.0, 0.6)):
        z_new = new.camera.linearize(_render(new, view)[1])
        z_old = old.camera.linearize(_render(old, view)[1])
        both = np.isfinite(z_new) & np.isfinite(z_old)
        assert both.mean() > 0.5
        assert (np.isfinite(z_new) != np.isfinite(z_old)).mean() < 0.002
        dz = np.abs(z_new - z_old)[both]
        assert np.median(dz) < 0.001
        # edges may fall on the other pixel; away from them a few millimetres at most
        assert np.percentile(dz, 98) < 0.005, np.percentile(dz, [50, 90, 98, 99.5])


def test_the_depth_of_the_can_is_where_it_stands(pair):
    new, _ = pair
    rgb, depth = new.render_camera()
    pos, orn = new.link_pose("camera_optical_frame")
    R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
    can = np.array(new.object_pose("can_1")[:3])
    red = (rgb[:, :, 0] > 100) & (rgb[:, :, 1] < 60) & (rgb[:, :, 2] < 60)
    assert red.sum() > 300
    front = R.T @ (can - np.array([0.033, 0, 0]) - np.array(pos))
    assert np.nanmedian(depth[red]) == pytest.approx(front[2], abs=0.01)


def test_a_known_objects_colours_agree(pair):
    new, old = pair
    for name in ("can_1", "bottle_1", "box_1"):
        view = _view_at(new, name)
        body = new.scene.objects[name]
        rgb_new, _, ids = _render(new, view, segmentation=True)
        rgb_old, _ = _render(old, view)
        mask = ids == body
        # the object's inside, away from its outline
        inner = mask & np.roll(mask, 2, 0) & np.roll(mask, -2, 0) & np.roll(mask, 2, 1) & np.roll(mask, -2, 1)
        assert inner.sum() > 200, name
        a = rgb_new[inner].astype(float).mean(0)
        b = rgb_old[inner].astype(float).mean(0)
        assert np.abs(a - b).max() < 0.08 * 255, (name, a, b)
        assert np.argmax(a) == np.argmax(b), (name, a, b)


def test_a_moved_object_renders_at_its_new_place(monkeypatch):
    sim = _world(monkeypatch, "gl")
    try:
        cam = sim.camera
        body = sim.scene.objects["can_1"]
        x, y, yaw = sim.robot_pose()
        pos, orn = sim.link_pose("camera_optical_frame")
        view = cam.view(pos, orn)
        R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
        K = np.array(cam.K()).reshape(3, 3)

        def where(name):
            """(u, v) of the body's pixels (median), and how many."""
            ids = _render(sim, view, segmentation=True)[2]
            rows, cols = np.nonzero(ids == sim.scene.objects[name])
            return (np.median(cols), np.median(rows)), len(rows)

        def expected(name):
            pc = R.T @ (np.array(sim.object_pose(name)[:3]) - np.array(pos))
            return (K @ (pc / pc[2]))[:2]

        for ahead, side in ((0.6, 0.0), (0.7, 0.15), (0.5, -0.12)):
            c, s = math.cos(yaw), math.sin(yaw)
            sim.set_object_pose("can_1", x + ahead * c - side * s, y + ahead * s + side * c)
            (u, v), n = where("can_1")
            assert n > 100
            eu, ev = expected("can_1")
            assert abs(u - eu) < 3 and abs(v - ev) < 6, ((u, v), (eu, ev))
        # added during the run: drawn from the next frame on
        sim.add_object("can", x + 0.6 * c + 0.25 * s, y + 0.6 * s - 0.25 * c, name="can_9")
        (u, v), n = where("can_9")
        assert n > 100 and abs(u - expected("can_9")[0]) < 3
        # removed: gone
        sim._gl_call(p.removeBody, body, physicsClientId=sim.cid)
        ids = _render(sim, view, segmentation=True)[2]
        assert not (ids == body).any()
        assert (ids == sim.scene.objects["can_9"]).sum() > 100
    finally:
        sim.close()


def test_labels_are_drawn_from_their_textures(monkeypatch):
    """house_hard's labelled meshes: the GL renderer finds each one's texture, and the
    label's printing shows as in pybullet's renderer."""
    new = _world(monkeypatch, "gl", "house_hard", 0)
    old = _world(monkeypatch, "egl", "house_hard", 0)
    try:
        gl = new.renderer.gl
        _render(new, _view_at(new, "can_1"))
        labelled = [n for n in new.object_names() if new.object_category(n) in ("can", "bottle")]
        for name in labelled:
            shapes = gl._bodies[new.scene.objects[name]]["shapes"]
            assert shapes and all(s.texture and s.texture.endswith(".png") for s in shapes), name
        checked = 0
        for name in labelled:
            view = _view_at(new, name, 0.35, 1.0, 0.25)
            rgb_new, _, ids = _render(new, view, segmentation=True)
            rgb_old, _ = _render(old, view)
            mask = ids == new.scene.objects[name]
            if mask.sum() < 400:
                continue
            checked += 1
            # the spread of colours on the object: label and printing, not one flat colour
            sd_new = rgb_new[mask].astype(float).std(0).mean()
            sd_old = rgb_old[mask].astype(float).std(0).mean()
            assert sd_new > 10 and sd_new == pytest.approx(sd_old, rel=0.4), (name, sd_new, sd_old)
            mean_new, mean_old = rgb_new[mask].astype(float).mean(0), rgb_old[mask].astype(float).mean(0)
            assert np.abs(mean_new - mean_old).max() < 0.1 * 255, (name, mean_new, mean_old)
        assert checked >= 3
    finally:
        new.close()
        old.close()


def test_texture_for_mesh_reads_the_labelled_obj_header(tmp_path):
    png = tmp_path / "abc.png"
    png.write_bytes(b"x")
    obj = tmp_path / "m.obj"
    obj.write_text("# actorbt sim: a labelled body (sim/textures.py) for can_1 abc.png\nv 0 0 0\n")
    assert gl_meshes.texture_for_mesh(str(obj)) == str(png)
    obj.write_text("# something else\n")
    assert gl_meshes.texture_for_mesh(str(obj)) is None


def test_the_renderer_choice_falls_back_cleanly(monkeypatch, caplog):
    cid = p.connect(p.DIRECT)
    try:
        # asked for by the environment
        monkeypatch.setenv("ACTORBT_SIM_RENDERER", "tiny")
        r = Renderer(cid)
        assert (r.name, r.gl) == ("tiny", None) and "tiny asked for" in r.why
        r.close()
        monkeypatch.setenv("ACTORBT_SIM_RENDERER", "vulkan")
        with pytest.raises(ValueError, match="gl, egl, tiny"):
            Renderer(cid)
        monkeypatch.delenv("ACTORBT_SIM_RENDERER")
        monkeypatch.setenv("ACTORBT_SIM_NO_EGL", "1")
        r = Renderer(cid)
        assert r.name == "tiny"
        r.close()
        monkeypatch.delenv("ACTORBT_SIM_NO_EGL")

        # no GL here: the next one, with the reason logged
        def no_gl():
            raise glr.GLUnavailable("no EGL OpenGL 3.3 context: test")

        monkeypatch.setattr(glr, "create_context", no_gl)
        renderer_mod._warned.clear()
        with caplog.at_level("WARNING", logger="sim.renderer"):
            r = Renderer(cid, prefer_egl=False)
        assert r.name == "tiny" and "gl: no EGL OpenGL 3.3 context: test" in r.why
        assert "camera renderer: tiny" in caplog.text and "no EGL OpenGL 3.3 context" in caplog.text
        rgb, depth = r.render(
            8,
            6,
            p.computeViewMatrix([0, 0, 1], [1, 0, 1], [0, 0, 1]),
            p.computeProjectionMatrixFOV(60, 8 / 6, 0.05, 10),
        )
        assert rgb.shape == (6, 8, 3) and depth.shape == (6, 8)
        r.close()
    finally:
        p.disconnect(cid)


def test_a_gl_failure_while_rendering_falls_back_to_the_tiny_renderer(monkeypatch, caplog):
    cid = p.connect(p.DIRECT)
    try:
        r = Renderer(cid, prefer="gl")
        assert r.name == "gl"

        def broken(*a, **k):
            raise RuntimeError("lost the context")

        monkeypatch.setattr(r.gl, "render", broken)
        view = p.computeViewMatrix([0, 0, 1], [1, 0, 1], [0, 0, 1])
        proj = p.computeProjectionMatrixFOV(60, 8 / 6, 0.05, 10)
        with caplog.at_level("ERROR", logger="sim.renderer"):
            rgb, depth = r.render(8, 6, view, proj)
        assert rgb.shape == (6, 8, 3) and r.name == "tiny" and r.gl is None
        assert "gl failed" in caplog.text
        r.close()
    finally:
        p.disconnect(cid)


def test_primitives_and_meshes_tessellate_closed_and_outward():
    """Every triangle faces away from the shape's centre (back faces are culled)."""
    for pos, nrm, _ in (
        gl_meshes.box((0.1, 0.2, 0.3)),
        gl_meshes.cylinder(0.2, 0.05),
        gl_meshes.sphere(0.1),
        gl_meshes.capsule(0.2, 0.05),
    ):
        t = pos.reshape(-1, 3, 3).astype(float)
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        keep = np.linalg.norm(n, axis=1) > 1e-12
        centroid = t.mean(1)
        assert (np.einsum("ij,ij->i", n[keep], centroid[keep]) > 0).all()
        assert np.allclose(np.linalg.norm(nrm, axis=1), 1, atol=1e-5)
