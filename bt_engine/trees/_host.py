"""Trees as actors: the trees of one runtime, registered under their names.

``register_tree_folder(rt, "trees")`` parses and validates every mission of the folder
(all at load time, before anything runs) and registers each as a sync actor of the root
SubSystem, with its inputs as parameters and its outputs as result. With
``strict=False`` the trees that do not load are skipped (see ``TreeLibrary.broken``), and
calling one by name raises the reason. Calling a tree actor builds a fresh tree with its own
blackboard namespace and ticks it in the caller's greenlet until it finishes. So trees call
trees with ``do:``, actors call trees with ``run_actor`` in every call mode, and a Python
program calls one through the runtime.
"""

from __future__ import annotations

import inspect
import itertools
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Literal, Mapping, overload

import py_trees
import py_trees.behaviours

from ..catalog import json_type
from ..docstrings import attach as attach_docs
from ..docstrings import unit_of
from ._behaviours import CallSite
from ._errors import DuplicateTreeError, MissionError
from ._library import SkippedTreeError, TreeLibrary
from ._model import Mission, UseBehaviour, walk
from ._plugins import PluginSpec, node_plugins, plugin_spec
from ._run import TreeObserver, TreeRun
from ._safety import mission_safety

if TYPE_CHECKING:
    from ..runtime import Runtime

__all__ = ["STANDARD_BEHAVIOURS", "BehaviourFactory", "TreeHost", "register_tree_folder", "tree_host"]

#: Makes a py_trees Behaviour for ``behaviour:``; called with the ``with:`` arguments,
#: plus ``name=`` and ``blackboard_namespace=`` when it accepts them.
BehaviourFactory = Callable[..., py_trees.behaviour.Behaviour]

#: the key of a runtime's TreeHost among its extensions (``rt.extension``)
EXTENSION_KEY = "trees"

#: py_trees' own behaviours, available to ``behaviour:`` in every host.
STANDARD_BEHAVIOURS: dict[str, BehaviourFactory] = {
    "Success": py_trees.behaviours.Success,
    "Failure": py_trees.behaviours.Failure,
    "Running": py_trees.behaviours.Running,
    "Periodic": py_trees.behaviours.Periodic,
    "SuccessEveryN": py_trees.behaviours.SuccessEveryN,
}


