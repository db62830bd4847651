"""A camera search program written ros_actor style: module-level API, a camera driver
thread feeding an async actor, a timed iterator over it. Run: python seed_pic_find.py
[virtual|wall]. Prints the can's pixel, the runtime time and the wall time it took."""

import sys
import threading
import time

import numpy as np

from bt_engine import (
    Runtime,
    SubSystem,
    actor,
    register_subsystem,
    run_actor,
    run_actor_async,
    run_actor_mode,
    set_default_runtime,
)

CAN_AFTER = 0.3  # [s, wall] the can comes into view


def find_coke(image):
    red = (image[..., 0] > 150) & (image[..., 1] < 80)
    if red.sum() < 20:
        return None
    ys, xs = np.nonzero(red)
    return int(xs.mean()), int(ys.mean())


class Camera(SubSystem):
    def __init__(self, name, parent):  # ros_actor's constructor form
        super().__init__(name, parent)
        self.started = time.monotonic()

    @actor("pic_receiver", "async")
    def pic_receiver(self, callback):
        """One frame, 50 ms after it is asked for, delivered by a driver thread."""

        def grab():
            img = np.zeros((24, 32, 3), np.uint8)
            if time.monotonic() - self.started > CAN_AFTER:
                img[10:18, 20:26] = (200, 20, 20)
            callback(img)

        t = threading.Timer(0.05, grab)
        t.start()
        return t.cancel

    @actor
    def pic_find(self):
        ret = None
        with self.run_actor_mode("pic_receiver", "timed_iterator", 10) as pic_iter:
            for cv_image in pic_iter:
                ret = find_coke(cv_image)
                if ret:
                    break
        return ret


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "wall":
        set_default_runtime(Runtime(clock="wall"))
    register_subsystem("camera", Camera)
    t0 = time.monotonic()
    found = run_actor("pic_find")
    got = []
    run_actor_async("pic_receiver", got.append)
    frame = run_actor_mode("pic_receiver", "timed", 1.0)
    while not got:
        time.sleep(0.01)
    print(f"found={found} frame={frame.shape} async={got[0].shape} wall={time.monotonic() - t0:.2f}")
