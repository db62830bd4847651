"""Builds a Runtime from actorbt.yaml and the command line: subsystems, trees, world."""
from __future__ import annotations

import argparse
import logging
from typing import Any

from ..runtime import Runtime
from .config import Config, ConfigError, import_object, load_config

log = logging.getLogger("actorbt.cli")


class App:
    """What one ``actorbt`` invocation works with."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.cfg: Config = load_config(getattr(args, "config", None))
        self.world: Any = None

    def runtime(self, clock: str | None = None, with_world: bool = True) -> Runtime:
        """A runtime with everything actorbt.yaml names, and the world started."""
        args = self.args
        # a window is watched by a person: --gui runs in real time unless told otherwise
        gui_clock = "wall" if getattr(args, "gui", False) else None
        clock = clock or getattr(args, "clock", None) or gui_clock or self.cfg.clock
        rt = Runtime(clock=clock, bus=self._transport())
        try:
            for name, spec in self.cfg.subsystems.items():
                cls = import_object(spec, f"subsystem {name!r}")
                rt.add_subsystem(name, cls)
            self._load_trees(rt)
            if with_world:
                self._start_world(rt)
        except BaseException:
            rt.close()
            raise
        return rt

    def _transport(self) -> Any:
        kind = "ros" if getattr(self.args, "ros", False) else self.cfg.transport
        if kind == "local":
            return None
        if kind == "ros":
            factory = import_object("bt_engine.bus.ros:RosTransport", "ROS transport")
            return factory
        raise ConfigError(f"unknown transport {kind!r}; expected 'local' or 'ros'")

    def _load_trees(self, rt: Runtime) -> None:
        folder = self.cfg.trees_dir()
        if folder is None or not folder.is_dir():
            return
        try:
            from ..trees import register_tree_folder
        except ImportError:  # trees layer not installed in this build
            return
        register_tree_folder(rt, folder)

    def world_spec(self) -> dict[str, Any] | None:
        w = dict(self.cfg.world or {})
        name = getattr(self.args, "world", None)
        if name == "none":  # the robot is whatever answers on the topics
            return None
        if name:
            w["name"] = name
        seed = getattr(self.args, "seed", None)
        if seed is not None:
            w["seed"] = seed
        if getattr(self.args, "gui", False):
            w["gui"] = True
        return w if w.get("name") else None

    def _start_world(self, rt: Runtime) -> None:
        spec = self.world_spec()
        if spec is None:
            return
        if not self.cfg.simulator:
            raise ConfigError("a world is configured but actorbt.yaml names no simulator "
                              "(e.g. simulator: sim:start_world)")
        start = import_object(self.cfg.simulator, "simulator")
        self.world = start(rt, spec["name"], seed=int(spec.get("seed", 0)),
                           gui=bool(spec.get("gui", False)))
        log.info("world %s (seed %s) started", spec["name"], spec.get("seed", 0))

    def close(self, rt: Runtime) -> None:
        if self.world is not None and hasattr(self.world, "close"):
            try:
                rt.run_on_hub(self.world.close)
            except Exception:
                log.exception("closing the world failed")
        rt.close()
