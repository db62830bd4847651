"""YAML read with its marks: the node graph (``yaml.compose``) rather than plain values, so
every error names file:line:column. World descriptions, map YAML and locations files are
read this way."""

from __future__ import annotations

import math

import yaml

from bt_engine.yaml_hints import syntax_mark, syntax_message

from .world_spec import WorldError


class MarkedYaml:
    """Typed reads of the nodes of one file; each failure is a WorldError at the node."""

    def __init__(self, path: str):
        self.path = path

    def err(self, node, msg):
        where = f"{node.start_mark.line + 1}:{node.start_mark.column + 1}" if node is not None else "1:1"
        return WorldError(f"{self.path}:{where}: {msg}")

    def mapping(self, node, what):
        if not isinstance(node, yaml.MappingNode):
            raise self.err(node, f"{what} must be a mapping")
        out = {}
        for k, v in node.value:
            if not isinstance(k, yaml.ScalarNode):
                raise self.err(k, f"{what}: keys must be plain names")
            if k.value in out:
                raise self.err(k, f"{what}: duplicate key '{k.value}'")
            out[k.value] = (k, v)
        return out

    def keys(self, m, allowed, what):
        for key, (knode, _) in m.items():
            if key not in allowed:
                raise self.err(knode, f"{what}: unknown key '{key}' (allowed: {', '.join(sorted(allowed))})")

    def seq(self, node, what):
        if not isinstance(node, yaml.SequenceNode):
            raise self.err(node, f"{what} must be a list")
        return node.value

    def num(self, node, what, positive=False, nonneg=False):
        if not isinstance(node, yaml.ScalarNode):
            raise self.err(node, f"{what} must be a number")
        try:
            v = float(node.value)
        except ValueError:
            raise self.err(node, f"{what} must be a number, got '{node.value}'") from None
        if not math.isfinite(v):
            raise self.err(node, f"{what} must be finite")
        if positive and v <= 0:
            raise self.err(node, f"{what} must be > 0, got {v}")
        if nonneg and v < 0:
            raise self.err(node, f"{what} must be >= 0, got {v}")
        return v

    def int_(self, node, what, minimum=0):
        v = self.num(node, what)
        if v != int(v) or v < minimum:
            raise self.err(node, f"{what} must be an integer >= {minimum}, got {node.value}")
        return int(v)

    def vec(self, node, n, what, **kw):
        items = self.seq(node, what)
        if len(items) != n:
            raise self.err(node, f"{what} must have {n} numbers, got {len(items)}")
        return tuple(self.num(i, what, **kw) for i in items)

    def str_(self, node, what):
        if not isinstance(node, yaml.ScalarNode) or not node.value:
            raise self.err(node, f"{what} must be a non-empty string")
        return node.value


def compose_yaml(text: str, path: str, empty: str):
    """(root node, context) of a YAML text whose values keep their file:line:column; a
    syntax error or an empty file (``empty`` says what was expected) is a WorldError."""
    try:
        root = yaml.compose(text)
    except yaml.MarkedYAMLError as e:
        mark = syntax_mark(e)
        where = f"{mark.line + 1}:{mark.column + 1}" if mark else "1"
        raise WorldError(f"{path}:{where}: {syntax_message(e)}") from None
    if root is None:
        raise WorldError(f"{path}:1: {empty}")
    return root, MarkedYaml(path)
