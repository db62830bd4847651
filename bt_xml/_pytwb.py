"""The pytwb dialect: XML for py_trees-based workbenches (pytwb).

Tags are py_trees class names (``Sequence``, ``Selector``, ``Parallel
policy="SuccessOnOne"``, ``Retry num_failures``...), the name of another tree calls that
tree, and every other tag is a behaviour: here, an actor call. Attribute values are
strings, ``{key}`` blackboard references, or ``[...]`` Python literals, read with
``ast.literal_eval`` only (pytwb itself hands them to ``eval``; we never do).
py_trees' blackboard is global, so a tree call passes every key the called tree reads
and takes back every key it writes (as BehaviorTree.CPP's ``_autoremap``).
"""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Any

from bt_engine.trees import suggest
from ._builtins import Handler
from ._convert import Importer, _Tree
from ._errors import BtXmlError, Pos, UnsupportedXmlError
from ._nodes import PortSpec
from ._source import XElement

__all__ = ["PYTWB_NODES", "PytwbImporter"]


class PytwbImporter(Importer):
    """Converts pytwb XML trees (see the module docstring).

    A workbench is its trees folder: :meth:`load` takes the folder (every ``*.xml`` in
    it, by name) or files. pytwb names a tree after its file (``bt_pick.xml`` is
    ``bt_pick``, whatever its ``<BehaviorTree ID>`` says: the demo's files all say
    ``bt_all``), and that is the name other trees call it by. A file that holds several
    trees keeps their IDs.
    """

    dialect = "pytwb"

    def __init__(self, model: Any = None) -> None:
        super().__init__(model)
        self._trees_in_file = 0

    def load(self, path: str | Path, included_at: Any = None) -> None:
        folder = Path(path)
        if included_at is None and folder.is_dir():
            files = sorted(p for p in folder.iterdir() if p.suffix == ".xml" and p.is_file())
            if not files:
                raise BtXmlError(
                    Pos(str(folder), 1, 1), "the folder holds no .xml file, expected a pytwb workbench's trees folder"
                )
            for file in files:
                super().load(file)
            return
        super().load(path, included_at)

    def check_root(self, top: XElement) -> None:
        if top.tag != "root":
            raise BtXmlError(top.pos, f"the document element is <{top.tag}>, expected <root>")
        self._trees_in_file = sum(1 for child in top.children if child.tag == "BehaviorTree")

    def add_tree(self, element: XElement, file: str) -> None:
        if self._trees_in_file == 1 or "ID" not in element.attrs and "id" not in element.attrs:
            element.attrs.pop("id", None)
            element.attrs["ID"] = Path(file).stem  # pytwb names a tree after its file
        super().add_tree(element, file)

    def identify(self, el: XElement) -> tuple[str, str | None]:
        return el.tag, None

    def dispatch(
        self, el: XElement, node_id: str, long_kind: str | None, ports: dict[str, str], ctx: _Tree, parent: str
    ) -> dict:
        if node_id in self.trees:
            ports.setdefault("_autoremap", "true")
            return self.subtree(el, node_id, ports, ctx)
        handler = PYTWB_NODES.get(node_id)
        if handler is not None:
            return handler(self, el, node_id, ports, ctx, parent)
        if node_id in PYTWB_UNSUPPORTED:
            raise UnsupportedXmlError(el.pos, f"<{node_id}> is not supported: {PYTWB_UNSUPPORTED[node_id]}")
        if el.children:
            raise BtXmlError(
                el.pos,
                f"unknown composite {node_id!r}{suggest(node_id, [*PYTWB_NODES, *self.trees])}: "
                "it has child nodes, expected a py_trees composite or decorator or a tree name",
            )
        return self.leaf(el, node_id, ports, ctx, self.model.get(node_id))

    def literal(self, el: XElement, attr: str, text: str, port: PortSpec | None) -> Any:
        stripped = text.strip()
        if stripped.startswith("[") and stripped.endswith("]"):
            try:
                value = ast.literal_eval(stripped[1:-1])
            except (ValueError, SyntaxError, MemoryError, RecursionError) as exc:
                raise BtXmlError(
                    el.at(attr),
                    f"{attr}={text!r} is not a Python literal ({type(exc).__name__}), "
                    "expected e.g. [True], [3] or ['a', 'b']; expressions are not evaluated",
                ) from None
            return _escape(value)
        return text.replace("{", "{{").replace("}", "}}")

    def guess(self, text: str) -> Any:
        return self.literal(XElement("", {}, self._dummy_pos()), "", text, None)

    def _dummy_pos(self) -> Any:
        from ._errors import Pos

        return Pos("<pytwb>", 1, 1)


