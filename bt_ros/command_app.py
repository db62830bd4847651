"""What the ROS commands (``serve``, ``goal``, ``rcall``, ``rshell``, ``pose``, ``replay``
of a bag) use of the command line's App.

The App is :class:`bt_cli.app.App`, which this package may not import (``bt_cli`` sits
above it, docs/architecture.md); these protocols name the part of it the commands here
use, so the type checker reads them as the App they are.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING, Callable, Protocol, Sequence

from .rostypes import Value

if TYPE_CHECKING:
    from bt_engine import Runtime
    from .live_options import RobotSection

__all__ = ["CommandApp", "CommandConfig", "IndexEntry"]


class CommandConfig(Protocol):
    """actorbt.yaml as :class:`bt_cli.config.Config` holds it."""

    transport: str
    subsystems: dict[str, str]
    robot: RobotSection

    @property
    def base(self) -> pathlib.Path: ...

    def trees_dir(self) -> pathlib.Path | None: ...


class IndexEntry(Protocol):
    """One actor of the local actor index (:class:`bt_cli.actor_index.ActorEntry`)."""

    @property
    def path(self) -> str: ...

    @property
    def name(self) -> str: ...

    @property
    def kind(self) -> str: ...

    @property
    def is_tree(self) -> bool: ...

    @property
    def doc(self) -> str: ...

    #: the signature as ``actorbt list`` prints it
    @property
    def shown(self) -> str: ...


class CommandApp(Protocol):
    """The command line's App (:class:`bt_cli.app.App`)."""

    @property
    def cfg(self) -> CommandConfig: ...

    def world_spec(self) -> dict[str, Value] | None: ...

    def runtime(
        self,
        clock: str | None = None,
        with_world: bool = True,
        *,
        watchdog: float | None = 0.5,
        world_first: bool = False,
        # the world is whatever the simulator plugin starts
        world_setup: Callable[[object], None] | None = None,
    ) -> Runtime: ...

    def close(self, rt: Runtime) -> None: ...

    def actors_with_trees(self) -> Sequence[IndexEntry]: ...
