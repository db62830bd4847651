"""An episode's runtime with its robot localised where it stands, for tests that drive the
actors by hand (approach, pick, carry) instead of running a tree."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

from demo.episode import episode_app
from geometry_msgs.msg import PoseWithCovarianceStamped
from sim.initial_pose import initial_pose_msg


@contextlib.contextmanager
def localised_rig(world: str, seed: int, start: tuple, setup: Callable) -> Iterator[tuple]:
    """``world`` ``seed``'s episode runtime, its world set up by ``setup(sim)``, the robot
    told it stands at ``start`` (x, y, yaw) and localised there: yields (runtime, sim)."""
    app = episode_app(world, seed)
    rt = app.runtime(watchdog=None, world_first=True, world_setup=setup)
    try:
        rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(start))
        rt.call("require_localised")
        yield rt, app.world
    finally:
        app.close(rt)
