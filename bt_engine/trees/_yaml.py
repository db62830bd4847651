"""Safe YAML parsing that keeps the position of every node.

PyYAML's ``SafeLoader`` composes a node graph whose marks know line and column; the
constructed Python values forget them. We compose, then walk the graph ourselves into
:class:`YMap` / :class:`YSeq` / :class:`YScalar`, so that every later error can point at
``file:line:column``. Walking ourselves is also where duplicate keys are rejected, since
SafeLoader silently keeps the last one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator, Union

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from ._errors import DuplicateKeyError, MissionSyntaxError, Pos

__all__ = ["YMap", "YNode", "YScalar", "YSeq", "parse_yaml", "plain"]

_MERGE_TAG = "tag:yaml.org,2002:merge"
_CORE = "tag:yaml.org,2002:"
_PLAIN_TAGS = {"str", "int", "float", "bool", "null", "timestamp", "binary"}


def _pos(file: str, mark: yaml.Mark) -> Pos:
    return Pos(file, mark.line + 1, mark.column + 1)


@dataclass(frozen=True, eq=False)
class YScalar:
    """A scalar with its constructed value and its source text.

    Attributes:
        value: what SafeLoader makes of it (str, int, float, bool, None, date...).
        raw: the scalar's text as written, without quotes.
        style: ``None`` for plain, ``'"'``/``"'"`` for quoted, ``"|"``/``">"`` for blocks.
        pos: where the scalar starts (at the opening quote when quoted).
    """

    value: Any
    raw: str
    style: str | None
    pos: Pos

    @property
    def text_pos(self) -> Pos:
        """Where ``raw`` starts: after the opening quote of a quoted scalar."""
        return self.pos.shifted(1) if self.style in ('"', "'") else self.pos

    def pos_at(self, offset: int) -> Pos:
        """Position of character ``offset`` of ``raw``, exact for one-line scalars."""
        if self.style in ("|", ">") or "\n" in self.raw[:offset]:
            return self.pos
        return self.text_pos.shifted(offset)


@dataclass(frozen=True, eq=False)
class YSeq:
    """A YAML sequence whose items keep their positions."""

    items: tuple[YNode, ...]
    pos: Pos

    def __iter__(self) -> Iterator[YNode]:
        return iter(self.items)

    def __len__(self) -> int:
        return len(self.items)


@dataclass(frozen=True, eq=False)
class YMap:
    """A YAML mapping with string keys, in source order, without duplicates."""

    items: tuple[tuple[YScalar, YNode], ...]
    pos: Pos

    def keys(self) -> list[str]:
        return [k.raw for k, _ in self.items]

    def get(self, key: str) -> YNode | None:
        for k, v in self.items:
            if k.raw == key:
                return v
        return None

    def key_node(self, key: str) -> YScalar | None:
        for k, _ in self.items:
            if k.raw == key:
                return k
        return None

    def __contains__(self, key: object) -> bool:
        return any(k.raw == key for k, _ in self.items)

    def __len__(self) -> int:
        return len(self.items)


YNode = Union[YScalar, YSeq, YMap]


class _Walker:
    def __init__(self, loader: yaml.SafeLoader, file: str) -> None:
        self.loader = loader
        self.file = file
        self.done: dict[int, YNode] = {}  # aliases share composed nodes; share ours too
        self.active: set[int] = set()

    def walk(self, node: Node) -> YNode:
        key = id(node)
        if key in self.done:
            return self.done[key]
        pos = _pos(self.file, node.start_mark)
        if key in self.active:
            raise MissionSyntaxError(pos, "recursive YAML alias, expected a finite document")
        self.active.add(key)
        try:
            result = self._walk(node, pos)
        finally:
            self.active.discard(key)
        self.done[key] = result
        return result

    def _walk(self, node: Node, pos: Pos) -> YNode:
        if isinstance(node, ScalarNode):
            if not (node.tag.startswith(_CORE) and node.tag[len(_CORE):] in _PLAIN_TAGS):
                raise MissionSyntaxError(pos, f"unsupported YAML tag {node.tag!r}, expected plain YAML values")
            try:
                value = self.loader.construct_object(node, deep=True)
            except yaml.MarkedYAMLError as exc:
                raise _syntax_error(self.file, exc) from None
            return YScalar(value, node.value, node.style, pos)
        if isinstance(node, SequenceNode):
            if node.tag != "tag:yaml.org,2002:seq":
                raise MissionSyntaxError(pos, f"unsupported YAML tag {node.tag!r}, expected a plain list")
            return YSeq(tuple(self.walk(item) for item in node.value), pos)
        if isinstance(node, MappingNode):
            if node.tag != "tag:yaml.org,2002:map":
                raise MissionSyntaxError(pos, f"unsupported YAML tag {node.tag!r}, expected a plain mapping")
            items: list[tuple[YScalar, YNode]] = []
            seen: dict[str, Pos] = {}
            for key_node, value_node in node.value:
                key_pos = _pos(self.file, key_node.start_mark)
                if key_node.tag == _MERGE_TAG:
                    raise MissionSyntaxError(key_pos, "YAML merge keys (<<) are not supported, expected the fields written out")
                key = self.walk(key_node)
                if not isinstance(key, YScalar) or isinstance(key.value, (list, dict)):
                    raise MissionSyntaxError(key_pos, "complex mapping key, expected a plain string key")
                if key.raw in seen:
                    first = seen[key.raw]
                    raise DuplicateKeyError(
                        key_pos,
                        f"duplicate key {key.raw!r} (first at line {first.line}, column {first.column}), "
                        "expected each key once per mapping",
                    )
                seen[key.raw] = key_pos
                items.append((key, self.walk(value_node)))
            return YMap(tuple(items), pos)
        raise MissionSyntaxError(pos, f"unsupported YAML node {type(node).__name__}")  # pragma: no cover


def _syntax_error(file: str, exc: yaml.MarkedYAMLError) -> MissionSyntaxError:
    mark = exc.problem_mark or exc.context_mark
    pos = _pos(file, mark) if mark is not None else Pos(file, 1, 1)
    what = exc.problem or "invalid YAML"
    if exc.context:
        what = f"{exc.context}, {what}"
    return MissionSyntaxError(pos, f"YAML syntax error: {what}")


def parse_yaml(text: str, file: str) -> YNode | None:
    """Parse one YAML document into position-keeping nodes (``None`` if empty).

    Raises:
        MissionSyntaxError: invalid YAML, several documents, unsupported tags or aliases.
        DuplicateKeyError: a mapping repeats a key.
    """
    loader = yaml.SafeLoader(text)
    try:
        try:
            node = loader.get_single_node()
        except yaml.MarkedYAMLError as exc:
            raise _syntax_error(file, exc) from None
        except yaml.YAMLError as exc:  # reader errors: bad bytes, control characters
            raise MissionSyntaxError(Pos(file, 1, 1), f"YAML error: {exc}") from None
        except RecursionError:
            raise MissionSyntaxError(Pos(file, 1, 1), "YAML nested too deeply") from None
        if node is None:
            return None
        try:
            return _Walker(loader, file).walk(node)
        except RecursionError:
            raise MissionSyntaxError(_pos(file, node.start_mark), "YAML nested too deeply") from None
    finally:
        loader.dispose()


def plain(node: YNode) -> Any:
    """The plain Python value of a node (positions dropped)."""
    if isinstance(node, YScalar):
        return node.value
    if isinstance(node, YSeq):
        return [plain(item) for item in node.items]
    return {k.raw: plain(v) for k, v in node.items}