class TreeHost:
    """The trees of one runtime: their library, their actors, and their runs.

    Args:
        rt: the runtime whose root SubSystem receives the tree actors.
        behaviours: factories ``behaviour:`` nodes may name, besides
            :data:`STANDARD_BEHAVIOURS`.
        max_period: the longest time [s, runtime clock] between two ticks of a run;
            ``None`` ticks on events only.
        behaviour_period: the longest time between ticks for trees that contain
            ``behaviour:`` nodes, which may poll and so cannot wake the loop.
        nodes: controls and decorators written in Python (marked classes) that
            ``control:`` and ``decorator:`` may name, besides every registered one.

    Attributes:
        library: the parsed, validated missions.
        observers: told about every run (progress display, trace recorder).
    """

    def __init__(
        self,
        rt: Runtime,
        *,
        behaviours: Mapping[str, BehaviourFactory] | None = None,
        max_period: float | None = None,
        behaviour_period: float = 0.1,
        nodes: Iterable[type] = (),
    ) -> None:
        self.rt = rt
        self.behaviours: dict[str, BehaviourFactory] = {**STANDARD_BEHAVIOURS, **(behaviours or {})}
        self.nodes: dict[str, PluginSpec] = node_plugins()
        for cls in nodes:
            spec = plugin_spec(cls)
            if spec is None:
                raise TypeError(f"{cls.__qualname__} is not marked with @control_node or @decorator_node")
            self.nodes[spec.name] = spec
        self.max_period = max_period
        self.behaviour_period = behaviour_period
        self.library = TreeLibrary(resolver=self._resolve, behaviours=self.behaviours, nodes=self.nodes)
        self.observers: list[TreeObserver] = []
        self._run_ids = itertools.count(1)
        self._runs_by_txn: dict[int, TreeRun] = {}
        self._live: dict[int, TreeRun] = {}
        self._stubs: set[str] = set()  # names of skipped trees registered as failing actors

    # ------------------------------------------------------------ loading and registration

    def _resolve(self, name: str) -> Any:
        return self.rt.run_on_hub(self.rt.root.resolve, name)

    def load_folder(self, folder: str | Path, *, strict: bool = True) -> list[Mission]:
        """Parse, validate and register every ``*.yaml`` of a folder.

        With ``strict`` (the default) it is all or nothing. Without, the files that do
        not load, and the trees that call them (directly or not), are skipped: see
        ``library.broken`` for why. A skipped tree name is registered as an actor that
        raises :class:`SkippedTreeError` with the reason, so calling it says why.

        Returns:
            the missions registered now.

        Raises:
            MissionError: (strict) the first problem in any file; nothing is registered
                then. Also without ``strict`` when the folder cannot be listed.
        """
        if strict:
            missions = self.library.load_folder(folder)
            self.library.check([m.name for m in missions])
            for mission in missions:
                self.register(mission)
            return missions
        missions = self.library.load_folder(folder, strict=False)
        for mission in missions:
            conflict = self._name_conflict(mission)
            if conflict is not None:  # it would hide an actor: skip it, under its file
                self.library.skip(mission.name, conflict, key=mission.file)
        loaded = set(self.library.names)
        self.library.check([m.name for m in missions if m.name in loaded], strict=False)
        loaded = set(self.library.names)
        registered = [m for m in missions if m.name in loaded and self.library[m.name] is m]
        for mission in registered:
            self.register(mission)
        self._register_skipped()
        return registered

    def _name_conflict(self, mission: Mission) -> MissionError | None:
        """The error when a root actor that is not a tree already has the mission's name."""
        name = mission.name
        existing = self.rt.run_on_hub(lambda: self.rt.root.actors().get(name))
        if existing is None or existing.is_tree or name in self._stubs:
            return None
        return DuplicateTreeError(
            mission.pos, f"tree name {name!r} is already the actor {existing.path}, expected a name no root actor has"
        )

    def _register_skipped(self) -> None:
        """Register each skipped tree name as an actor that raises the reason."""
        for name in list(self.library.broken):
            if not self.library.is_skipped(name):
                continue
            existing = self.rt.run_on_hub(lambda n=name: self.rt.root.actors().get(n))
            if existing is not None and not existing.is_tree and name not in self._stubs:
                continue  # a real actor of that name: leave it
            error = self.library.broken[name]
            self.rt.run_on_hub(
                self.rt.root.add_actor,
                name,
                _skipped_tree(name, error),
                "sync",
                doc=f"Skipped tree {name}: {error}",
                signature=_ANY_ARGUMENTS,
                replace=True,
            )
            self._stubs.add(name)

    def reload_folder(self, folder: str | Path) -> list[Mission]:
        """Load ``folder`` again as it is now, tolerantly (as ``load_folder(strict=False)``).

        The folder's trees are forgotten first, so an edited file is read again, the tree
        of a removed file is unregistered, and a file that no longer loads is skipped
        (``library.broken`` says why). Trees from elsewhere stay. Runs under way keep
        the mission they started with. Call it on the hub (``rt.run_on_hub``): the
        library is swapped in one step, so no goal sees it half loaded.

        Returns:
            the missions registered now.
        """
        where = Path(folder).resolve()

        def outside(file: str) -> bool:
            return Path(file).resolve().parent != where

        old = self.library
        fresh = TreeLibrary(resolver=self._resolve, behaviours=self.behaviours, nodes=self.nodes)
        for mission in old:
            if outside(mission.file):
                fresh.add(mission)
        fresh.broken.update({k: e for k, e in old.broken.items() if outside(e.pos.file)})
        before = set(old.names) | self._stubs
        self.library = fresh
        registered = self.load_folder(folder, strict=False)
        for name in before - set(fresh.names):
            if name in self._stubs and fresh.is_skipped(name):
                continue  # still skipped: its stub says why
            ref = self.rt.root.actors().get(name)
            if ref is not None and (ref.is_tree or name in self._stubs):
                self.rt.root.remove_actor(name)
            self._stubs.discard(name)
        return registered

    def load_file(self, path: str | Path) -> Mission:
        """Parse, validate and register one mission file.

        Raises:
            MissionError: the first problem in the file.
        """
        mission = self.library.load_file(path)
        self.library.check([mission.name])
        self.register(mission)
        return mission

    def register(self, mission: Mission) -> None:
        """Register a (validated) mission as a sync actor of the root, under its name.

        Raises:
            DuplicateTreeError: a root actor that is not a tree already has the name.
        """
        conflict = self._name_conflict(mission)
        if conflict is not None:
            raise conflict
        name = mission.name

        def run_tree(*args: Any, **kwargs: Any) -> dict[str, Any]:
            return self.run(name, *args, **kwargs)

        run_tree.__name__ = name
        run_tree.__doc__ = mission.doc
        # the catalog's parameter and result descriptions (bt_engine.catalog.tool_schema)
        attach_docs(run_tree, {spec.name: spec.doc for spec in mission.inputs if spec.doc}, _outputs_schema(mission))
        self.rt.run_on_hub(
            self.rt.root.add_actor,
            name,
            run_tree,
            "sync",
            doc=mission.doc or f"Tree {name} ({mission.file}).",
            signature=mission.signature(),
            is_tree=True,
            replace=True,
            safety=mission_safety(mission, self.library.resolve),
        )
        self._stubs.discard(name)

    # ------------------------------------------------------------ running

    def next_run_id(self) -> int:
        """A fresh run id (unique among this host's runs)."""
        return next(self._run_ids)

    def period_for(self, mission: Mission) -> float | None:
        """The max tick period of a run of ``mission``."""
        if any(isinstance(node, UseBehaviour) for node in walk(mission.root)):
            return self.behaviour_period if self.max_period is None else min(self.max_period, self.behaviour_period)
        return self.max_period

    def actor_target(self, name: str) -> tuple[str, str]:
        """The path a ``do:`` name starts (library trees are root actors by name), and
        the actor's kind (``sync``, ``async``, ``multi``)."""
        info = self.library.resolve(name)
        kind = getattr(info, "kind", "sync")
        return info.path, getattr(kind, "value", kind)

    def node_plugin(self, name: str) -> PluginSpec:
        """The control or decorator written in Python that ``control:``/``decorator:``
        names (the library validated that it is there)."""
        return self.nodes[name]

    def start_actor(
        self, run: TreeRun, leaf: CallSite, args: tuple, kwargs: dict, on_done: Callable[[Any], None]
    ) -> Any:
        """Start the actor of an actor leaf and return its Transaction; replay overrides
        this to answer from a recording."""
        return self.rt.start(leaf.actor_path, *args, on_done=on_done, **kwargs)

    def prepare(self, name: str, /, *args: Any, **kwargs: Any) -> TreeRun:
        """Build a run of tree ``name`` without ticking it (for ticking by hand on the hub).

        Raises:
            InputError: the arguments do not fit the tree's inputs.
        """
        mission = self.library[name]
        inputs = mission.bind_inputs(*args, **kwargs)
        return self.rt.run_on_hub(self._new_run, mission, inputs)

    def _new_run(self, mission: Mission, inputs: dict[str, Any]) -> TreeRun:
        task = self.rt.hub.current_task()
        txn = task.txns[-1] if task is not None and task.txns else None
        parent = None
        if txn is not None and txn.parent is not None:
            parent = self._runs_by_txn.get(txn.parent.id)
        run = TreeRun(self, mission, inputs, parent)
        self._live[run.id] = run
        if txn is not None:
            self._runs_by_txn[txn.id] = run
            run.txn_id = txn.id
        return run

    def run_closed(self, run: TreeRun) -> None:
        """Forget a run that has ended (TreeRun calls this from ``close``)."""
        self._live.pop(run.id, None)
        if run.txn_id is not None:
            self._runs_by_txn.pop(run.txn_id, None)

    def run(self, name: str, /, *args: Any, **kwargs: Any) -> dict[str, Any]:
        """Run tree ``name`` to the end in the calling actor (the tree actor's body).
        (``name`` is positional-only: a tree may have an input called ``name``.)

        Returns:
            the outputs, ``{name: value}``.

        Raises:
            InputError: the arguments do not fit the tree's inputs.
            TreeFailure: the tree failed.
        """
        mission = self.library[name]
        inputs = mission.bind_inputs(*args, **kwargs)
        return self._new_run(mission, inputs).run()

    def run_mission(self, mission: Mission, /, *args: Any, **kwargs: Any) -> dict[str, Any]:
        """Run a validated mission that need not be in the library (a draft an MCP client
        sent) to the end in the calling actor, as :meth:`run` runs a library tree.

        Raises:
            InputError: the arguments do not fit the mission's inputs.
            TreeFailure: the tree failed.
        """
        return self._new_run(mission, mission.bind_inputs(*args, **kwargs)).run()

    def live_runs(self) -> list[TreeRun]:
        """Runs built and not closed yet (leak checks)."""
        return list(self._live.values())


