"""``actorbt xml btlog``: traces as Groot2 logs (BehaviorTree.CPP 4's FileLogger2 format),
read back with a small reader written here from the format, not from our writer."""

from __future__ import annotations

import json
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from bt_cli.main import main

REPO = Path(__file__).resolve().parents[1]
TRACES = sorted((REPO / "tests" / "replays").glob("*.jsonl"))


def read_btlog(data: bytes) -> tuple[ET.Element, int, list[tuple[int, int, int]]]:
    """Header, XML, first timestamp and 9-byte records of a FileLogger2 file."""
    magic = b"BTCPP4-FileLogger2"
    assert data[: len(magic)] == magic
    i = len(magic)
    assert data[i] == 1  # protocol
    i += 1
    (size,) = struct.unpack_from("<i", data, i)
    i += 4
    xml = ET.fromstring(data[i : i + size].decode("utf-8"))
    i += size
    (first,) = struct.unpack_from("<q", data, i)
    i += 8
    body = data[i:]
    assert len(body) % 9 == 0
    records = [
        (int.from_bytes(body[j : j + 6], "little"), *struct.unpack_from("<HB", body, j + 6))
        for j in range(0, len(body), 9)
    ]
    return xml, first, records


def status_events(trace: Path) -> list[dict]:
    events = [json.loads(line) for line in trace.read_text().splitlines() if line.strip()]
    return [e for e in events if e.get("type") == "status"]


@pytest.mark.parametrize("trace", TRACES, ids=lambda p: p.stem)
def test_a_trace_becomes_a_groot2_log(trace: Path, tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(REPO)  # the traces name their tree files relative to the repository
    out = tmp_path / f"{trace.stem}.btlog"
    assert main(["xml", "btlog", str(trace), "--out", str(out)]) == 0
    assert "transitions" in capsys.readouterr().out
    xml, first, records = read_btlog(out.read_bytes())
    assert xml.tag == "root" and xml.get("BTCPP_format") == "4"
    assert xml.find("TreeNodesModel") is not None
    uids = [int(e.get("_uid")) for e in xml.iter() if e.get("_uid") is not None]
    nodes = [e for t in xml.findall("BehaviorTree") for e in t.iter() if e.tag != "BehaviorTree"]
    assert len(uids) == len(nodes) and len(set(uids)) == len(uids)  # every node numbered, once
    assert all(0 < u < 65536 for u in uids)
    assert first > 1_600_000_000 * 10**6  # microseconds since the epoch, from the header
    events = status_events(trace)
    assert len(records) == len(events)
    assert all(uid in set(uids) for _, uid, _ in records)
    assert all(status in (0, 1, 2, 3, 4) for _, _, status in records)
    times = [t for t, _, _ in records]
    assert times == sorted(times)
    codes = {"INVALID": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3}
    assert [s for _, _, s in records] == [codes[e["new"]] for e in events]
    by_uid = {int(e.get("_uid")): e for e in xml.iter() if e.get("_uid") is not None}
    first_event = events[0]
    assert by_uid[records[0][1]].get("name") == first_event["path"].rsplit("/", 1)[-1]


def test_subtree_instances_follow_their_calls(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(REPO)
    out = tmp_path / "pp.btlog"
    assert main(["xml", "btlog", "tests/replays/bt_pick_place_house_seed0.jsonl", "--out", str(out)]) == 0
    xml, _, records = read_btlog(out.read_bytes())
    trees = xml.findall("BehaviorTree")
    assert [(t.get("ID"), t.get("_fullpath")) for t in trees] == [
        ("bt_pick_place", ""),
        ("bt_search", "search"),
        ("bt_catch", "catch"),
        ("bt_carry", "carry"),
        ("reset", "return home"),
    ]
    call = xml.find(".//SubTree[@ID='bt_search']")
    assert call.get("_fullpath") == "search"
    search = trees[1]
    watch = search.find(".//watch")
    # the run of bt_search reports its nodes with the uids of its instance
    assert int(watch.get("_uid")) in {uid for _, uid, _ in records}
    assert int(watch.get("_uid")) == int(call.get("_uid")) + 3  # numbered right after the SubTree node


@pytest.mark.parametrize(
    "content, message",
    [
        (b"\x00\xffBTCPP4-FileLogger2", "not a trace"),
        (b'{"type": "header", "format": "other"}\n', "not an actorbt trace"),
        (b"not json\n", "not JSON"),
    ],
)
def test_bad_input_is_one_line(tmp_path: Path, capsys, content: bytes, message: str) -> None:
    trace = tmp_path / "t.jsonl"
    trace.write_bytes(content)
    assert main(["xml", "btlog", str(trace), "--out", str(tmp_path / "x.btlog")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


def test_a_trace_of_a_changed_tree_says_which_node(tmp_path: Path, capsys) -> None:
    (tmp_path / "trees").mkdir()
    text = (REPO / "trees" / "demo_patrol.yaml").read_text().replace("name: arrived", "name: got there")
    (tmp_path / "trees" / "demo_patrol.yaml").write_text(text)
    trace = REPO / "tests" / "replays" / "demo_patrol.jsonl"
    assert (
        main(["xml", "btlog", str(trace), "--trees", str(tmp_path / "trees"), "--out", str(tmp_path / "x.btlog")]) == 2
    )
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "has no node 'patrol/arrived'" in err, err
    assert main(["xml", "btlog", str(tmp_path / "missing.jsonl"), "--out", str(tmp_path / "x.btlog")]) == 2
    assert "cannot read trace" in capsys.readouterr().err
