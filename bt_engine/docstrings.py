"""Parameter docs of actors: the ``Args:`` convention, and explicit docs.

An actor documents its parameters in a Google-style ``Args:`` section of its docstring,
one ``name: text`` entry per parameter (more-indented lines continue it). A unit goes
in square brackets and stays part of the text; the catalog also reports it alone::

    @actor
    def goto(self, x: float, y: float, timeout: float | None = None) -> tuple:
        \"\"\"Drive to (x, y) in the map frame.

        Args:
            x: goal x in the map frame [m]
            y: goal y in the map frame [m]
            timeout: give up after this long [s]; default from the path length
        \"\"\"

Also understood: ``Arguments:`` / ``Parameters:``, ``name (type): text`` (the type in
parentheses is ignored, the hints say it), ``*q:`` for a variadic parameter, and
``x, y: text`` for several parameters with the same text. A ``Returns:`` (or
``Yields:``) section describes the result.

Where a docstring is not possible (a generated callable, a tree), :func:`param_docs`
attaches the same information to the function; it wins over the docstring.
"""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

#: the attributes :func:`param_docs` sets on a function
PARAMS_ATTR = "_actor_param_docs"
RETURNS_ATTR = "_actor_returns_doc"

_ARGS = {"args", "arguments", "parameters", "params", "keyword args", "keyword arguments"}
_RETURNS = {"returns", "return", "yields", "yield"}
_HEADER = re.compile(r"^(?P<indent>\s*)(?P<name>[A-Za-z][A-Za-z ]*?)\s*:\s*$")
_ENTRY = re.compile(
    r"^(?P<names>\*{0,2}[A-Za-z_]\w*(?:\s*,\s*\*{0,2}[A-Za-z_]\w*)*)"
    r"\s*(?:\([^)]*\))?\s*:(?:\s+(?P<text>.*)|$)"
)
_BRACKET = re.compile(r"\[([^\[\]]*)\]")
_UNIT = re.compile(r"^(?=.*[A-Za-zµ°%Ω])[\wµ°%Ω/^*·.\-]{1,12}$")


@dataclass(frozen=True)
class Docstring:
    """A docstring split for the catalog.

    Attributes:
        text: the docstring without its ``Args:`` and ``Returns:`` sections, lines as
            written (what ``actorbt catalog`` prints above the parameters).
        summary: the first paragraph, on one line.
        details: the other paragraphs, each on one line, without the ``Args:`` and
            ``Returns:`` sections ("" when there are none).
        params: parameter name -> its text, in the order written.
        returns: the ``Returns:`` / ``Yields:`` text ("" when there is none).
    """

    text: str = ""
    summary: str = ""
    details: str = ""
    params: dict[str, str] = field(default_factory=dict)
    returns: str = ""


def parse(doc: str | None) -> Docstring:
    """Split a docstring into summary, details, parameter texts and returns text."""
    lines = inspect.cleandoc(doc or "").splitlines()
    kept: list[str] = []
    params: dict[str, str] = {}
    returns = ""
    i = 0
    while i < len(lines):
        m = _HEADER.match(lines[i])
        section = m.group("name").lower() if m else ""
        if m is None or (section not in _ARGS and section not in _RETURNS):
            kept.append(lines[i])
            i += 1
            continue
        indent = len(m.group("indent"))
        body: list[str] = []
        i += 1
        while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > indent):
            body.append(lines[i])
            i += 1
        if section in _ARGS:
            params.update(_entries(body))
        else:
            returns = _one_line(body)
    paragraphs = [_one_line(p) for p in _paragraphs(kept)]
    text = re.sub(r"\n{3,}", "\n\n", "\n".join(line.rstrip() for line in kept).strip("\n"))
    return Docstring(text, paragraphs[0] if paragraphs else "", "\n".join(paragraphs[1:]), params, returns)


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _one_line(lines: list[str]) -> str:
    return " ".join(" ".join(line.split()) for line in lines if line.strip())


def _paragraphs(lines: list[str]) -> list[list[str]]:
    out: list[list[str]] = [[]]
    for line in lines:
        if line.strip():
            out[-1].append(line)
        elif out[-1]:
            out.append([])
    return [p for p in out if p]


def _entries(body: list[str]) -> dict[str, str]:
    """``name: text`` entries of a section body; lines indented deeper than the first
    entry (or not of the entry form) continue the entry above."""
    filled = [line for line in body if line.strip()]
    if not filled:
        return {}
    column = _indent(filled[0])
    out: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in filled:
        m = _ENTRY.match(line.strip()) if _indent(line) <= column else None
        if m:
            current = [m.group("text") or ""]
            for name in m.group("names").split(","):
                out[name.strip().lstrip("*")] = current
        elif current is not None:
            current.append(line)
    return {name: _one_line(text) for name, text in out.items()}


def unit_of(text: str | None) -> str | None:
    """The unit a text gives in square brackets (``"goal x [m]"`` -> ``"m"``), or None.

    A bracket holds a unit when it is one short word with a letter and no spaces
    (``[m]``, ``[rad/s]``, ``[m/s^2]``, ``[deg]``, ``[%]``); ``[x, y]`` is not one. When
    the text names several different units (``x, y [m], yaw [rad]``), it has no single
    unit and None is returned.
    """
    units = {u.strip() for u in _BRACKET.findall(text or "") if _UNIT.match(u.strip())}
    return units.pop() if len(units) == 1 else None


def param_docs(
    docs: Mapping[str, str] | None = None, /, *, returns: str | Mapping[str, Any] | None = None, **more: str
) -> Callable[[F], F]:
    """Document an actor's parameters without a docstring ``Args:`` section.

    ::

        @actor
        @param_docs(x="goal x [m]", y="goal y [m]")
        def goto(self, x: float, y: float) -> None: ...

    ``returns``: a text, or a JSON-Schema fragment, describing the result. These win over
    the docstring's entries of the same names.
    """

    def deco(fn: F) -> F:
        return attach(fn, {**(docs or {}), **more}, returns)

    return deco


def attach(fn: F, params: Mapping[str, str] | None = None, returns: str | Mapping[str, Any] | None = None) -> F:
    """Attach parameter docs (and a result description) to ``fn``; returns ``fn``."""
    if params:
        setattr(fn, PARAMS_ATTR, {**getattr(fn, PARAMS_ATTR, {}), **params})
    if returns is not None:
        setattr(fn, RETURNS_ATTR, returns)
    return fn


def explicit(fn: Callable[..., Any]) -> tuple[dict[str, str], str | Mapping[str, Any] | None]:
    """What :func:`param_docs` / :func:`attach` put on ``fn`` (a bound method reads its
    function's): the parameter docs and the result description."""
    params = getattr(fn, PARAMS_ATTR, None)
    return (dict(params) if isinstance(params, Mapping) else {}), getattr(fn, RETURNS_ATTR, None)
