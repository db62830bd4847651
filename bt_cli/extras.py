"""Which extra of the actorbt distribution a command needs, and what to say when it is missing.

``pip install actorbt`` is the engine alone (docs/install.md); each front-end's third-party
packages come with an extra. A command whose extra is not installed stays in ``--help``,
marked, and running it says which extra to install instead of a bare ImportError.
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
from typing import Callable

from bt_engine.errors import ActorbtError

#: an extra -> the module whose presence shows it is installed
MARKER = {"ros": "rclpy", "mcp": "mcp", "draw": "graphviz", "sim": "pybullet", "planning": "ompl", "cluster": "ray"}

#: a third-party module (its top-level name) -> the extra that installs it
EXTRA_OF = {
    "rclpy": "ros",
    "rosbags": "ros",
    "foxglove": "ros",
    "numpy": "ros",
    "builtin_interfaces": "ros",
    "geometry_msgs": "ros",
    "sensor_msgs": "ros",
    "nav_msgs": "ros",
    "std_msgs": "ros",
    "diagnostic_msgs": "ros",
    "action_msgs": "ros",
    "rosidl_runtime_py": "ros",
    "mcp": "mcp",
    "jsonschema": "mcp",
    "graphviz": "draw",
    "matplotlib": "draw",
    "pybullet": "sim",
    "cv2": "sim",
    "moderngl": "sim",
    "ompl": "planning",
    "ruckig": "planning",
    "scipy": "planning",
    "ray": "cluster",
}

#: built by interfaces/ rather than installed from a registry: no extra brings them
SOURCE_BUILT = {"actorbt_interfaces", "tf2_msgs", "control_msgs", "nav2_msgs"}


@functools.cache  # several command modules ask about the same extra at every start
def installed(extra: str) -> bool:
    return importlib.util.find_spec(MARKER[extra]) is not None


def install_hint(extra: str) -> str:
    return f"pip install 'actorbt[{extra}]'"


def missing_module_message(error: ModuleNotFoundError) -> str | None:
    """What to install for the module ``error`` did not find; None when it is not a module
    an extra or interfaces/ provides (a real bug, to be raised as it is)."""
    top = (error.name or "").split(".")[0]
    if top in SOURCE_BUILT:
        return (
            f"needs the ROS interface packages built from actorbt's interfaces/ folder (module {top!r} "
            "is missing): pip install ./interfaces/upstream ./interfaces (interfaces/README.md)"
        )
    extra = EXTRA_OF.get(top)
    if extra is None:
        return None
    return f"needs the [{extra}] extra (module {top!r} is missing): {install_hint(extra)}"


def mark_commands(sub: argparse._SubParsersAction, first: int, extra: str) -> None:
    """The commands ``sub`` gained since it had ``first``: when ``extra`` is not installed,
    their summary says so and running one says what to install."""
    if installed(extra):
        return
    for action in sub._choices_actions[first:]:
        action.help = f"{action.help} [needs actorbt[{extra}]]"
        _refuse_everywhere(sub.choices[action.dest], _needs(action.dest, extra))


def _refuse_everywhere(parser: argparse.ArgumentParser, refuse: Callable[..., int]) -> None:
    """``refuse`` as the command of ``parser`` and of its sub-commands (``topic list``...):
    a sub-command's own default would win over its parent's."""
    parser.set_defaults(func=refuse)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                _refuse_everywhere(child, refuse)


def _needs(command: str, extra: str) -> Callable[..., int]:
    def refuse(*_: object) -> int:
        raise ActorbtError(
            f"`actorbt {command}` needs the [{extra}] extra, which is not installed: {install_hint(extra)}"
        )

    return refuse