def _escape(value: Any) -> Any:
    if isinstance(value, str):
        return value.replace("{", "{{").replace("}", "}}")
    if isinstance(value, (list, tuple)):
        return [_escape(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _escape(v) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, float)):
        return value
    raise ValueError(f"unsupported literal {value!r}")


def _flag(imp: Importer, el: XElement, ports: dict[str, str], attr: str, default: bool) -> bool:
    if attr not in ports:
        return default
    value = imp.literal(el, attr, ports[attr], None)
    if isinstance(value, str):
        value = {"true": True, "false": False}.get(value.strip().lower(), value)
    if not isinstance(value, bool):
        raise BtXmlError(el.at(attr), f"{attr} is {ports[attr]!r}, expected [True] or [False]")
    return value


def _int(imp: Importer, el: XElement, ports: dict[str, str], attr: str, ctx: _Tree) -> Any:
    text = ports[attr]
    key = imp.key(el, attr, text)
    if key is not None:
        return imp.input_value(el, attr, text, ctx)
    value = imp.literal(el, attr, text, None)
    if isinstance(value, str) and value.strip().lstrip("-").isdigit():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise BtXmlError(el.at(attr), f"{attr} is {text!r}, expected a number such as [3]")
    return value


def _memory(kind: str, reactive: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ("memory",))
        chosen = kind if _flag(imp, el, ports, "memory", True) else reactive
        return {chosen: imp.children(el, ctx, chosen)}

    return handler


_POLICIES = {"SuccessOnAll": "success_on_all", "SuccessOnOne": "success_on_one"}


def _parallel(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("policy", "synchronise"))
    policy = ports.get("policy", "SuccessOnAll").strip()
    if policy not in _POLICIES:
        extra = ""
        if policy == "SuccessOnSelected":
            extra = " (SuccessOnSelected needs behaviour objects, which XML cannot name)"
        raise BtXmlError(
            el.at("policy"),
            f"policy {policy!r}{suggest(policy, _POLICIES)}{extra}, expected one of: {', '.join(_POLICIES)}",
        )
    return {"parallel": {"policy": _POLICIES[policy], "children": imp.children(el, ctx, "parallel")}}


def _counted(kind: str, attr: str, forever: bool) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, (attr,))
        child = imp.child(el, ctx, kind)
        times = _int(imp, el, ports, attr, ctx) if attr in ports else (-1 if forever else 3)
        if times == -1:
            return {kind: {"child": child}} if forever else {kind: {"times": "forever", "child": child}}
        if isinstance(times, int) and times < 1:
            raise BtXmlError(el.at(attr), f"{attr} is {times}, expected -1 or >= 1")
        return {kind: {"times": times, "child": child}}

    return handler


def _timeout(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("duration",))
    seconds = _int(imp, el, ports, "duration", ctx) if "duration" in ports else 5.0
    return {"timeout": {"seconds": seconds, "child": imp.child(el, ctx, "timeout")}}


def _simple(kind: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ("policy",) if kind == "run_once" else ())
        return {kind: imp.child(el, ctx, kind)}

    return handler


def _status(node: dict) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ())
        imp.children(el, ctx, "leaf", (0, 0))
        return dict(node)

    return handler


#: py_trees composites, decorators and behaviours that pytwb offers
PYTWB_NODES: dict[str, Handler] = {
    "Sequence": _memory("sequence", "reactive_sequence"),
    "Selector": _memory("selector", "reactive_selector"),
    "Parallel": _parallel,
    "Retry": _counted("retry", "num_failures", forever=False),
    "Repeat": _counted("repeat", "num_success", forever=True),
    "Timeout": _timeout,
    "Inverter": _simple("invert"),
    "FailureIsSuccess": _simple("force_success"),
    "SuccessIsFailure": _simple("force_failure"),
    "OneShot": _simple("run_once"),
    "Success": _status({"check": "true"}),
    "Failure": _status({"check": "false"}),
    "Running": _status({"behaviour": "Running"}),
}

PYTWB_UNSUPPORTED: dict[str, str] = {
    name: "it takes a Python callable or status mapping that XML cannot express; write it as an actor"
    for name in (
        "Condition",
        "EternalGuard",
        "StatusToBlackboard",
        "Count",
        "FailureIsRunning",
        "RunningIsFailure",
        "RunningIsSuccess",
        "SuccessIsRunning",
        "PassThrough",
    )
}
