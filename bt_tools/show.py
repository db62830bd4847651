"""Pictures of a mission: an ASCII tree for the terminal and Graphviz DOT for drawings.

``actorbt show TREE`` prints :func:`ascii_tree`; ``--out x.dot`` writes :func:`dot_tree`,
and ``--out x.png`` / ``x.svg`` renders it with Graphviz' ``dot`` (installed by
``make deps``; without it, write ``.dot`` and run ``dot -Tpng x.dot -o x.png``).

The DOT source is built with the ``graphviz`` package (quoting, escaping, running
``dot``), imported only when a drawing is made.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from bt_engine.errors import ActorbtError
from bt_engine.trees import (
    Check,
    Decorator,
    Do,
    Mission,
    Node,
    IfThenElse,
    Parallel,
    PipelineSequence,
    PluginControl,
    PluginNode,
    ReactiveSelector,
    ReactiveSequence,
    Recovery,
    ResumeSequence,
    Selector,
    Sequence,
    SetValues,
    UseBehaviour,
    Wait,
    WhileDoElse,
    children_of,
)

if TYPE_CHECKING:
    import graphviz

__all__ = ["RenderError", "ascii_tree", "describe", "dot_graph", "dot_tree", "render"]


class RenderError(ActorbtError):
    """A drawing could not be made (unknown format, Graphviz missing or failing)."""


def _value(value: object) -> str:
    text = str(value) if not isinstance(value, (dict, list)) else json.dumps(value, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


def describe(node: Node) -> str:
    """One line about a node: its kind and what it does."""
    if isinstance(node, Do):
        args = [_value(a) for a in node.args] + [f"{k}={_value(v)}" for k, v in node.kwargs.items()]
        text = f"{node.kind} {node.actor}({', '.join(args)})"
        return text + (f" -> {node.out}" if node.out else "")
    if isinstance(node, SetValues):
        return "set " + ", ".join(f"{k}={_value(v)}" for k, v in node.values.items())
    if isinstance(node, Check):
        return f"check {node.source}"
    if isinstance(node, Wait):
        return f"wait {node.seconds}s"
    if isinstance(node, UseBehaviour):
        return f"behaviour {node.behaviour}"
    if isinstance(node, PluginNode):
        ports = [f"{k}={_value(v)}" for k, v in node.ports.items()] + [f"{k}->{v}" for k, v in node.outs.items()]
        return f"{node.kind} {node.plugin}" + (f"({', '.join(ports)})" if ports else "")
    if isinstance(node, Parallel) and node.counted:
        return f"parallel success_count={node.success_count} failure_count={node.failure_count}"
    if isinstance(node, Parallel):
        selected = f" {list(node.selected)}" if node.selected else ""
        return f"parallel {node.policy.value}{selected}"
    return node.default_label()


def _line(node: Node) -> str:
    what = describe(node)
    return f"{node.name}  [{what}]" if node.name is not None else what


def ascii_tree(mission: Mission) -> str:
    """The mission as an indented tree, one node per line."""
    inputs = ", ".join(
        f"{i.name}: {i.type.value}" + ("" if i.required else f" = {i.default!r}") for i in mission.inputs
    )
    outputs = ", ".join(o.name for o in mission.outputs)
    lines = [f"{mission.name}({inputs}) -> {{{outputs}}}"]

    def emit(node: Node, prefix: str, last: bool) -> None:
        lines.append(f"{prefix}{'└── ' if last else '├── '}{_line(node)}")
        kids = children_of(node)
        for i, child in enumerate(kids):
            emit(child, prefix + ("    " if last else "│   "), i == len(kids) - 1)

    emit(mission.root, "", True)
    return "\n".join(lines)


#: node attributes by node class, first match wins; ``label`` is a format for the text
_STYLES: list[tuple[type | tuple[type, ...], dict[str, str]]] = [
    (ReactiveSequence, {"shape": "box", "style": "rounded,filled", "fillcolor": "#fde9c8", "label": "⟳→ {}"}),
    (Sequence, {"shape": "box", "style": "filled", "fillcolor": "#fde9c8", "label": "→ {}"}),
    (ReactiveSelector, {"shape": "octagon", "style": "filled", "fillcolor": "#d4e8fc", "label": "⟳? {}"}),
    (Selector, {"shape": "octagon", "style": "filled", "fillcolor": "#d4e8fc", "label": "? {}"}),
    (ResumeSequence, {"shape": "box", "style": "filled", "fillcolor": "#fde9c8", "label": "→| {}"}),
    (PipelineSequence, {"shape": "box", "style": "filled", "fillcolor": "#fde9c8", "label": "⇶ {}"}),
    ((IfThenElse, WhileDoElse), {"shape": "diamond", "style": "filled", "fillcolor": "#d4e8fc", "label": "{}"}),
    (Recovery, {"shape": "octagon", "style": "filled", "fillcolor": "#fbd5d5", "label": "↺ {}"}),
    (Parallel, {"shape": "parallelogram", "style": "filled", "fillcolor": "#e3d7f5", "label": "⇉ {}"}),
    (PluginControl, {"shape": "box3d", "style": "filled", "fillcolor": "#d4e8fc", "label": "{}"}),
    (Decorator, {"shape": "ellipse", "style": "filled", "fillcolor": "#eeeeee", "label": "{}"}),
    (Do, {"shape": "box", "style": "rounded,filled", "fillcolor": "#d8f3d8", "label": "{}"}),
    (Check, {"shape": "ellipse", "style": "filled", "fillcolor": "#fff7b3", "label": "{}"}),
]


def dot_graph(mission: Mission) -> "graphviz.Digraph":
    """The mission as a ``graphviz.Digraph`` (top-down): name and kind on each node."""
    import graphviz

    graph = graphviz.Digraph(
        mission.name,
        graph_attr={"rankdir": "TB", "fontname": "Helvetica"},
        node_attr={
            "fontname": "Helvetica",
            "fontsize": "11",
            "shape": "box",
            "style": "rounded,filled",
            "fillcolor": "white",
        },
    )
    count = 0

    def visit(node: Node) -> str:
        nonlocal count
        nid, count = f"n{count}", count + 1
        text = graphviz.escape(describe(node))  # mission text is literal: no \l, no <html>
        if node.name is not None:
            text = graphviz.escape(node.name) + "\\n" + text
        attrs = dict(next((style for cls, style in _STYLES if isinstance(node, cls)), {"label": "{}"}))
        attrs["label"] = graphviz.nohtml(attrs["label"].format(text))
        graph.node(nid, **attrs)
        for child in children_of(node):
            graph.edge(nid, visit(child))
        return nid

    visit(mission.root)
    return graph


def dot_tree(mission: Mission) -> str:
    """The mission as Graphviz DOT source (see :func:`dot_graph`)."""
    return dot_graph(mission).source


def render(mission: Mission, path: str | Path) -> Path:
    """Write the drawing; the suffix picks the format (.dot, .png, .svg, .pdf).

    Raises:
        RenderError: unknown suffix, or Graphviz is missing or fails.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    if fmt in ("dot", "gv"):
        path.write_text(dot_tree(mission), encoding="utf-8")
        return path
    if fmt not in ("png", "svg", "pdf"):
        raise RenderError(f"cannot draw {path.name}: unknown format {fmt!r}, expected .dot, .png, .svg or .pdf")
    import graphviz

    try:
        data = dot_graph(mission).pipe(format=fmt, quiet=True)
    except graphviz.ExecutableNotFound:
        raise RenderError(
            f"Graphviz 'dot' is not installed, so {path.name} cannot be drawn; "
            f"install graphviz (make deps) or write {path.with_suffix('.dot').name} and render it yourself"
        ) from None
    except graphviz.CalledProcessError as exc:
        stderr = (exc.stderr or b"").decode(errors="replace").strip()
        raise RenderError(f"dot failed on {path.name}: {stderr or exc}") from None
    path.write_bytes(data)
    return path
