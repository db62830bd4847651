"""The pybullet world: a TurtleBot3 Waffle Pi + OpenManipulator-X in a house, on the bus.

    from sim import SimWorld
    sim = SimWorld(rt, world="house", seed=0).start()    # physics timer + ROS topics
    ...
    sim.close()

Helpers for the CLI: write_map(world, seed, out_pgm), snapshot(world, seed, out_png, camera).

The names below are imported on first use (PEP 562), so ``import sim.cli`` (what
``actorbt --help`` does to list the ``sim`` commands) loads neither pybullet nor numpy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .description import list_worlds, load_world
    from .simworld import SimWorld
    from .world_spec import WorldError, WorldSpec

__all__ = ["SimWorld", "start_world", "WorldError", "WorldSpec", "list_worlds", "load_world", "write_map", "snapshot"]

#: name -> the submodule that defines it
_LAZY = {
    "SimWorld": "simworld",
    "WorldError": "world_spec",
    "WorldSpec": "world_spec",
    "list_worlds": "description",
    "load_world": "description",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


def write_map(world="house", seed=0, out_pgm="map.pgm", resolution=0.05, height=None, locations=None):
    """Write map_server's PGM + YAML pair for a world; returns (pgm_path, yaml_path).
    ``height`` [m]: a slice at that height (see :func:`sim.gridmap.build_grid`); None:
    every static box."""
    from .description import load_world
    from .gridmap import build_grid, write_pgm_yaml

    return write_pgm_yaml(build_grid(load_world(world, seed, locations), resolution, height), out_pgm)


def snapshot(world="house", seed=0, out_png="world.png", camera=False, camera_size=(640, 480), locations=None):
    """Top view PNG of the world; with camera=True also <out>_camera.png (RGB | depth).
    Returns the list of files written."""
    from .topview import snapshot as _snapshot

    if locations is not None:
        from .description import load_world

        world = load_world(world, seed, locations)

    return _snapshot(world, seed, out_png, camera=camera, camera_size=camera_size)


def start_world(runtime, world="house", seed=0, gui=False, locations=None, **options):
    """Build ``world`` with ``seed`` and put it on ``runtime`` (what actorbt.yaml's
    ``simulator: sim:start_world`` names); ``locations``: a locations YAML for a world
    built from a map_server map; ``options``: more of :class:`SimWorld`'s keywords
    (``initial_pose``, ``faults``). Returns the started SimWorld."""
    from .simworld import SimWorld

    return SimWorld(runtime, world=world, seed=seed, gui=gui, locations=locations, **options).start()
