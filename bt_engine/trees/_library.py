"""A set of mission files validated together: the trees folder.

Trees call trees by name with ``do:``, so a tree is only valid in the company of the
trees it calls. The library parses every file, then resolves names to its own trees
first and to the actor resolver otherwise, and validates each mission against that,
subtree cycles included.

Loading is strict (the first problem raises, nothing is kept) or tolerant
(``strict=False``): a file that does not parse or validate is *skipped*, and so is every
tree that calls a skipped tree, directly or not; the rest loads. :attr:`TreeLibrary.broken`
says what was skipped and why, and asking for a skipped tree by name raises
:class:`SkippedTreeError` with that reason.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Collection, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, overload

from ..errors import ActorbtError, UnknownActorError
from ._errors import DuplicateTreeError, MissionError, Pos
from ._model import Do, Mission, walk
from ._parse import read_mission
from ._plugins import PluginSpec, node_plugins
from ._validate import ActorInfo, Resolver, validate_mission

__all__ = ["BrokenDependencyError", "SkippedTreeError", "TreeInfo", "TreeLibrary", "check_files", "load_mission"]

#: what a tree name looks like (keys of ``TreeLibrary.broken`` that are not file paths)
_TREE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: a top-level ``name:`` line, to know which tree a file that does not parse declares
_DECLARED_NAME = re.compile(r"""^name:[ \t]*(["']?)([A-Za-z_][A-Za-z0-9_]*)\1[ \t]*(?:#.*)?$""", re.MULTILINE)


class BrokenDependencyError(MissionError):
    """A tree calls (directly or not) a tree that was skipped; it is skipped too.

    Attributes:
        chain: the trees from the one called here down to the broken one.
        root: the located error of the broken tree's file.
    """

    def __init__(self, pos: Pos, chain: list[str], root: MissionError) -> None:
        self.chain = list(chain)
        self.root = root
        via = "".join(f", which calls {name!r}" for name in chain[1:])
        super().__init__(pos, f"calls tree {chain[0]!r}{via}, which does not load: {root}")


class SkippedTreeError(ActorbtError, LookupError):
    """A tree asked for by name was skipped when its folder was loaded.

    Attributes:
        name: the tree.
        error: why: its file's located error, or a :class:`BrokenDependencyError`.
    """

    def __init__(self, name: str, error: MissionError) -> None:
        self.name = name
        self.error = error
        super().__init__(f"tree {name!r} was skipped: {error}")


def _duplicate(mission: Mission, other_file: str) -> DuplicateTreeError:
    return DuplicateTreeError(
        mission.pos,
        f"tree name {mission.name!r} is already used by {other_file}, expected one file per tree name",
    )


def _declared_name(path: str | Path) -> str | None:
    """The tree name a mission file declares on a top-level ``name:`` line, if it can
    be read (for files that do not parse)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read(1 << 20)
    except (OSError, ValueError):
        return None
    match = _DECLARED_NAME.search(text)
    return match.group(2) if match else None


@dataclass(frozen=True)
class TreeInfo:
    """A library tree seen as an actor (what the resolver returns for it)."""

    name: str
    path: str
    signature: inspect.Signature
    doc: str | None
    mission: Mission
    is_tree: bool = True
    kind: str = "sync"


@dataclass(frozen=True)
class _AnyActor:
    path: str = "?"
    signature: inspect.Signature = inspect.Signature(
        [
            inspect.Parameter("args", inspect.Parameter.VAR_POSITIONAL),
            inspect.Parameter("kwargs", inspect.Parameter.VAR_KEYWORD),
        ]
    )
    is_tree: bool = False


_UNCHECKED = _AnyActor()


class TreeLibrary:
    """Mission files parsed and validated together.

    Args:
        resolver: ``name -> ActorInfo`` for actors that are not trees of this library
            (``rt.root.resolve``); ``None`` accepts any other name as an actor with
            an unknown signature (structure-only checking).
        behaviours: names ``behaviour:`` may use; ``None`` skips that check.
        nodes: the controls and decorators written in Python that ``control:`` and
            ``decorator:`` may name; by default every registered one.

    Attributes:
        broken: what tolerant loading skipped and why: tree name (or the file, for a
            file whose tree name is unknown) -> its located :class:`MissionError`; a
            tree that calls a skipped tree has a :class:`BrokenDependencyError`.

    Example::

        lib = TreeLibrary(resolver=rt.root.resolve)
        lib.load_folder("trees")
        lib.check()                       # raises the first MissionError
        lib["demo_patrol"].signature()

        lib.load_folder("trees", strict=False)
        lib.check(strict=False)           # skips what does not load
        lib.broken                        # {"bt_x": MissionError(...)}
    """

    def __init__(
        self,
        resolver: Resolver | None = None,
        behaviours: Collection[str] | None = None,
        nodes: Mapping[str, PluginSpec] | None = None,
    ) -> None:
        self.resolver = resolver
        self.behaviours = behaviours
        self.nodes: dict[str, PluginSpec] = dict(node_plugins() if nodes is None else nodes)
        self._missions: dict[str, Mission] = {}
        self.broken: dict[str, MissionError] = {}

    # ------------------------------------------------------------ loading

    @overload
    def add(self, mission: Mission, *, strict: Literal[True] = True) -> Mission: ...

    @overload
    def add(self, mission: Mission, *, strict: bool) -> Mission | None: ...

    def add(self, mission: Mission, *, strict: bool = True) -> Mission | None:
        """Add a parsed mission.

        Without ``strict``, a name two files declare is skipped (both files: which one
        was meant is unknown), and ``None`` is returned.

        Raises:
            DuplicateTreeError: (strict) another file already declares this tree name.
        """
        name = mission.name
        other = self._missions.get(name)
        if other is not None and other.file != mission.file:
            error = _duplicate(mission, other.file)
            if strict:
                raise error
            del self._missions[name]
            self.broken[name] = error
            return None
        if not strict and name in self.broken:
            previous = self.broken[name]
            if previous.pos.file != mission.file:  # another file that declares this name
                if not isinstance(previous, DuplicateTreeError):
                    self.broken[name] = _duplicate(mission, previous.pos.file)
                return None
        self.broken.pop(name, None)  # (re)loaded from its own file
        self._missions[name] = mission
        return mission

    @overload
    def load_file(self, path: str | Path, *, strict: Literal[True] = True) -> Mission: ...

    @overload
    def load_file(self, path: str | Path, *, strict: bool) -> Mission | None: ...

    def load_file(self, path: str | Path, *, strict: bool = True) -> Mission | None:
        """Parse one file and add it (see :meth:`add`).

        Without ``strict``, a file that does not parse is recorded in :attr:`broken`
        (under the tree name it declares, when that can be read, else under the file)
        and ``None`` is returned.

        Raises:
            MissionError: (strict) the file does not parse, or its name is taken.
        """
        if strict:
            return self.add(read_mission(path))
        try:
            mission = read_mission(path)
        except MissionError as error:
            name = _declared_name(path)
            key = name if name is not None and name not in self._missions else str(path)
            self.broken[key] = error
            return None
        return self.add(mission, strict=False)

    def load_folder(self, folder: str | Path, *, strict: bool = True) -> list[Mission]:
        """Parse every ``*.yaml`` / ``*.yml`` file of a folder (not recursive), in name order.

        Without ``strict``, files that do not parse (or declare a name another file
        declares) are recorded in :attr:`broken` and the others are returned.

        Raises:
            MissionError: the folder cannot be listed, or (strict) the first file that
                does not parse.
        """
        try:
            paths = sorted(p for p in Path(folder).iterdir() if p.suffix in (".yaml", ".yml") and p.is_file())
        except OSError as exc:  # missing, not a folder, no permission (also from is_file)
            raise MissionError(Pos(str(folder), 1, 1), f"cannot read trees folder: {exc.strerror or exc}") from None
        missions = [self.load_file(p, strict=strict) for p in paths]
        return [m for m in missions if m is not None and self._missions.get(m.name) is m]

    # ------------------------------------------------------------ lookup

    def __contains__(self, name: object) -> bool:
        """True for the trees that loaded, and for the tree names that were skipped
        (``library[name]`` then raises the reason)."""
        return name in self._missions or self.is_skipped(name)

    def __getitem__(self, name: str) -> Mission:
        """The mission of tree ``name``.

        Raises:
            SkippedTreeError: the tree was skipped; the error says why.
            KeyError: no such tree.
        """
        mission = self._missions.get(name)
        if mission is None:
            if self.is_skipped(name):
                raise SkippedTreeError(name, self.broken[name])
            raise KeyError(name)
        return mission

    def __iter__(self) -> Iterator[Mission]:
        return iter(self._missions.values())

    def __len__(self) -> int:
        return len(self._missions)

    @property
    def names(self) -> list[str]:
        """The trees that loaded (not the skipped ones)."""
        return list(self._missions)

    def is_skipped(self, name: object) -> bool:
        """True when ``name`` is a tree name that tolerant loading skipped."""
        return isinstance(name, str) and name in self.broken and _TREE_NAME.fullmatch(name) is not None

    def info(self, name: str) -> TreeInfo:
        mission = self._missions[name]
        return TreeInfo(name, name, mission.signature(), mission.doc, mission)

    def resolve(self, name: str) -> ActorInfo:
        """A library tree by name, else whatever the actor resolver says.

        Raises:
            UnknownActorError: neither knows the name (``.suggestions`` lists close ones).
        """
        if name in self._missions:
            return self.info(name)
        if self.is_skipped(name):
            raise SkippedTreeError(name, self.broken[name])
        if self.resolver is None:
            return _UNCHECKED
        try:
            return self.resolver(name)
        except (LookupError, ActorbtError) as exc:
            suggestions = getattr(exc, "suggestions", None)
            if suggestions is None or not self._missions:
                raise
            # Offer library trees too: they are not registered with the runtime yet.
            raise UnknownActorError(name, [*suggestions, *self._missions]) from exc

    # ------------------------------------------------------------ validation

    def validate(self, names: Iterable[str] | None = None) -> list[MissionError]:
        """Every load-time problem of the named trees (all by default), by file and position."""
        errors: list[MissionError] = []
        for name in names if names is not None else list(self._missions):
            errors.extend(
                validate_mission(
                    self._missions[name],
                    self.resolve,
                    behaviours=self.behaviours,
                    trees=self._missions,
                    nodes=self.nodes,
                )
            )
        return sorted(errors, key=lambda e: (e.pos.file, e.pos.line, e.pos.column))

    def check(self, names: Iterable[str] | None = None, *, strict: bool = True) -> dict[str, MissionError]:
        """Validate the named trees (all by default).

        ``strict`` raises the first problem. Otherwise every tree with a problem is
        skipped (see :meth:`skip`), then every tree of the library that calls a skipped
        tree, directly or not; the newly skipped trees are returned, ``{name: error}``.

        Raises:
            MissionError: (strict) the first problem.
        """
        if strict:
            errors = self.validate(names)
            if errors:
                raise errors[0]
            return {}
        before = set(self.broken)
        self.skip_dependents()  # trees calling what did not even parse
        # Validate all first, skip after: a caller is checked against its callee's
        # signature, and its dependency on a broken callee is reported below.
        found: dict[str, MissionError] = {}
        for name in list(names if names is not None else self._missions):
            mission = self._missions.get(name)
            if mission is None:
                continue
            errors = validate_mission(
                mission, self.resolve, behaviours=self.behaviours, trees=self._missions, nodes=self.nodes
            )
            if errors:
                found[name] = min(errors, key=lambda e: (e.pos.line, e.pos.column))
        for name, error in found.items():
            self.skip(name, error)
        self.skip_dependents()
        return {k: e for k, e in self.broken.items() if k not in before}

    def skip(self, name: str, error: MissionError, *, key: str | None = None) -> None:
        """Take tree ``name`` out of the library, with the reason; the trees that call it
        are skipped by the next :meth:`skip_dependents` (or tolerant :meth:`check`).

        ``key`` records it in :attr:`broken` under another key than its name (its file,
        when the name means something else, such as an actor the tree would hide).
        """
        self._missions.pop(name, None)
        self.broken[key if key is not None else name] = error

    def skip_dependents(self) -> dict[str, MissionError]:
        """Skip every tree that calls a skipped tree, directly or not; returns them."""
        skipped: dict[str, MissionError] = {}
        changed = True
        while changed:
            changed = False
            for name, mission in list(self._missions.items()):
                for node in walk(mission.root):
                    if isinstance(node, Do) and self.is_skipped(node.actor):
                        error = self.broken[node.actor]
                        if isinstance(error, BrokenDependencyError):
                            chain, root = [node.actor, *error.chain], error.root
                        else:
                            chain, root = [node.actor], error
                        skipped[name] = BrokenDependencyError(node.at(node.kind), chain, root)
                        self.skip(name, skipped[name])
                        changed = True
                        break
        return skipped


def load_mission(
    path: str | Path,
    resolver: Resolver | None = None,
    *,
    behaviours: Collection[str] | None = None,
    library: TreeLibrary | None = None,
) -> Mission:
    """Read, parse and validate one mission file.

    Args:
        path: the YAML file.
        resolver: actor resolver (``rt.root.resolve``); ``None`` skips actor checks.
        behaviours: names ``behaviour:`` may use.
        library: trees the mission may call; the mission is added to it.

    Raises:
        MissionError: the first problem, ``file:line:column: message``.
    """
    mission = read_mission(path)
    if library is None:
        library = TreeLibrary(resolver, behaviours)
    library.add(mission)
    library.check([mission.name])
    return mission


def check_files(
    paths: Iterable[str | Path],
    resolver: Resolver | None = None,
    *,
    behaviours: Collection[str] | None = None,
    library: TreeLibrary | None = None,
) -> list[MissionError]:
    """Validate mission files without running them (``actorbt check FILE...``).

    The files are validated together (they may call each other), plus whatever trees
    ``library`` already holds. Returns every problem found, by file and position; a file
    that does not parse contributes its first error only.
    """
    library = library if library is not None else TreeLibrary(resolver, behaviours)
    errors: list[MissionError] = []
    names: list[str] = []
    for path in paths:
        try:
            names.append(library.load_file(path).name)
        except MissionError as exc:
            errors.append(exc)
    errors.extend(library.validate(names))
    return sorted(errors, key=lambda e: (e.pos.file, e.pos.line, e.pos.column))
