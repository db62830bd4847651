"""BehaviorTree.CPP v4 XML to actorbt missions: one mission (a plain dict, as its YAML
would read) per ``<BehaviorTree>``.

How the two models meet (docs/btxml.md says it for users):

- Built-in controls and decorators map to mission nodes; Nav2's PipelineSequence,
  RecoveryNode, RateController and SingleTrigger too, when the XML's long form or the
  node model says they are controls or decorators.
- Any other node is a leaf: ``do:`` the actor of that name. Its input ports are the
  arguments; its output ports are its result (the value itself for one output port, a
  mapping ``{port: value}`` for several), written to the keys the ports name.
- ``{key}`` ports are blackboard references. Keys a tree reads and does not write
  become its inputs; keys it writes become its outputs. A SubTree call passes the
  remapped ports as arguments and writes the remapped outputs back from its result.
- Scripts and pre/post conditions are translated to ``set:`` and ``check:``
  (:mod:`._script`); what has no equivalent is refused with a located error.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from bt_engine.trees import PluginSpec, Ref, keys_of, node_plugins, parse_expression, suggest
from ._builtins import BUILTINS, NAV2, UNSUPPORTED
from ._errors import BtXmlError, Pos, UnknownXmlNodeError, UnsupportedXmlError
from ._extensions import HANDLERS as EXTENSION_HANDLERS
from ._nodes import (
    JSON_PREFIX,
    NodeKind,
    NodeModel,
    NodeSpec,
    PortSpec,
    convert_literal,
    decode_json,
    guess_literal,
    plugin_ports,
)
from ._script import Assignment, condition, statements
from ._source import XElement, read_xml
from ._values import REF_TEXT, RESULT_TYPE, ref_keys, value_type_of_port

__all__ = ["BUILTINS", "NAV2", "UNSUPPORTED", "Importer", "TreeDef", "TreeInterface"]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_ACTOR = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*\Z")
_REF = re.compile(r"\{([^{}]*)\}\Z")
_LONG_FORMS = ("Action", "Condition", "Control", "Decorator", "SubTree")
#: attributes that are not ports
_META = ("name", "ID", "_uid", "_fullpath", "_description")
_PRE = ("_failureIf", "_successIf", "_skipIf", "_while")
_POST = ("_onSuccess", "_onFailure", "_post", "_onHalted")
_SELECTORS = ("selector", "reactive_selector")


@dataclass(frozen=True)
class TreeDef:
    """One ``<BehaviorTree>``: its ID, element and file."""

    id: str
    element: XElement
    file: str


@dataclass
class TreeInterface:
    """What a converted tree reads and writes: its inputs (required when it never writes
    them) and outputs, by key. When the node model declares the tree (``<SubTree ID>``),
    its ports are the interface: typed, documented, in their order, with the tree's
    description as its doc, and ``result_port`` the output port (of type
    :data:`~._values.RESULT_TYPE`) that receives the whole result mapping."""

    inputs: dict[str, bool] = field(default_factory=dict)  # key -> required
    outputs: list[str] = field(default_factory=list)
    types: dict[str, str] = field(default_factory=dict)  # key -> mission type name
    defaults: dict[str, Any] = field(default_factory=dict)
    docs: dict[str, str] = field(default_factory=dict)  # input key -> its doc
    output_types: dict[str, str] = field(default_factory=dict)
    output_docs: dict[str, str] = field(default_factory=dict)
    declared: bool = False
    doc: str | None = None
    result_port: str | None = None


class _Tree:
    """The blackboard keys one tree reads (first position) and writes, while converting."""

    def __init__(self, tree: TreeDef) -> None:
        self.tree = tree
        self.reads: dict[str, Pos] = {}
        self.writes: dict[str, Pos] = {}
        self.temps = 0

    def read(self, key: str, pos: Pos) -> None:
        self.reads.setdefault(key, pos)

    def write(self, key: str, pos: Pos) -> None:
        self.writes.setdefault(key, pos)

    def temp(self, what: str) -> str:
        self.temps += 1
        return f"_{what}_out{self.temps}"


class Importer:
    """Converts the trees of a set of XML files (``<include>`` followed).

    Args:
        model: nodes declared elsewhere (``--nodes``); ``<TreeNodesModel>`` elements in
            the imported files are added to it.
    """

    dialect = "btcpp"

    def __init__(self, model: NodeModel | None = None) -> None:
        self.model = model if model is not None else NodeModel()
        self.has_model = model is not None and len(model) > 0
        self.trees: dict[str, TreeDef] = {}
        self.order: list[str] = []
        self.main: dict[str, str] = {}  # file -> main_tree_to_execute
        self.missions: dict[str, dict] = {}
        self.interfaces: dict[str, TreeInterface] = {}
        self._active: list[tuple[str, Pos]] = []
        self._files: set[Path] = set()
        #: the controls and decorators written in Python, to read an undeclared tag by
        self.plugins: dict[str, PluginSpec] = node_plugins()

    # ------------------------------------------------------------ files

    def load(self, path: str | Path, included_at: Pos | None = None) -> None:
        """Read one file's trees, node models and includes.

        Raises:
            BtXmlError: the file does not parse, or is not a BehaviorTree.CPP v4 file.
        """
        resolved = Path(path).resolve()
        if resolved in self._files:
            return
        self._files.add(resolved)
        if included_at is not None and not Path(path).is_file():
            raise BtXmlError(
                included_at,
                f"included file {str(path)!r} does not exist, expected a path relative to the including file",
            )
        top = read_xml(path)
        self.check_root(top)
        file = str(path)
        for element in top.children:
            if element.tag == "BehaviorTree":
                self.add_tree(element, file)
            elif element.tag == "include":
                target = element.attrs.get("path")
                if not target:
                    raise BtXmlError(element.pos, '<include> has no path, expected <include path="other.xml"/>')
                if "ros_pkg" in element.attrs:
                    raise UnsupportedXmlError(
                        element.at("ros_pkg"),
                        "<include ros_pkg=...> needs a ROS package index, expected a path relative to this file",
                    )
                self.load(Path(path).parent / target, element.at("path"))
            elif element.tag == "TreeNodesModel":
                self.model.add_element(element)
                self.has_model = True
            else:
                raise UnknownXmlNodeError(
                    element.pos,
                    f"unexpected <{element.tag}> in <root>"
                    f"{suggest(element.tag, ('BehaviorTree', 'include', 'TreeNodesModel'))}, "
                    "expected <BehaviorTree>, <include> or <TreeNodesModel>",
                )
        main = top.attrs.get("main_tree_to_execute")
        if main:
            self.main[file] = main

    def check_root(self, top: XElement) -> None:
        if top.tag != "root":
            raise BtXmlError(top.pos, f'the document element is <{top.tag}>, expected <root BTCPP_format="4">')
        fmt = top.attrs.get("BTCPP_format")
        if fmt is not None and fmt != "4":
            raise UnsupportedXmlError(
                top.at("BTCPP_format"),
                f'BTCPP_format is {fmt!r}: only BehaviorTree.CPP v4 XML is imported, expected BTCPP_format="4"',
            )

    def add_tree(self, element: XElement, file: str) -> None:
        tree_id = element.attrs.get("ID") or element.attrs.get("id")
        if not tree_id:
            raise BtXmlError(element.pos, '<BehaviorTree> has no ID, expected <BehaviorTree ID="MainTree">')
        if not _IDENT.match(tree_id):
            raise BtXmlError(
                element.at("ID"), f"tree ID {tree_id!r} is not a valid mission name, expected letters, digits and '_'"
            )
        if tree_id in self.trees:
            first = self.trees[tree_id].element.pos
            raise BtXmlError(
                element.pos, f"tree {tree_id!r} is defined twice (first at {first}), expected one <BehaviorTree> per ID"
            )
        nodes = element.children
        if len(nodes) != 1:
            raise BtXmlError(
                element.pos, f'<BehaviorTree ID="{tree_id}"> has {len(nodes)} root nodes, expected exactly one'
            )
        self.trees[tree_id] = TreeDef(tree_id, element, file)
        self.order.append(tree_id)

    # ------------------------------------------------------------ trees

    def convert_all(self) -> dict[str, dict]:
        """Every tree as a mission dict, by name, in file order."""
        for tree_id in self.order:
            self.convert(tree_id, self.trees[tree_id].element.pos)
        return {tree_id: self.missions[tree_id] for tree_id in self.order}

    def convert(self, tree_id: str, at: Pos) -> TreeInterface:
        """Convert one tree (once) and return its interface; subtrees are converted first."""
        if tree_id in self.interfaces:
            return self.interfaces[tree_id]
        if any(t == tree_id for t, _ in self._active):
            chain = [t for t, _ in self._active]
            chain = chain[chain.index(tree_id) :] + [tree_id]
            raise BtXmlError(at, f"subtree cycle {' -> '.join(chain)}, expected trees that do not call themselves")
        tree = self.trees[tree_id]
        self._active.append((tree_id, at))
        try:
            ctx = _Tree(tree)
            root = self.node(tree.element.children[0], ctx, "sequence")
        finally:
            self._active.pop()
        spec = self.model.get(tree_id)
        iface = self.interface(tree_id, ctx, spec if spec is not None and spec.kind is NodeKind.SUBTREE else None)
        self.interfaces[tree_id] = iface
        self.missions[tree_id] = self.mission(tree, iface, root)
        return iface

    def interface(self, tree_id: str, ctx: _Tree, spec: NodeSpec | None) -> TreeInterface:
        iface = TreeInterface(declared=spec is not None)
        declared = {p.name: p for p in spec.ports if p.type.strip() != RESULT_TYPE} if spec is not None else {}
        if spec is not None:
            iface.doc = spec.description or None
            iface.result_port = next((p.name for p in spec.ports if p.writes and p.type.strip() == RESULT_TYPE), None)
        # A key is an input when the tree reads it before (in document order) it writes it;
        # when the model declares the subtree, its input ports are (in the model's order,
        # required when the port has no default, as BehaviorTree.CPP has it).
        read_first = [k for k, pos in ctx.reads.items() if k not in ctx.writes or _order(pos) < _order(ctx.writes[k])]
        inputs = [p.name for p in declared.values() if p.reads]
        for key in inputs if spec is not None else read_first:
            port = declared.get(key)
            iface.inputs[key] = key not in ctx.writes
            if port is not None and port.reads:
                iface.inputs[key] = port.default is None
                iface.types[key] = value_type_of_port(port.type).value
                if port.description:
                    iface.docs[key] = port.description
                if port.default is not None and not _REF.match(port.default):
                    iface.defaults[key] = _default(port.default, port, port.pos)
        if spec is None:
            iface.outputs = [k for k in ctx.writes if not k.startswith("_")]
        else:
            iface.outputs = [p.name for p in declared.values() if p.writes]
            for port in declared.values():
                if port.writes:
                    iface.output_types[port.name] = value_type_of_port(port.type).value
                    if port.description:
                        iface.output_docs[port.name] = port.description
        written = [k for k in ctx.writes if not k.startswith("_")]
        for port in declared.values():
            if port.writes and port.name not in written:
                raise BtXmlError(
                    port.pos,
                    f"subtree {tree_id!r} declares output port {port.name!r}, but nothing in it writes that key",
                )
        return iface

    def mission(self, tree: TreeDef, iface: TreeInterface, root: dict) -> dict:
        inputs: dict[str, Any] = {}
        for key, required in iface.inputs.items():
            vtype = iface.types.get(key, "any")
            spec: dict[str, Any] = {"type": vtype}
            if not required:
                spec["default"] = iface.defaults.get(key)
            if key in iface.docs:
                spec["doc"] = iface.docs[key]
            inputs[key] = vtype if list(spec) == ["type"] else spec
        mission: dict[str, Any] = {"name": tree.id}
        if iface.declared:
            if iface.doc is not None:
                mission["doc"] = iface.doc
        else:
            mission["doc"] = (
                f"Imported from {Path(tree.file).name}:{tree.element.pos.line} (BehaviorTree.CPP "
                f'<BehaviorTree ID="{tree.id}">).'
                if self.dialect == "btcpp"
                else f"Imported from {Path(tree.file).name}:{tree.element.pos.line} (pytwb)."
            )
        if inputs:
            mission["inputs"] = inputs
        if iface.output_types and any(t != "any" for t in iface.output_types.values()) or iface.output_docs:
            mission["outputs"] = {
                key: {
                    "type": iface.output_types.get(key, "any"),
                    **({"doc": iface.output_docs[key]} if key in iface.output_docs else {}),
                }
                for key in iface.outputs
            }
        elif iface.outputs:
            mission["outputs"] = list(iface.outputs)
        mission["root"] = root
        return mission

    # ------------------------------------------------------------ nodes

    def node(self, el: XElement, ctx: _Tree, parent: str) -> dict:
        """One XML node (with its pre/post conditions) as a mission node."""
        node_id, long_kind = self.identify(el)
        attrs = {k: v for k, v in el.attrs.items() if k not in _META}
        special = {k: v for k, v in attrs.items() if k.startswith("_") and k != "_autoremap"}
        for key in special:
            if key not in (*_PRE, *_POST):
                raise BtXmlError(
                    el.at(key),
                    f"unknown attribute {key!r}{suggest(key, (*_PRE, *_POST, '_autoremap'))}, "
                    f"expected one of: {', '.join((*_PRE, *_POST, '_autoremap'))}",
                )
        ports = {k: v for k, v in attrs.items() if k not in special}
        result = self.dispatch(el, node_id, long_kind, ports, ctx, parent)
        name = el.attrs.get("name")
        if name and name != node_id:
            result = _named(result, name)
        return self.wrap(el, result, special, ctx, parent)

    def identify(self, el: XElement) -> tuple[str, str | None]:
        if el.tag in _LONG_FORMS:
            node_id = el.attrs.get("ID")
            if not node_id:
                raise BtXmlError(el.pos, f'<{el.tag}> has no ID, expected e.g. <{el.tag} ID="Name">')
            return node_id, el.tag
        return el.tag, None

    def dispatch(
        self, el: XElement, node_id: str, long_kind: str | None, ports: dict[str, str], ctx: _Tree, parent: str
    ) -> dict:
        if long_kind == "SubTree":
            return self.subtree(el, node_id, ports, ctx)
        handler = BUILTINS.get(node_id)
        if handler is not None:
            return handler(self, el, node_id, ports, ctx, parent)
        spec = self.model.get(node_id)
        declared = long_kind or (spec.kind.value if spec is not None else None)
        if node_id in NAV2 and declared in ("Control", "Decorator"):
            return NAV2[node_id](self, el, node_id, ports, ctx, parent)
        if node_id in EXTENSION_HANDLERS and declared is not None:
            return EXTENSION_HANDLERS[node_id](self, el, node_id, ports, ctx, parent)
        if node_id in UNSUPPORTED:
            raise UnsupportedXmlError(el.pos, f"<{el.tag}> is not supported: {UNSUPPORTED[node_id]}")
        plugin = self.plugins.get(node_id)
        if declared in ("Control", "Decorator") or plugin is not None and declared is None and el.children:
            kind = declared or ("Control" if plugin is not None and plugin.kind == "control" else "Decorator")
            return self.plugin(el, node_id, kind, ports, ctx, spec, plugin)
        if spec is not None and spec.kind is NodeKind.SUBTREE or node_id in self.trees and self.dialect == "pytwb":
            return self.subtree(el, node_id, ports, ctx)
        if el.children:
            choices = [
                *BUILTINS,
                *NAV2,
                *(n for n, s in self.model.nodes.items() if s.kind in (NodeKind.CONTROL, NodeKind.DECORATOR)),
            ]
            raise UnknownXmlNodeError(
                el.pos,
                f"unknown control node {node_id!r}{suggest(node_id, choices)}: it has child nodes, expected a "
                "built-in control or decorator, or one that a node model (--nodes) declares as <Control> "
                "or <Decorator>",
            )
        if self.has_model and spec is None and long_kind is None:
            choices = [*BUILTINS, *self.model.nodes, *self.trees]
            raise UnknownXmlNodeError(
                el.pos,
                f"unknown node {node_id!r}{suggest(node_id, choices)}, expected a built-in node, a tree or a "
                f"node declared in the node model ({', '.join(self.model.files) or 'the XML'})",
            )
        return self.leaf(el, node_id, ports, ctx, spec, condition=declared == "Condition")

    # ------------------------------------------------------------ values

    def key(self, el: XElement, attr: str, text: str) -> str | None:
        """The blackboard key of a ``{key}`` / ``{=}`` value, or None for a literal."""
        m = _REF.match(text.strip())
        if m is None:
            return None
        key = m.group(1).strip()
        if key == "=":
            key = attr
        if key.startswith("@"):
            raise UnsupportedXmlError(
                el.at(attr),
                f"{text}: the root blackboard ('@' keys) is not supported, "
                "expected a key of this tree (pass values through SubTree ports)",
            )
        if not _IDENT.match(key):
            raise BtXmlError(
                el.at(attr), f"blackboard key {key!r} is not a valid key, expected letters, digits and '_'"
            )
        return key

    def literal(self, el: XElement, attr: str, text: str, port: PortSpec | None) -> Any:
        if port is not None and port.type:
            return _convert(text, port, el.at(attr))
        return self.guess(text)

    def guess(self, text: str) -> Any:
        value = guess_literal(text)
        return value.replace("{", "{{").replace("}", "}}") if isinstance(value, str) else value

    def input_value(self, el: XElement, attr: str, text: str, ctx: _Tree, port: PortSpec | None = None) -> Any:
        """An input port's value as a mission value: a reference (``{key}``, ``{=}``,
        ``{key.field}``), ``json:`` text (whose references are read) or a literal."""
        stripped = text.strip()
        if stripped.startswith(JSON_PREFIX):
            return self.json_value(el, attr, text, ctx)
        dotted = REF_TEXT.match(stripped)
        if dotted is not None and dotted.group(2):
            ctx.read(dotted.group(1), el.at(attr))
            return stripped
        key = self.key(el, attr, text)
        if key is None:
            return self.literal(el, attr, text, port)
        ctx.read(key, el.at(attr))
        return "{" + key + "}"

    def json_value(self, el: XElement, attr: str, text: str, ctx: _Tree) -> Any:
        """``json:`` text as a mission value: its strings are mission strings (references
        and doubled braces); the keys it references are read."""
        try:
            value = decode_json(text)
        except ValueError as exc:
            raise BtXmlError(el.at(attr), f"{attr}: {exc}, expected json: and a JSON value") from None
        for key in ref_keys(value):
            ctx.read(key, el.at(attr))
        return value

    def number(
        self, el: XElement, attr: str, text: str, ctx: _Tree, *, integer: bool, scale: float = 1.0, ref_ok: bool = True
    ) -> Any:
        dotted = REF_TEXT.match(text.strip())
        if dotted is not None and dotted.group(2) and ref_ok:
            ctx.read(dotted.group(1), el.at(attr))
            return text.strip()
        key = self.key(el, attr, text)
        if key is not None:
            if not ref_ok:
                raise UnsupportedXmlError(
                    el.at(attr),
                    f"{attr}={text!r}: a blackboard reference is not supported "
                    "here (the unit differs), expected a number",
                )
            ctx.read(key, el.at(attr))
            return "{" + key + "}"
        try:
            value = convert_literal(text, "int" if integer else "double")
        except ValueError:
            raise BtXmlError(
                el.at(attr),
                f"{attr} is {text!r}, expected {'an integer' if integer else 'a number'} or a {{key}} reference",
            ) from None
        return value * scale if scale != 1.0 else value

    def params(self, el: XElement, ports: dict[str, str], allowed: Iterable[str], required: Iterable[str] = ()) -> None:
        allowed = tuple(allowed)
        for attr in ports:
            if attr not in allowed and attr != "_autoremap":
                raise BtXmlError(
                    el.at(attr),
                    f"<{el.tag}> has no attribute {attr!r}{suggest(attr, allowed)}, "
                    f"expected {', '.join(allowed) or 'none besides name'}",
                )
        for attr in required:
            if attr not in ports:
                raise BtXmlError(el.pos, f'<{el.tag}> has no {attr!r}, expected {attr}="..."')

    def children(self, el: XElement, ctx: _Tree, kind: str, count: tuple[int, int] | None = None) -> list[dict]:
        lo, hi = count or (1, 1_000_000)
        n = len(el.children)
        if not lo <= n <= hi:
            expected = f"{lo}" if lo == hi else (f"{lo} or {hi}" if hi == lo + 1 else f"at least {lo}")
            raise BtXmlError(el.pos, f"<{el.tag}> has {n} child node{'s' if n != 1 else ''}, expected {expected}")
        kids = [self.node(child, ctx, kind) for child in el.children]
        return _distinct_names(kids)

    def child(self, el: XElement, ctx: _Tree, kind: str) -> dict:
        return self.children(el, ctx, kind, (1, 1))[0]

    def check(self, el: XElement, attr: str, text: str, ctx: _Tree) -> dict:
        expr = condition(text, lambda i: el.value_pos(attr, i))
        for key in keys_of(parse_expression(expr)):
            ctx.read(key.name, el.at(attr))
        return {"check": expr}

    def script(self, el: XElement, attr: str, text: str, ctx: _Tree, conditions: bool = False) -> list[dict]:
        """A script's assignments as ``set:`` nodes (a new one whenever a value reads a key
        this script set); with ``conditions``, its conditions as ``check:`` nodes."""
        nodes: list[dict] = []
        current: dict[str, Any] | None = None
        for statement in statements(text, lambda i: el.value_pos(attr, i)):
            if isinstance(statement, Assignment):
                value = statement.value
                if isinstance(value, Ref):
                    ctx.read(value.key, el.at(attr))
                    if current is not None and value.key in current:
                        current = None
                    value = "{" + value.key + "}"
                elif isinstance(value, str):
                    value = value.replace("{", "{{").replace("}", "}}")
                if current is None:
                    current = {}
                    nodes.append({"set": current})
                current[statement.key] = value
                ctx.write(statement.key, el.at(attr))
            elif conditions:
                for key in keys_of(parse_expression(statement)):
                    ctx.read(key.name, el.at(attr))
                nodes.append({"check": statement})
                current = None
        return nodes

    # ------------------------------------------------------------ leaves and subtrees

    def leaf(
        self,
        el: XElement,
        node_id: str,
        ports: dict[str, str],
        ctx: _Tree,
        spec: NodeSpec | None,
        condition: bool = False,
    ) -> dict:
        """An actor call: a ``condition:`` leaf for a node declared a Condition (it answers
        within the tick, as reactive parents need), else ``do:``."""
        if not _ACTOR.match(node_id):
            raise BtXmlError(el.pos, f"node {node_id!r} is not a valid actor name, expected letters, digits and '_'")
        if "_autoremap" in ports:
            raise BtXmlError(el.at("_autoremap"), "_autoremap applies to SubTree nodes only")
        declared = {p.name: p for p in spec.ports} if spec is not None else None
        args, outs = self.port_values(el, node_id, ports, declared, ctx)
        for port in spec.ports if spec is not None else ():
            if port.name in ports or port.default is None:
                continue
            key = self.key(el, port.name, port.default)
            if key is None:
                continue  # a literal default: the actor's own
            if port.reads:
                args[port.name] = "{" + key + "}"
                ctx.read(key, el.pos)
            if port.writes:
                outs.append((port.name, key))
                ctx.write(key, el.pos)
        return self.call(node_id, args, outs, ctx, "condition" if condition else "do")

    def plugin(
        self,
        el: XElement,
        node_id: str,
        kind: str,
        ports: dict[str, str],
        ctx: _Tree,
        spec: NodeSpec | None,
        plugin: PluginSpec | None,
    ) -> dict:
        """A control or decorator the model (or the long form) declares, or a registered
        plugin: a call of the plugin of that name, ``control:`` or ``decorator:``, its
        input ports as ``with:`` and its output ports as ``out:``. Ports come from the
        model, else from the plugin; a port left out is left to the plugin (its default,
        ``{key}`` defaults included, or unset)."""
        if not _IDENT.match(node_id):
            raise BtXmlError(el.pos, f"node {node_id!r} is not a valid plugin name, expected letters, digits and '_'")
        if spec is not None:
            declared: dict[str, PortSpec] | None = {p.name: p for p in spec.ports}
        else:
            declared = plugin_ports(plugin, el.pos) if plugin is not None else None
        args, out_list = self.port_values(el, node_id, ports, declared, ctx)
        outs = dict(out_list)
        mission_kind = "control" if kind == "Control" else "decorator"
        node: dict[str, Any] = {mission_kind: node_id}
        if args:
            node["with"] = args
        if outs:
            node["out"] = outs
        if mission_kind == "control":
            node["children"] = self.children(el, ctx, "control")
        else:
            node["child"] = self.child(el, ctx, "decorator")
        return node

    def port_values(
        self,
        el: XElement,
        node_id: str,
        ports: dict[str, str],
        declared: dict[str, PortSpec] | None,
        ctx: _Tree,
    ) -> tuple[dict[str, Any], list[tuple[str, str]]]:
        """A node's attributes as the inputs it reads and the (port, key) pairs it writes.
        ``declared``: its ports (the model's, or a plugin's), each attribute checked against
        them; None: nothing declares the node, so every attribute is an input."""
        args: dict[str, Any] = {}
        outs: list[tuple[str, str]] = []
        for attr, text in ports.items():
            port = declared.get(attr) if declared is not None else None
            if declared is not None and port is None:
                raise BtXmlError(
                    el.at(attr),
                    f"node {node_id!r} has no port {attr!r}{suggest(attr, declared)}, "
                    f"expected one of: {', '.join(declared) or '(no ports)'}",
                )
            if not _IDENT.match(attr):
                raise BtXmlError(el.at(attr), f"port {attr!r} is not a valid argument name")
            if port is None or port.reads:
                args[attr] = self.input_value(el, attr, text, ctx, port)
            if port is not None and port.writes:
                key = self.key(el, attr, text) or (text.strip() if _IDENT.match(text.strip()) else None)
                if key is None:
                    raise BtXmlError(
                        el.at(attr), f'output port {attr!r} is {text!r}, expected a blackboard key such as "{{goal}}"'
                    )
                outs.append((attr, key))
                ctx.write(key, el.at(attr))
        return args, outs

    def call(self, actor: str, args: dict[str, Any], outs: list[tuple[str, str]], ctx: _Tree, kind: str = "do") -> dict:
        node: dict[str, Any] = {kind: actor}
        if args:
            node["with"] = args
        if len(outs) == 1:
            node["out"] = outs[0][1]
            return node
        if not outs:
            return node
        temp = ctx.temp(actor)
        node["out"] = temp
        return {"sequence": [node, {"set": {key: "{" + f"{temp}.{port}" + "}" for port, key in outs}}]}

    def subtree(self, el: XElement, tree_id: str, ports: dict[str, str], ctx: _Tree) -> dict:
        if tree_id not in self.trees:
            raise UnknownXmlNodeError(
                el.at("ID") if "ID" in el.attrs else el.pos,
                f"unknown tree {tree_id!r}{suggest(tree_id, self.trees)}, expected one of the "
                f"imported trees: {', '.join(self.trees)}",
            )
        iface = self.convert(tree_id, el.pos)
        autoremap = ports.pop("_autoremap", "false").strip().lower() in ("true", "1")
        if ports.pop("__shared_blackboard", "false").strip().lower() in ("true", "1"):
            autoremap = True
        args: dict[str, Any] = {}
        outs: list[tuple[str, str]] = []
        result_key = None
        if iface.result_port is not None and iface.result_port in ports:
            text = ports.pop(iface.result_port)
            result_key = self.key(el, iface.result_port, text)
            if result_key is None:
                raise BtXmlError(
                    el.at(iface.result_port),
                    f"port {iface.result_port!r} receives the result of tree {tree_id!r}, "
                    f'expected a blackboard key such as "{{result}}"',
                )
            ctx.write(result_key, el.at(iface.result_port))
        spec = self.model.get(tree_id)
        known = [*iface.inputs, *(o for o in iface.outputs if o not in iface.inputs)]
        for port, text in ports.items():
            if port not in iface.inputs and port not in iface.outputs:
                raise BtXmlError(
                    el.at(port),
                    f"tree {tree_id!r} has no port {port!r}{suggest(port, known)}: it neither reads nor writes "
                    f"that key, expected one of: {', '.join(known) or '(none)'}",
                )
            if port in iface.inputs:
                declared = spec.port(port) if spec is not None and spec.kind is NodeKind.SUBTREE else None
                args[port] = self.input_value(el, port, text, ctx, declared)
            if port in iface.outputs:
                key = self.key(el, port, text) if not text.strip().startswith(JSON_PREFIX) else None
                if key is None:
                    if port not in iface.inputs:
                        raise BtXmlError(
                            el.at(port),
                            f"port {port!r} of tree {tree_id!r} is an output, expected a "
                            'blackboard key such as "{' + port + '}"',
                        )
                    continue
                outs.append((port, key))
                ctx.write(key, el.at(port))
        if autoremap:
            for port in iface.inputs:
                if port not in ports:
                    args[port] = "{" + port + "}"
                    ctx.read(port, el.pos)
            for port in iface.outputs:
                if port not in ports:
                    outs.append((port, port))
                    ctx.write(port, el.pos)
        for port, required in iface.inputs.items():
            if required and port not in args:
                raise BtXmlError(
                    el.pos,
                    f"SubTree {tree_id!r} reads {port!r}, which nothing in it writes, but this "
                    f'call does not pass it, expected {port}="{{key}}" or _autoremap="true"',
                )
        if result_key is not None:
            call = {"do": tree_id, **({"with": args} if args else {}), "out": result_key}
            if not outs:
                return call
            return {"sequence": [call, {"set": {key: "{" + f"{result_key}.{port}" + "}" for port, key in outs}}]}
        if not outs:
            return self.call(tree_id, args, [], ctx)
        temp = ctx.temp(tree_id)
        node: dict[str, Any] = {"do": tree_id, "out": temp}
        if args:
            node = {"do": tree_id, "with": args, "out": temp}
        return {"sequence": [node, {"set": {key: "{" + f"{temp}.{port}" + "}" for port, key in outs}}]}

    # ------------------------------------------------------------ pre and post conditions

    def skipped(self, parent: str) -> dict:
        """What BehaviorTree.CPP's SKIPPED means to the parent: a selector moves on as on
        a failure, everything else as on a success."""
        return {"name": "skipped", "check": "false" if parent in _SELECTORS else "true"}

    def wrap(self, el: XElement, node: dict, special: dict[str, str], ctx: _Tree, parent: str) -> dict:
        if "_onHalted" in special:
            raise UnsupportedXmlError(
                el.at("_onHalted"),
                "_onHalted is not supported: a mission runs nothing when "
                "a node is halted (cancelled actors clean up themselves)",
            )
        for attr in ("_onSuccess", "_onFailure", "_post"):
            if attr in special:
                sets = self.script(el, attr, special[attr], ctx)
                if not sets:
                    continue
                action = sets[0] if len(sets) == 1 else {"sequence": sets}
                if attr == "_onSuccess":
                    node = {"sequence": [node, action]}
                elif attr == "_onFailure":
                    node = {"selector": [node, {"force_failure": action}]}
                else:
                    node = {"selector": [{"sequence": [node, action]}, {"force_failure": action}]}
        if "_while" in special:
            node = {"while_do_else": [self.check(el, "_while", special["_while"], ctx), node, self.skipped(parent)]}
        outcomes = {
            "_skipIf": self.skipped(parent),
            "_successIf": {"name": "success", "check": "true"},
            "_failureIf": {"name": "failure", "check": "false"},
        }
        for attr in ("_skipIf", "_successIf", "_failureIf"):  # the last wrapped is checked first
            if attr in special:
                node = {"if_then_else": [self.check(el, attr, special[attr], ctx), outcomes[attr], node]}
        return node


# ---------------------------------------------------------------- helpers


def _order(pos: Pos) -> tuple[str, int, int]:
    return (pos.file, pos.line, pos.column)


def _default(text: str, port: PortSpec, pos: Pos) -> Any:
    """A declared input default as a plain value (not a mission string: no references)."""
    try:
        return convert_literal(text, port.type)
    except ValueError as exc:
        raise BtXmlError(
            pos, f"the default of port {port.name!r} is declared {port.type or 'untyped'}, but {exc}"
        ) from None


def _convert(text: str, port: PortSpec, pos: Pos) -> Any:
    try:
        value = convert_literal(text, port.type)
    except ValueError as exc:
        raise BtXmlError(pos, f"port {port.name!r} is declared {port.type}, but {exc}") from None
    return value.replace("{", "{{").replace("}", "}}") if isinstance(value, str) else value


def _named(node: dict, name: str) -> dict:
    name = name.replace("/", "|").strip()
    if not name:
        return node
    return {"name": name, **{k: v for k, v in node.items() if k != "name"}}


def _distinct_names(kids: list[dict]) -> list[dict]:
    seen: dict[str, int] = {}
    out = []
    for kid in kids:
        name = kid.get("name")
        if name is not None:
            seen[name] = seen.get(name, 0) + 1
            if seen[name] > 1:
                kid = _named(kid, f"{name} ({seen[name]})")
        out.append(kid)
    return out
