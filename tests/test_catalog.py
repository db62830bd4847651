"""The catalog and its JSON-Schema export."""
from __future__ import annotations

from typing import Optional

from bt_engine import SubSystem, actor
from bt_engine.catalog import catalog, tool_schemas


class Nav(SubSystem):
    @actor
    def goto(self, x: float, y: float, theta: float = 0.0, frame: str = "map") -> bool:
        """Drive to (x, y, theta) in the map frame.

        Longer explanation that the summary leaves out."""
        return True

    @actor("watch", "multi")
    def watch(self, emit, labels: list[str], limit: Optional[int] = None):
        """Stream detections."""
        return lambda: None


def test_catalog_lists_path_doc_signature_kind(rt):
    rt.add_subsystem("nav", Nav)
    entries = {e["path"]: e for e in catalog(rt.root)}
    assert entries["nav.goto"]["kind"] == "sync"
    assert entries["nav.watch"]["kind"] == "multi"
    assert entries["nav.goto"]["signature"].startswith("nav.goto(x: float, y: float")
    assert entries["nav.goto"]["doc"].startswith("Drive to")
    assert "sleep" in entries


def test_json_schema_tools(rt):
    rt.add_subsystem("nav", Nav)
    tools = {t["name"]: t for t in tool_schemas(rt.root)}
    goto = tools["nav.goto"]
    assert goto["description"] == "Drive to (x, y, theta) in the map frame."
    assert goto["parameters"] == {
        "type": "object",
        "properties": {"x": {"type": "number"}, "y": {"type": "number"},
                       "theta": {"type": "number", "default": 0.0},
                       "frame": {"type": "string", "default": "map"}},
        "required": ["x", "y"]}
    watch = tools["nav.watch"]["parameters"]
    assert watch["properties"]["labels"] == {"type": "array", "items": {"type": "string"}}
    assert watch["properties"]["limit"]["anyOf"] == [{"type": "integer"}, {"type": "null"}]
    assert watch["required"] == ["labels"]
