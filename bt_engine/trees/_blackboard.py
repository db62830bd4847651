"""One run's blackboard: a py_trees client confined to a namespace of its own.

py_trees keeps one class-global blackboard. Every run of a tree gets a fresh namespace
(``/actorbt/<tree>/<random id>``: random because the storage is shared by every runtime
of the process), seeded from its inputs, and removes it when it ends, so two runs of the
same tree (recursion, parallel calls, two runtimes) never see each other's keys.
"""

from __future__ import annotations

import uuid
from typing import Any, Callable, Iterable

import py_trees

__all__ = ["RunBlackboard"]

_Access = py_trees.common.Access


class RunBlackboard:
    """Read and write the keys of one run.

    Args:
        tree: the tree's name (part of the namespace).
        keys: keys to register up front (inputs and everything the tree writes).
        on_write: ``on_write(key, value)`` after every write (trace, progress).
    """

    def __init__(self, tree: str, keys: Iterable[str] = (), on_write: Callable[[str, Any], None] | None = None) -> None:
        self.namespace = f"/actorbt/{tree}/r{uuid.uuid4().hex[:16]}"
        self._client: py_trees.blackboard.Client | None = py_trees.blackboard.Client(
            name=f"actorbt:{tree}", namespace=self.namespace
        )
        self._keys: set[str] = set()
        self._storage = py_trees.blackboard.Blackboard.storage
        self.on_write = on_write
        for key in keys:
            self._register(key)

    def _live_client(self) -> py_trees.blackboard.Client:
        if self._client is None:
            raise RuntimeError(f"blackboard {self.namespace} is closed: its run has ended")
        return self._client

    def _register(self, key: str) -> None:
        if key not in self._keys:
            self._live_client().register_key(key, access=_Access.WRITE)
            self._keys.add(key)

    def get(self, key: str) -> Any:
        """The value of ``key``.

        Raises:
            KeyError: the key is not set.
        """
        try:
            return self._storage[f"{self.namespace}/{key}"]
        except KeyError:
            raise KeyError(key) from None

    def set(self, key: str, value: Any) -> None:
        self._register(key)
        self._live_client().set(key, value)
        if self.on_write is not None:
            self.on_write(key, value)

    def __contains__(self, key: object) -> bool:
        return f"{self.namespace}/{key}" in self._storage

    def items(self) -> dict[str, Any]:
        """Every key set in this run."""
        prefix = self.namespace + "/"
        return {k[len(prefix) :]: v for k, v in self._storage.items() if k.startswith(prefix)}

    def close(self) -> None:
        """Remove the namespace and its keys from py_trees' global blackboard."""
        if self._client is None:
            return
        client, self._client = self._client, None
        client.unregister(clear=True)
        prefix = self.namespace + "/"
        for key in [k for k in self._storage if k.startswith(prefix)]:
            del self._storage[key]
