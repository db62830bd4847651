"""``--bag DIR``, ``--foxglove [PORT]`` and ``--foxglove-host ADDR``: the options of
``run``, ``demo`` and ``serve`` that record a rosbag2 folder and serve a live Foxglove
view (docs/recording.md). Declaring them imports nothing heavy: the parser is built on
every ``actorbt`` start."""

from __future__ import annotations

import argparse
import errno
import socket
from dataclasses import dataclass
from typing import TypedDict

from bt_engine.errors import ActorbtError
from .rostypes import QosSetting

__all__ = ["FOXGLOVE_PORT", "FoxgloveError", "LiveOptions", "add_live_options"]

#: the Foxglove app's default WebSocket port
FOXGLOVE_PORT = 8765


class FoxgloveError(ActorbtError):
    """The live view cannot start: the port is taken, or the address is not this host's."""


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a TCP port number, got {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"expected a TCP port from 0 to 65535, got {port}")
    return port


def add_live_options(p: argparse.ArgumentParser, *, trace: bool = True) -> None:
    """Add the options to a command's parser; ``trace``: the command runs one tree, whose
    trace the bag also holds (``run``, ``demo``; not ``serve``)."""
    holds = (
        "the robot's topics, the tree's status and the run's trace"
        if trace
        else "the robot's topics and the trees' status"
    )
    p.add_argument(
        "--bag",
        metavar="DIR",
        help=f"Record a rosbag2 folder (MCAP, CDR) in the new folder DIR: {holds}, for "
        + ("`ros2 bag play`, Foxglove and `actorbt replay DIR`." if trace else "`ros2 bag play` and Foxglove."),
    )
    p.add_argument(
        "--foxglove",
        nargs="?",
        const=FOXGLOVE_PORT,
        type=_port,
        metavar="PORT",
        help="Serve a live view for the Foxglove app on ws://127.0.0.1:PORT (default "
        f"{FOXGLOVE_PORT}): the map, the robot and its path, the scan, the camera, "
        "the detections, the goals and the tree's status (docs/recording.md).",
    )
    p.add_argument(
        "--foxglove-host",
        default="127.0.0.1",
        metavar="ADDR",
        help="The address the Foxglove view listens on (default 127.0.0.1, this machine "
        "only; 0.0.0.0 serves every network interface).",
    )


#: a robot topic to record and show: (name, type, qos, compress)
RobotTopic = tuple[str, str, QosSetting, bool]


class RobotSection(TypedDict, total=False):
    """actorbt.yaml's ``robot:`` section, as :mod:`bt_cli.config` checked it."""

    #: the robot's box, (sx, sy, sz, x) [m], or None
    body: tuple[float, float, float, float] | None
    topics: tuple[RobotTopic, ...]


@dataclass(frozen=True)
class LiveOptions:
    """What the options asked for."""

    #: the new bag folder, or None
    bag: str | None = None
    #: the Foxglove view's port (0: any free one), or None for no view
    foxglove: int | None = None
    foxglove_host: str = "127.0.0.1"
    #: the robot's box in the view, (sx, sy, sz, x) [m], or None (actorbt.yaml ``robot: body:``)
    body: tuple[float, float, float, float] | None = None
    #: the robot's topics besides the standard ones, (name, type, qos, compress) each
    #: (actorbt.yaml ``robot: topics:``)
    topics: tuple[RobotTopic, ...] = ()

    @classmethod
    def of(cls, args: argparse.Namespace, robot: RobotSection | None = None) -> LiveOptions:
        """The options of a command's ``args``, with the configuration's ``robot:`` section
        (:attr:`bt_cli.config.Config.robot`)."""
        robot = robot or {}
        return cls(
            getattr(args, "bag", None),
            getattr(args, "foxglove", None),
            getattr(args, "foxglove_host", None) or "127.0.0.1",
            body=robot.get("body"),
            topics=tuple(robot.get("topics") or ()),
        )

    def __bool__(self) -> bool:
        return self.bag is not None or self.foxglove is not None

    def check(self) -> None:
        """Fail now, before a world is built, on a bag folder that is not new or a port
        that is taken (one-line errors)."""
        if self.bag is not None:
            from .bag import check_bag_path

            check_bag_path(self.bag)
        if self.foxglove:
            family = socket.AF_INET6 if ":" in self.foxglove_host else socket.AF_INET
            with socket.socket(family) as s:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the server binds
                try:
                    s.bind((self.foxglove_host, self.foxglove))
                except socket.gaierror as exc:
                    raise FoxgloveError(
                        f"--foxglove-host {self.foxglove_host}: not an address of this machine ({exc.strerror})"
                    ) from None
                except OSError as exc:
                    why = "the port is in use" if exc.errno == errno.EADDRINUSE else (exc.strerror or str(exc))
                    raise FoxgloveError(
                        f"--foxglove {self.foxglove}: cannot listen on {self.foxglove_host}:{self.foxglove}: {why}"
                    ) from None
