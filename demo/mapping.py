"""A mapping run: the robot explores a simulated world it has no map of and builds one from
``/scan`` and ``/odom`` (``actorbt map build``).

The world runs without its map server (``SimWorld.serve_map = False``), navstack's
``start_mapping`` runs the mapper instead of the localiser, and the robot's ``explore``
actor drives to frontiers until none is left; then ``save_map`` writes the map_server map.
The referee's side is the episode's: the true path and the error of the mapper's pose
(map -> base_footprint on /tf) against the simulator's truth.
"""

from __future__ import annotations

import dataclasses
import pathlib
import time
from dataclasses import dataclass
from typing import Callable, TextIO

from geometry_msgs.msg import PoseWithCovarianceStamped

from bt_engine import ActorError, Runtime
from bt_cli import find_config, load_config
from sim import SimWorld
from sim.initial_pose import initial_pose_msg

from .episode import REPO_CONFIG, Episode, TruthProbe, episode_app, without_map_server


@dataclass
class MappingRun:
    """What a mapping run did. Times in seconds, lengths in metres."""

    world: str
    seed: int
    success: bool = False
    reason: str = ""
    map_yaml: str = ""
    explore: dict = dataclasses.field(default_factory=dict)
    mapping: dict = dataclasses.field(default_factory=dict)
    sim_time: float = 0.0
    wall_time: float = 0.0
    traj_rmse_m: float = float("nan")
    traj_max_m: float = float("nan")
    path: list = dataclasses.field(default_factory=list)


def build_map(
    world: str,
    seed: int,
    out_dir: str | pathlib.Path,
    *,
    locations: str | None = None,
    max_time: float = 900.0,
    progress: TextIO | None = None,
    observe: Callable[[Runtime, SimWorld], Callable[[], None]] | None = None,
) -> MappingRun:
    """Explore ``world`` (seed ``seed``) from its start pose and write the map to
    ``out_dir``/map.yaml (+ map.pgm). The map frame is the world's: the mapper is told
    the start pose on ``/initialpose``, as slam_toolbox's ``map_start_pose``.
    ``observe(rt, sim)`` is called once the world runs (a referee's recorder, as
    bench/mapping_replay.py's); what it returns is called when the run ends."""
    run = MappingRun(world=world, seed=seed)
    out = pathlib.Path(out_dir)
    wall0 = time.perf_counter()
    app = episode_app(world, seed, config=load_config(find_config() or REPO_CONFIG), locations=locations)
    rt = app.runtime(watchdog=None, world_first=True, world_setup=without_map_server(None))
    sim = app.world
    ep = Episode(tree="map_build", world=world, seed=seed, category="")
    probe = TruthProbe(rt, sim, ep)
    stop_observing = observe(rt, sim) if observe is not None else None
    try:
        rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(
            initial_pose_msg(tuple(sim.spec.robot_start))
        )
        sim0 = rt.now()
        try:
            rt.call("start_mapping")
            run.explore = rt.call("explore", max_time=max_time)
            run.success = True
        except ActorError as e:
            run.reason = str(e.__cause__ or e)
        finally:
            run.sim_time = rt.now() - sim0
        try:
            saved = rt.call("save_map", str(out / "map.yaml"))
            run.map_yaml = saved["yaml"]
            run.mapping = {**rt.call("mapping_status"), **saved}
        except ActorError as e:
            run.success = False
            run.reason = run.reason or str(e.__cause__ or e)
        if progress is not None:
            print(f"explored for {run.sim_time:.0f} s sim: {run.explore or run.reason}", file=progress)
    finally:
        if stop_observing is not None:
            stop_observing()
        probe.close()
        probe.summarise()
        app.close(rt)
    run.traj_rmse_m, run.traj_max_m, run.path = ep.loc_rmse_m, ep.loc_max_m, ep.path
    run.wall_time = time.perf_counter() - wall0
    return run
