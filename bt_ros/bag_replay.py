"""``actorbt replay`` of a rosbag2 folder written with ``--bag``.

A bag of a tree run (``run --bag``, ``demo --bag``) holds the run's trace on
``/actorbt/trace``: one std_msgs/String per JSON Lines record, header first, the same
lines ``--record`` writes. Replay reads them back in order and replays them as it
replays a ``.jsonl`` file; the trees are looked for beside the bag folder (or in
``--trees DIR``). The /actorbt/status topic is for people and viewers: it holds the
status changes but not the actor results replay answers calls with.

Reading needs only ``rosbags`` (pure Python): no rclpy, no simulator.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, cast

from bt_tools.replay import ReplayError, replay
from .bag import STRING, TRACE_TOPIC

if TYPE_CHECKING:
    from rosbags.typesys.stores.ros2_jazzy import std_msgs__msg__String

    from .command_app import CommandApp

__all__ = ["bag_folder", "cmd_replay", "trace_lines"]


def bag_folder(path: str | Path) -> Path | None:
    """The rosbag2 folder ``path`` names (the folder, its metadata.yaml or one of its
    .mcap files), or None when it is not one."""
    path = Path(path)
    if path.is_dir():
        return path if (path / "metadata.yaml").is_file() else None
    if path.suffix in (".mcap", ".yaml") and (path.parent / "metadata.yaml").is_file():
        return path.parent
    return None


def trace_lines(path: str | Path) -> list[str]:
    """The trace's lines in a bag, in the order they were written.

    Raises:
        ReplayError: not a readable rosbag2 folder, or it holds no trace.
    """
    from rosbags.rosbag2 import Reader
    from rosbags.rosbag2.errors import ReaderError

    from .cdr import typestore

    folder = bag_folder(path)
    if folder is None:
        raise ReplayError(f"{path}: not a rosbag2 folder (no metadata.yaml)")
    try:
        with Reader(folder) as reader:
            connections = [c for c in reader.connections if c.topic == TRACE_TOPIC and c.msgtype == STRING]
            if not connections:
                raise ReplayError(
                    f"{folder}: the bag holds no {TRACE_TOPIC} topic, so no tree run to "
                    "replay (`serve --bag` records none: replay the goal traces of "
                    "--record-dir)"
                )
            store = typestore()
            # deserialize_cdr is typed to return object; these connections are std_msgs/String
            return [
                cast("std_msgs__msg__String", store.deserialize_cdr(raw, STRING)).data
                for _, _, raw in reader.messages(connections=connections)
            ]
    except ReaderError as exc:
        raise ReplayError(f"{folder}: cannot read the bag: {exc}") from None


def cmd_replay(args: argparse.Namespace, app: CommandApp) -> int:
    """``actorbt replay TRACE``: a ``.jsonl`` trace or a bag folder."""
    folder = bag_folder(args.trace)
    if folder is None:
        from bt_tools.cli import cmd_replay as replay_jsonl

        return replay_jsonl(args, app)
    report = replay(folder, trees=args.trees, lines=trace_lines(folder))
    print(report)
    return 0 if report.ok else 1
