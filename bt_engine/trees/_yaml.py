"""Safe YAML parsing that keeps the position of every node.

PyYAML's ``SafeLoader`` composes a node graph whose marks know line and column; the
constructed Python values forget them. We compose, then walk the graph ourselves into
:class:`YMap` / :class:`YSeq` / :class:`YScalar`, so that every later error can point at
``file:line:column``. Walking ourselves is also where duplicate keys are rejected, since
SafeLoader silently keeps the last one.

Mission files come from people and tools, so nothing in them may crash the loader: each
limit below turns what would be a ``ReaderError``, ``RecursionError``, ``ValueError``
(Python's 4,300-digit int limit) or an alias bomb into a positioned MissionError.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator, Protocol, Union

import yaml
from yaml.events import AliasEvent, CollectionStartEvent
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.reader import Reader

from ._errors import DuplicateKeyError, LimitError, MissionSyntaxError, Pos, shorten
from ..yaml_hints import syntax_mark, syntax_message

__all__ = [
    "MAX_NUMBER_DIGITS",
    "MAX_SCALAR_LENGTH",
    "MAX_YAML_DEPTH",
    "YMap",
    "YNode",
    "YScalar",
    "YSeq",
    "parse_yaml",
    "plain",
]

#: Deepest nesting of YAML mappings and lists. Composing, walking and parsing recurse
#: once per level; 100 keeps every stage far below Python's recursion limit and allows
#: trees about 50 nodes deep (real missions are under 15).
MAX_YAML_DEPTH = 100

#: Longest scalar (string, number, expression) in characters.
MAX_SCALAR_LENGTH = 10_000

#: Longest int or float scalar in characters (Python refuses int <-> str conversions
#: past 4,300 digits; no mission needs more than a few).
MAX_NUMBER_DIGITS = 100

_MERGE_TAG = "tag:yaml.org,2002:merge"
_CORE = "tag:yaml.org,2002:"
_PLAIN_TAGS = {"str", "int", "float", "bool", "null", "timestamp", "binary"}
_NUMBER_TAGS = {_CORE + "int", _CORE + "float"}
_VALUE_TAG = _CORE + "value"  # what YAML 1.1 makes of a lone plain '='


class _Mark(Protocol):
    """Where PyYAML saw something (``yaml.Mark``, or the C loader's own mark), 0-based."""

    line: int
    column: int


def _pos(file: str, mark: _Mark | None) -> Pos:
    """The 1-based position of ``mark``; the start of the file when PyYAML gives none."""
    if mark is None:
        return Pos(file, 1, 1)
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

    def required(self, key: str) -> YNode:
        """The value of ``key``, which the caller has checked is there."""
        value = self.get(key)
        if value is None:
            raise LookupError(f"no {key!r} in the mapping at {self.pos}")
        return value

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


class _Loader(yaml.SafeLoader):
    """SafeLoader that refuses aliases and nesting past MAX_YAML_DEPTH, at the place
    they occur (PyYAML's composer recurses once per level)."""

    def __init__(self, text: str, file: str) -> None:
        super().__init__(text)
        self.file = file
        self.depth = 0

    def compose_node(self, parent: Node | None, index: int | Node | None) -> Node | None:
        event = self.peek_event()
        if isinstance(event, AliasEvent):
            # An alias shares a node: nine of them nested make a billion items once expanded.
            raise MissionSyntaxError(
                _pos(self.file, event.start_mark),
                f"YAML alias *{shorten(event.anchor)[1:-1]} is not supported, expected the value written out",
            )
        nested = isinstance(event, CollectionStartEvent)
        if nested:
            if self.depth >= MAX_YAML_DEPTH:
                raise _too_deep(self.file, event.start_mark)
            self.depth += 1
        try:
            # types-PyYAML has index: int, but the composer passes the key node for a
            # mapping's value and None for a document's root
            return super().compose_node(parent, index)  # type: ignore[arg-type]
        finally:
            if nested:
                self.depth -= 1

    def fetch_flow_collection_start(self, TokenClass: type) -> None:
        # The scanner runs ahead of the composer, and its work per token grows with the
        # number of open '[' / '{': stop it at the same depth. Open block collections
        # are its indents (an indentless list has none: then the composer stops first).
        if self.flow_level + len(self.indents) >= MAX_YAML_DEPTH:
            raise _too_deep(self.file, self.get_mark())
        super().fetch_flow_collection_start(TokenClass)


def _too_deep(file: str, mark: _Mark | None) -> LimitError:
    return LimitError(
        _pos(file, mark),
        f"YAML nested deeper than {MAX_YAML_DEPTH} levels, expected a flatter mission "
        "(move deep parts into trees of their own)",
    )


class _Walker:
    def __init__(self, loader: yaml.SafeLoader, file: str) -> None:
        self.loader = loader
        self.file = file

    def walk(self, node: Node) -> YNode:
        pos = _pos(self.file, node.start_mark)
        if isinstance(node, ScalarNode):
            return self.scalar(node, pos)
        if isinstance(node, SequenceNode):
            if node.tag != "tag:yaml.org,2002:seq":
                raise MissionSyntaxError(pos, f"unsupported YAML tag {shorten(node.tag, 80)}, expected a plain list")
            return YSeq(tuple(self.walk(item) for item in node.value), pos)
        if isinstance(node, MappingNode):
            if node.tag != "tag:yaml.org,2002:map":
                raise MissionSyntaxError(pos, f"unsupported YAML tag {shorten(node.tag, 80)}, expected a plain mapping")
            items: list[tuple[YScalar, YNode]] = []
            seen: dict[str, Pos] = {}
            for key_node, value_node in node.value:
                key_pos = _pos(self.file, key_node.start_mark)
                if key_node.tag == _MERGE_TAG:
                    raise MissionSyntaxError(
                        key_pos, "YAML merge keys (<<) are not supported, expected the fields written out"
                    )
                key = self.walk(key_node)
                if not isinstance(key, YScalar) or isinstance(key.value, (list, dict)):
                    raise MissionSyntaxError(key_pos, "complex mapping key, expected a plain string key")
                if key.raw in seen:
                    first = seen[key.raw]
                    raise DuplicateKeyError(
                        key_pos,
                        f"duplicate key {shorten(key.raw)} (first at line {first.line}, column {first.column}), "
                        "expected each key once per mapping",
                    )
                seen[key.raw] = key_pos
                items.append((key, self.walk(value_node)))
            return YMap(tuple(items), pos)
        raise MissionSyntaxError(pos, f"unsupported YAML node {type(node).__name__}")  # pragma: no cover

    def scalar(self, node: ScalarNode, pos: Pos) -> YScalar:
        text = node.value
        if len(text) > MAX_SCALAR_LENGTH:
            raise LimitError(pos, f"YAML value longer than {MAX_SCALAR_LENGTH} characters, expected a shorter value")
        if node.tag == _VALUE_TAG:
            return YScalar(text, text, node.style, pos)
        if not (node.tag.startswith(_CORE) and node.tag[len(_CORE) :] in _PLAIN_TAGS):
            raise MissionSyntaxError(pos, f"unsupported YAML tag {shorten(node.tag, 80)}, expected plain YAML values")
        kind = node.tag[len(_CORE) :]
        if node.tag in _NUMBER_TAGS and len(text) > MAX_NUMBER_DIGITS:
            raise LimitError(
                pos,
                f"number longer than {MAX_NUMBER_DIGITS} digits, expected a shorter number "
                "(quote it to keep it as text)",
            )
        # An explicit tag must agree with the text: SafeLoader's constructors assume it
        # does and fail with KeyError or AttributeError on `!!bool maybe`, `!!timestamp x`.
        if kind not in ("str", "binary"):
            implicit = self.loader.resolve(ScalarNode, text, (True, False))
            if node.tag != implicit and not (kind == "float" and implicit == _CORE + "int"):
                raise MissionSyntaxError(pos, f"{shorten(text)} is not a valid {kind}, expected a {kind} or no tag")
        try:
            value = self.loader.construct_object(node, deep=True)
        except yaml.MarkedYAMLError as exc:
            raise _syntax_error(self.file, exc) from None
        except (ValueError, OverflowError) as exc:  # dates that do not exist: 2001-02-30
            raise MissionSyntaxError(
                pos, f"invalid {kind} {shorten(text)}: {exc}, expected a valid {kind} (quote it to keep it as text)"
            ) from None
        return YScalar(value, text, node.style, pos)


def _check_printable(text: str, file: str) -> None:
    # PyYAML's reader checks this in the loader's constructor, with a character offset.
    bad = Reader.NON_PRINTABLE.search(text)
    if bad is None:
        return
    line = text.count("\n", 0, bad.start()) + 1
    column = bad.start() - (text.rfind("\n", 0, bad.start()) + 1) + 1
    raise MissionSyntaxError(
        Pos(file, line, column),
        f"non-printable character U+{ord(bad.group()):04X} is not allowed in YAML, expected printable text "
        "(write it as an escape in a double-quoted string)",
    )


def _syntax_error(file: str, exc: yaml.MarkedYAMLError) -> MissionSyntaxError:
    mark = syntax_mark(exc)
    return MissionSyntaxError(_pos(file, mark), syntax_message(exc))


def parse_yaml(text: str, file: str) -> YNode | None:
    """Parse one YAML document into position-keeping nodes (``None`` if empty).

    Raises:
        MissionSyntaxError: invalid YAML, non-printable characters, several documents,
            unsupported tags, aliases.
        LimitError: nesting, a value or a number past MAX_YAML_DEPTH, MAX_SCALAR_LENGTH
            or MAX_NUMBER_DIGITS.
        DuplicateKeyError: a mapping repeats a key.
    """
    _check_printable(text, file)
    loader = _Loader(text, file)
    try:
        try:
            node = loader.get_single_node()
        except yaml.MarkedYAMLError as exc:
            raise _syntax_error(file, exc) from None
        if node is None:
            return None
        return _Walker(loader, file).walk(node)
    finally:
        loader.dispose()


def plain(node: YNode) -> Any:
    """The plain Python value of a node (positions dropped)."""
    if isinstance(node, YScalar):
        return node.value
    if isinstance(node, YSeq):
        return [plain(item) for item in node.items]
    return {k.raw: plain(v) for k, v in node.items}
