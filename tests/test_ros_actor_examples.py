"""The classic ros_actor examples (a camera search, a subsystem of skills), written as a
ros_actor user writes them, doing what their documentation says."""

from __future__ import annotations

import numpy as np
from sensor_msgs.msg import Image

from bt_engine import SubSystem, actor


def find_coke(cv_image: np.ndarray):
    """A cola can is a red blob: return its pixel centre, or None."""
    red = (cv_image[..., 0] > 150) & (cv_image[..., 1] < 80) & (cv_image[..., 2] < 80)
    if red.sum() < 20:
        return None
    ys, xs = np.nonzero(red)
    return int(xs.mean()), int(ys.mean())


class SampleSystem(SubSystem):
    def __init__(self):
        super().__init__()
        self.register_subscriber("pic", Image, "/intel_realsense_r200_depth/image_raw", 10)

    @actor
    def sample_actor(self, mes):
        print(mes)

    # hub_only: the local bus calls back on the hub, so the virtual clock need not pace
    # itself to wall time while a picture is awaited (tests/test_foreign_completion.py
    # runs the same pattern fed by a thread).
    @actor("pic_receiver", "async", hub_only=True)
    def pic_receiver(self, callback):
        """Start receiving one picture; call back with it as an array."""

        def on_frame(msg):
            sub.close()
            callback(np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.width, 3))

        sub = self.runtime.bus.subscribe("/intel_realsense_r200_depth/image_raw", Image, on_frame)
        return sub.close

    @actor
    def pic_find(self):
        ret = None
        with self.run_actor_mode("pic_receiver", "timed_iterator", 10) as pic_iter:
            for cv_image in pic_iter:
                ret = find_coke(cv_image)
                if ret:
                    break
        return ret


def start_camera(rt, coke_after: float | None):
    """Publish 32x24 frames at 10 Hz; a red can appears at ``coke_after`` seconds."""
    pub = rt.bus.publisher("/intel_realsense_r200_depth/image_raw", Image)

    def frame():
        img = np.zeros((24, 32, 3), np.uint8)
        if coke_after is not None and rt.now() >= coke_after:
            img[10:18, 20:26] = (200, 20, 20)
        msg = Image(height=24, width=32, encoding="rgb8", step=96, data=img.tobytes())
        pub.publish(msg)

    return rt.call_every(0.1, frame)


def test_sample_actor_prints_hello(rt, capsys):
    s = rt.add_subsystem("sample", SampleSystem)
    from tests.conftest import run_in_actor

    run_in_actor(rt, lambda: s.run_actor("sample_actor", "hello"))
    assert capsys.readouterr().out == "hello\n"


def test_async_call_runs_callback_when_finished(rt, capsys):
    s = rt.add_subsystem("sample", SampleSystem)
    calls = []
    callback = calls.append
    from tests.conftest import run_in_actor

    run_in_actor(rt, lambda: (s.run_actor_mode("sample_actor", "async", callback, "hi"), rt.sleep(0.1)))
    assert calls == [None] and capsys.readouterr().out == "hi\n"


def test_iterator_calls_repeatedly_with_same_arguments(rt, capsys):
    s = rt.add_subsystem("sample", SampleSystem)
    from tests.conftest import run_in_actor

    def body():
        iterator = s.run_actor_mode("sample_actor", "iterator", "again")
        with iterator:
            for _, _ in zip(range(3), iterator):
                pass

    run_in_actor(rt, body)
    assert capsys.readouterr().out == "again\n" * 3


def test_pic_find_finds_the_can_in_the_stream(rt):
    rt.add_subsystem("sample", SampleSystem)
    start_camera(rt, coke_after=2.5)
    t0 = rt.now()
    assert rt.call("pic_find") == (22, 13)
    assert 2.5 <= rt.now() - t0 <= 2.7


def test_pic_find_gives_up_after_ten_seconds(rt):
    rt.add_subsystem("sample", SampleSystem)
    start_camera(rt, coke_after=None)
    t0 = rt.now()
    assert rt.call("pic_find") is None
    assert rt.now() - t0 == 10.0


def test_subscriber_is_a_stream_actor(rt):
    rt.add_subsystem("sample", SampleSystem)
    start_camera(rt, coke_after=None)
    with rt.stream("pic", timeout=1.05) as frames:
        got = list(frames)
    assert len(got) == 10 and all(isinstance(m, Image) for m in got)