_ANY_ARGUMENTS = inspect.Signature(
    [
        inspect.Parameter("args", inspect.Parameter.VAR_POSITIONAL),
        inspect.Parameter("kwargs", inspect.Parameter.VAR_KEYWORD),
    ]
)


def _outputs_schema(mission: Mission) -> dict[str, Any]:
    """The tree's result as a JSON-Schema fragment: an object with one property per
    output, typed and described as declared."""
    props: dict[str, Any] = {}
    for spec in mission.outputs:
        schema = dict(json_type(spec.type.python_type))
        if spec.doc:
            schema["description"] = spec.doc
            unit = unit_of(spec.doc)
            if unit:
                schema["unit"] = unit
        props[spec.name] = schema
    return {"type": "object", "description": "the outputs (null: not written in this run)", "properties": props}


def _skipped_tree(name: str, error: MissionError) -> Callable[..., Any]:
    """The actor a skipped tree name stands for: it raises why the tree was skipped."""

    def skipped_tree(*args: Any, **kwargs: Any) -> Any:
        raise SkippedTreeError(name, error)

    skipped_tree.__name__ = name
    return skipped_tree


@overload
def tree_host(rt: Runtime, create: Literal[True]) -> TreeHost: ...


@overload
def tree_host(rt: Runtime, create: bool = False) -> TreeHost | None: ...


def tree_host(rt: Runtime, create: bool = False) -> TreeHost | None:
    """The TreeHost of a runtime (made now with ``create``), or None.

    The host is kept by the runtime itself, so it goes when the runtime goes.
    """
    return rt.extension(EXTENSION_KEY, (lambda: TreeHost(rt)) if create else None)


def register_tree_folder(rt: Runtime, folder: str | Path, *, strict: bool = True, **options: Any) -> TreeHost:
    """Parse, validate and register every mission in ``folder`` as an actor of ``rt``.

    ``options`` go to :class:`TreeHost` the first time; the runtime keeps one host.
    Without ``strict``, what does not load is skipped (``host.library.broken``).

    Raises:
        MissionError: (strict) the first problem found, ``file:line:column: message``.
    """
    host = rt.extension(EXTENSION_KEY, lambda: TreeHost(rt, **options))
    host.load_folder(folder, strict=strict)
    return host
