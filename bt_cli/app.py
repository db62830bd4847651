"""Builds a Runtime from actorbt.yaml and the command line: subsystems, trees, world.

Commands that only need to know the actors (``check``, ``list``, ``catalog``) read the
:class:`~bt_cli.actor_index.ActorIndex` instead (see that module).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator

from bt_engine.runtime import Runtime
from .actor_index import ActorEntry, ActorIndex, loaded_sources
from .config import Config, ConfigError, import_object, load_config, run_imports

if TYPE_CHECKING:
    from bt_engine.bus import Transport
    from bt_ros.command_app import CommandApp
    from bt_engine.trees import TreeLibrary

log = logging.getLogger("actorbt.cli")


class App:
    """What one ``actorbt`` invocation works with."""

    def __init__(self, args: argparse.Namespace, cfg: Config | None = None) -> None:
        self.args = args
        self.cfg: Config = cfg if cfg is not None else load_config(getattr(args, "config", None))
        run_imports(self.cfg)  # what they register (object categories) must be known first
        self.world: Any = None
        self._warned: set[str] = set()

    def for_world(self, world: str | None, seed: int | None = None, locations: str | None = None) -> App:
        """An App with this configuration (and its warnings already given) for another
        world and seed (and the world's locations file, when given): what ``demo`` and
        ``eval`` build each episode's runtime with."""
        args = argparse.Namespace(**{**vars(self.args), "world": world, "seed": seed})
        if locations is not None:
            args.locations = locations
        other = App(args, self.cfg)
        other._warned = self._warned
        return other

    def runtime(
        self,
        clock: str | None = None,
        with_world: bool = True,
        *,
        watchdog: float | None = 0.5,
        world_first: bool = False,
        world_setup: Callable[[Any], None] | None = None,
    ) -> Runtime:
        """A runtime with everything actorbt.yaml names, and the world started.

        Args:
            clock: overrides ``--clock`` and actorbt.yaml.
            with_world: start the world actorbt.yaml (or ``--world``) names.
            watchdog: the runtime's hub watchdog [s]; ``None`` for none.
            world_first: start the world before the subsystems are added (the robot
                boots in a running world), not after the trees are loaded.
            world_setup: called with the started world (``self.world``) before the
                subsystems see it when ``world_first``, else once it runs.
        """
        args = self.args
        # a window (or a live Foxglove view) is watched by a person: it runs in real time
        # unless told otherwise
        watched = getattr(args, "gui", False) or getattr(args, "foxglove", None) is not None
        gui_clock = "wall" if watched else None
        clock = clock or getattr(args, "clock", None) or gui_clock or self.cfg.clock
        rt = Runtime(clock=clock, bus=self._transport(), watchdog=watchdog)
        try:
            with _c_stdout_to_stderr():  # stdout is for results (`call --json`), not banners
                if with_world and world_first:
                    self._start_world(rt, world_setup)
                self._add_subsystems(rt)
                self._load_trees(rt)
                if with_world and not world_first:
                    self._start_world(rt, world_setup)
        except BaseException:
            self.close(rt)
            raise
        return rt

    def _transport(self) -> Callable[[Runtime], Transport] | None:
        kind = getattr(self.args, "bus", None) or self.cfg.transport
        if kind == "local":
            return None
        if kind == "ros":
            factory = import_object("bt_ros.transport:RosTransport", "ROS transport")
            return factory
        raise ConfigError(f"unknown transport {kind!r}; expected 'local' or 'ros'")

    def _add_subsystems(self, rt: Runtime) -> None:
        for name, spec in self.cfg.subsystems.items():
            cls = import_object(spec, f"subsystem {name!r}")
            rt.add_subsystem(name, cls)

    # -- the actors without a runtime --------------------------------------------------
    def index_path(self) -> Path | None:
        """Where the actor index is kept (``None`` without an actorbt.yaml)."""
        return self.cfg.base / ".actorbt" / "actors.json" if self.cfg.path else None

    def actor_index(self) -> ActorIndex:
        """The subsystems' actors (no trees): from the stored index while the code it was
        built from is unchanged, else from a runtime built now (and stored)."""
        path = self.index_path()
        if path is not None:
            index = ActorIndex.load(path, self.cfg.subsystems)
            if index is not None:
                return index
        with _c_stdout_to_stderr():  # native banners must not end up in `catalog --json`
            rt = Runtime(clock="virtual")  # the actors do not depend on the transport or clock
            try:
                self._add_subsystems(rt)
                index = ActorIndex.of(rt.root.all_actors())
            finally:
                rt.close()
        if path is not None:
            index.save(path, self.cfg.subsystems, loaded_sources(self.cfg.subsystems.values()))
        return index

    def actors_with_trees(self) -> list[ActorEntry]:
        """What ``list`` and ``catalog`` show: the index plus the trees folder's trees,
        registered as a runtime would register them (validated against the index)."""
        index = self.actor_index()
        entries = list(index.entries)
        folder = self.cfg.trees_dir()
        if folder is not None and folder.is_dir():
            entries += self._tree_entries(folder, index)
        return sorted(entries, key=lambda e: e.path)

    def _tree_entries(self, folder: Path, index: ActorIndex) -> list[ActorEntry]:
        from bt_engine.trees import TreeHost

        rt = Runtime(clock="virtual")
        try:
            host = TreeHost(rt)
            host.library.resolver = index.resolve  # the subsystems are in the index, not in rt
            host.load_folder(folder, strict=False)
            self.warn_skipped(host.library, folder)
            return [ActorEntry.of(ref) for ref in rt.root.all_actors() if ref.is_tree]
        finally:
            rt.close()

    def _load_trees(self, rt: Runtime) -> None:
        """Register the trees folder's trees. A tree that does not load (or calls one
        that does not) is skipped with a warning; calling it by name gives the reason
        (``actorbt check`` is the strict one)."""
        folder = self.cfg.trees_dir()
        if folder is None or not folder.is_dir():
            return
        try:
            from bt_engine.trees import register_tree_folder
        except ImportError:  # trees layer not installed in this build
            return
        host = register_tree_folder(rt, folder, strict=False)
        self.warn_skipped(host.library, folder)

    def warn_skipped(self, library: TreeLibrary, folder: Path) -> None:
        """One line on stderr per skipped tree file, once per invocation."""
        for error in sorted(library.broken.values(), key=lambda e: (e.pos.file, e.pos.line, e.pos.column)):
            text = _relative(str(error), folder)
            if text not in self._warned:
                self._warned.add(text)
                print(f"actorbt: warning: skipped {text}", file=sys.stderr)

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
        locations = getattr(self.args, "locations", None)
        if locations:
            w["locations"] = str(locations)
        return w if w.get("name") else None

    def _start_world(self, rt: Runtime, setup: Callable[[Any], None] | None = None) -> None:
        spec = self.world_spec()
        if spec is None:
            return
        if not self.cfg.simulator:
            raise ConfigError(
                "a world is configured but actorbt.yaml names no simulator (e.g. simulator: sim:start_world)"
            )
        start = import_object(self.cfg.simulator, "simulator")
        # the locations file goes only to a simulator that is given one (the engine does
        # not read it: it is the simulator's business)
        extra = {"locations": spec["locations"]} if spec.get("locations") else {}
        self.world = start(rt, spec["name"], seed=int(spec.get("seed", 0)), gui=bool(spec.get("gui", False)), **extra)
        log.info("world %s (seed %s) started", spec["name"], spec.get("seed", 0))
        if setup is not None:
            setup(self.world)

    def close(self, rt: Runtime) -> None:
        if self.world is not None and hasattr(self.world, "close"):
            try:
                rt.run_on_hub(self.world.close)
            except Exception:
                log.exception("closing the world failed")
        rt.close()


def _relative(text: str, folder: Path) -> str:
    """``text`` with the trees folder's path as the user would type it from here."""
    try:
        shown = os.path.relpath(folder)
    except ValueError:  # another drive
        return text
    if shown.startswith(os.pardir) or shown == str(folder):
        return text
    return text.replace(str(folder) + os.sep, shown + os.sep)


@contextlib.contextmanager
def _c_stdout_to_stderr() -> Iterator[None]:
    """Send what native code prints to stdout (pybullet's build banner) to stderr."""
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no real stdout (embedded): nothing to protect
        yield
        return
    try:
        os.dup2(2, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


if TYPE_CHECKING:

    def _as_command_app(app: App) -> CommandApp:
        """The ROS commands take the App as a CommandApp: the type checker holds the two
        to each other here (bt_ros may not import bt_cli)."""
        return app
