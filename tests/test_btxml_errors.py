"""Errors of `actorbt xml import`: one located line, what was expected, close matches."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_xml import BtXmlError, UnknownXmlNodeError, UnsupportedXmlError, XmlSyntaxError, import_files, read_node_model
from bt_cli.main import main

DATA = Path(__file__).parent / "data" / "btxml"


def imported(tmp_path: Path, body: str, *, nodes: bool = False, dialect: str = "btcpp", root: str | None = None):
    path = tmp_path / "t.xml"
    path.write_text(
        root
        if root is not None
        else f'<root BTCPP_format="4">\n  <BehaviorTree ID="T">\n{body}\n  </BehaviorTree>\n</root>\n'
    )
    model = read_node_model([DATA / "nav2_nodes.xml"]) if nodes else None
    return import_files([path], model, dialect=dialect)


def test_malformed_xml_is_a_located_error() -> None:
    with pytest.raises(XmlSyntaxError) as info:
        import_files([DATA / "malformed.xml"])
    assert str(info.value).endswith(
        "malformed.xml:6:7: not well-formed XML: mismatched tag, expected the closing tag of the element opened before"
    )


@pytest.mark.parametrize(
    "body, error, where, message",
    [
        (
            '    <ComputePathToPos goal="{goal}"/>',
            UnknownXmlNodeError,
            "3:5",
            "unknown node 'ComputePathToPos' (did you mean 'ComputePathToPose'?)",
        ),
        (
            "    <Sequense><AlwaysSuccess/></Sequense>",
            UnknownXmlNodeError,
            "3:5",
            "unknown control node 'Sequense' (did you mean 'Sequence'?)",
        ),
        ('    <FollowPath pth="{path}"/>', BtXmlError, "3:22", "has no port 'pth' (did you mean 'path'?)"),
        ('    <Script code="n := n + 1"/>', UnsupportedXmlError, "3:26", "cannot assign arithmetic ('+')"),
        ('    <Script code="n += 1"/>', UnsupportedXmlError, "3:21", "compound assignment"),
        ('    <Spin _onHalted="x := 1"/>', UnsupportedXmlError, "3:22", "_onHalted is not supported"),
        ('    <Spin _skipif="x"/>', BtXmlError, "3:20", "unknown attribute '_skipif' (did you mean '_skipIf'?)"),
        ('    <UnsetBlackboard key="x"/>', UnsupportedXmlError, "3:5", "never remove a blackboard key"),
        (
            '    <RoundRobin foo="1"><Spin/><Spin/></RoundRobin>',
            BtXmlError,
            "3:22",
            "node 'RoundRobin' has no port 'foo'",
        ),
        ('    <Timeout msec="{t}"><Spin/></Timeout>', UnsupportedXmlError, "3:20", "the unit differs"),
        ("    <Inverter><Spin/><Spin/></Inverter>", BtXmlError, "3:5", "has 2 child nodes, expected 1"),
        ('    <SubTree ID="Nope"/>', UnknownXmlNodeError, "3:18", "unknown tree 'Nope'"),
        ('    <Spin spin_dist="{@dist}"/>', UnsupportedXmlError, "3:22", "root blackboard"),
        ('    <Precondition if="a ? 1 : 2"><Spin/></Precondition>', UnsupportedXmlError, "3:25", "ternary"),
        ('    <Spin spin_dist="fast"/>', BtXmlError, "3:22", "declared double, but 'fast' is not a number"),
    ],
)
def test_import_errors_are_located(tmp_path: Path, body: str, error: type, where: str, message: str) -> None:
    with pytest.raises(error) as info:
        imported(tmp_path, body, nodes=True)
    assert f"t.xml:{where}: " in str(info.value) and message in str(info.value), str(info.value)


def test_subtree_errors(tmp_path: Path) -> None:
    root = (
        '<root BTCPP_format="4">\n'
        '  <BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>\n'
        '  <BehaviorTree ID="B"><Sequence><ScriptCondition code="x > 1"/><SubTree ID="A" x="{x}"/></Sequence>'
        "</BehaviorTree>\n</root>\n"
    )
    with pytest.raises(
        BtXmlError,
        match="t.xml:2:24: SubTree 'B' reads 'x', which nothing in it writes, but this call does not pass it",
    ):
        imported(tmp_path, "", root=root.replace('<SubTree ID="A" x="{x}"/>', ""))
    with pytest.raises(BtXmlError, match="subtree cycle"):
        imported(tmp_path, "", root=root.replace('<SubTree ID="B"/>', '<SubTree ID="B" x="1"/>'))


def test_document_level_errors(tmp_path: Path) -> None:
    with pytest.raises(UnsupportedXmlError, match="t.xml:1:21: BTCPP_format is '3'"):
        imported(tmp_path, "", root='<root BTCPP_format="3"><BehaviorTree ID="T"><Spin/></BehaviorTree></root>')
    with pytest.raises(XmlSyntaxError, match="DOCTYPE"):
        imported(tmp_path, "", root='<!DOCTYPE root [<!ENTITY a "b">]><root/>')
    with pytest.raises(BtXmlError, match="defined twice"):
        imported(
            tmp_path,
            "",
            root='<root><BehaviorTree ID="T"><Spin/></BehaviorTree><BehaviorTree ID="T"><Spin/></BehaviorTree></root>',
        )


def test_pytwb_arguments_are_literals_only(tmp_path: Path) -> None:
    root = '<root><BehaviorTree ID="T"><Go name="g" x="[__import__(\'os\').getcwd()]"/></BehaviorTree></root>'
    with pytest.raises(BtXmlError, match="is not a Python literal .* expressions are not evaluated"):
        imported(tmp_path, "", root=root, dialect="pytwb")


def test_cli_import_and_check_with_a_node_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    nodes = str(DATA / "nav2_nodes.xml")
    assert main(["xml", "import", str(DATA / "nav2_navigate.xml"), "--nodes", nodes, "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["NavigateWithReplanning.yaml", "RecoveryActions.yaml"]
    assert main(["check", "--nodes", nodes, *map(str, sorted(out.iterdir()))]) == 0
    assert "2 mission files OK" in capsys.readouterr().out
    assert main(["xml", "import", str(DATA / "malformed.xml"), "--out", str(out)]) == 2
    assert "malformed.xml:6:7: not well-formed XML" in capsys.readouterr().err
