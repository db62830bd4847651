"""A set of mission files validated together: the trees folder.

Trees call trees by name with ``do:``, so a tree is only valid in the company of the
trees it calls. The library parses every file, then resolves names to its own trees
first and to the actor resolver otherwise, and validates each mission against that,
subtree cycles included.
"""

from __future__ import annotations

import inspect
from collections.abc import Collection, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

from ..errors import ActorbtError, UnknownActorError
from ._errors import DuplicateTreeError, MissionError, Pos
from ._model import Mission
from ._parse import read_mission
from ._validate import ActorInfo, Resolver, validate_mission

__all__ = ["TreeInfo", "TreeLibrary", "check_files", "load_mission"]


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
        [inspect.Parameter("args", inspect.Parameter.VAR_POSITIONAL),
         inspect.Parameter("kwargs", inspect.Parameter.VAR_KEYWORD)]
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

    Example::

        lib = TreeLibrary(resolver=rt.root.resolve)
        lib.load_folder("trees")
        lib.check()                       # raises the first MissionError
        lib["demo_patrol"].signature()
    """

    def __init__(self, resolver: Resolver | None = None, behaviours: Collection[str] | None = None) -> None:
        self.resolver = resolver
        self.behaviours = behaviours
        self._missions: dict[str, Mission] = {}

    # ------------------------------------------------------------ loading

    def add(self, mission: Mission) -> Mission:
        """Add a parsed mission.

        Raises:
            DuplicateTreeError: another file already declares this tree name.
        """
        other = self._missions.get(mission.name)
        if other is not None and other.file != mission.file:
            raise DuplicateTreeError(
                mission.pos,
                f"tree name {mission.name!r} is already used by {other.file}, expected one file per tree name",
            )
        self._missions[mission.name] = mission
        return mission

    def load_file(self, path: str | Path) -> Mission:
        """Parse one file and add it (see :meth:`add`).

        Raises:
            MissionError: the file does not parse, or its name is taken.
        """
        return self.add(read_mission(path))

    def load_folder(self, folder: str | Path) -> list[Mission]:
        """Parse every ``*.yaml`` / ``*.yml`` file of a folder (not recursive), in name order.

        Raises:
            MissionError: the folder cannot be listed, or the first file that does not parse.
        """
        try:
            paths = sorted(p for p in Path(folder).iterdir() if p.suffix in (".yaml", ".yml") and p.is_file())
        except OSError as exc:  # missing, not a folder, no permission (also from is_file)
            raise MissionError(Pos(str(folder), 1, 1), f"cannot read trees folder: {exc.strerror or exc}") from None
        return [self.load_file(p) for p in paths]

    # ------------------------------------------------------------ lookup

    def __contains__(self, name: object) -> bool:
        return name in self._missions

    def __getitem__(self, name: str) -> Mission:
        return self._missions[name]

    def __iter__(self) -> Iterator[Mission]:
        return iter(self._missions.values())

    def __len__(self) -> int:
        return len(self._missions)

    @property
    def names(self) -> list[str]:
        return list(self._missions)

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
                validate_mission(self._missions[name], self.resolve, behaviours=self.behaviours, trees=self._missions)
            )
        return sorted(errors, key=lambda e: (e.pos.file, e.pos.line, e.pos.column))

    def check(self, names: Iterable[str] | None = None) -> None:
        """Raise the first problem of :meth:`validate`, if any.

        Raises:
            MissionError: the first problem.
        """
        errors = self.validate(names)
        if errors:
            raise errors[0]


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
