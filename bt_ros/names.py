"""The names a server and its clients agree on: node, action and service names of
``actorbt serve``, in the root namespace or a robot's.

    /actorbt/call          CallActor: call any actor
    /actorbt/tree/<name>   RunTree: one action per tree (``nav.patrol`` -> ``nav/patrol``)
    /actorbt/describe      Describe: the JSON Schema of every served tree and actor
    /actorbt/call_now      CallActorNow: a quick actor as a service

The constants are the names in the root namespace. The server creates its endpoints
under their relative names (:func:`relative`), so ``serve --namespace robot1`` (or
``--ros-args -r __ns:=/robot1``) serves ``/robot1/actorbt/call``; a client names the
same namespace (:func:`in_namespace`).
"""

from __future__ import annotations

import re

NODE_NAME = "actorbt"
CALL_ACTION = "/actorbt/call"
TREE_PREFIX = "/actorbt/tree/"
DESCRIBE_SERVICE = "/actorbt/describe"
CALL_NOW_SERVICE = "/actorbt/call_now"

__all__ = [
    "CALL_ACTION",
    "CALL_NOW_SERVICE",
    "DESCRIBE_SERVICE",
    "NODE_NAME",
    "TREE_PREFIX",
    "in_namespace",
    "namespace_of",
    "relative",
    "tree_action_name",
    "tree_of_action",
]


def tree_action_name(tree: str, namespace: str = "") -> str:
    """``/actorbt/tree/<name>`` for a tree path (dots become slashes), in ``namespace``."""
    parts = []
    for part in tree.replace("/", ".").split("."):
        part = re.sub(r"[^A-Za-z0-9_]", "_", part)
        if part and part[0].isdigit():
            part = "_" + part
        if part:
            parts.append(part)
    return in_namespace(TREE_PREFIX + "/".join(parts), namespace)


def tree_of_action(action: str, namespace: str = "") -> str | None:
    """The tree path an action name serves (``/actorbt/tree/nav/patrol`` -> ``nav.patrol``),
    or None when it is not a tree action of ``namespace``."""
    prefix = in_namespace(TREE_PREFIX, namespace)
    if not action.startswith(prefix) or len(action) == len(prefix):
        return None
    return action[len(prefix) :].replace("/", ".")


def namespace_of(namespace: str | None) -> str:
    """``robot1``, ``/robot1/`` -> ``/robot1``; empty or ``/`` -> ``""`` (the root)."""
    parts = [p for p in (namespace or "").split("/") if p]
    return "/" + "/".join(parts) if parts else ""


def in_namespace(name: str, namespace: str | None = "") -> str:
    """A root-namespace name (``/actorbt/call``) inside ``namespace`` (``/robot1/actorbt/call``)."""
    return namespace_of(namespace) + "/" + relative(name)


def relative(name: str) -> str:
    """``/actorbt/call`` -> ``actorbt/call``: what a node resolves in its own namespace."""
    return name.lstrip("/")
