"""What a mission does to the world, from the actors it calls: whether it moves the
robot, and whether it is read-only (see :class:`bt_engine.actor.Safety`).

A tree moves the robot when any actor it may call does, through the trees it calls
too; it is read-only when every actor it may call is. A ``behaviour:`` node is a
py_trees Behaviour we know nothing about: the tree is then not read-only.
"""

from __future__ import annotations

from typing import Any, Callable

from ..actor import Safety
from ._model import Do, Mission, UseBehaviour, walk

__all__ = ["mission_safety"]


def mission_safety(mission: Mission, resolve: Callable[[str], Any]) -> Safety:
    """The safety of ``mission``; ``resolve(name)`` is the library's resolver (a tree
    comes back with its ``mission``, an actor with its ``safety`` or ``moves`` /
    ``read_only``). A name that does not resolve counts as neither (the validator
    reports it)."""
    moves, read_only = _walk(mission, resolve, set())
    return Safety(moves=moves, read_only=read_only and not moves)


def _walk(mission: Mission, resolve: Callable[[str], Any], seen: set[str]) -> tuple[bool, bool]:
    seen.add(mission.name)
    moves, read_only = False, True
    for node in walk(mission.root):
        if isinstance(node, UseBehaviour):
            read_only = False
        if not isinstance(node, Do):
            continue
        try:
            info = resolve(node.actor)
        except Exception:  # unresolved: reported by the validator, not here
            read_only = False
            continue
        callee = getattr(info, "mission", None)
        if isinstance(callee, Mission):
            if callee.name in seen:  # a cycle (rejected at load time anyway)
                continue
            m, r = _walk(callee, resolve, seen)
        else:
            safety = getattr(info, "safety", None)
            m = bool(getattr(safety, "moves", getattr(info, "moves", False)))
            r = bool(getattr(safety, "read_only", getattr(info, "read_only", False)))
        moves, read_only = moves or m, read_only and r
    return moves, read_only
