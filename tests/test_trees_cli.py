"""The tree commands of ``actorbt``: run, check, show, replay, plot."""

from __future__ import annotations

import logging
import re
import shutil
from pathlib import Path

import pytest

from bt_cli.main import main

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def config(tmp_path: Path) -> str:
    trees = tmp_path / "trees"
    trees.mkdir()
    shutil.copy(REPO / "trees" / "demo_patrol.yaml", trees)
    (trees / "fails.yaml").write_text(
        "name: fails\nroot: {sequence: [{set: {n: 1}}, {name: too small, check: n > 5}]}\n"
    )
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems: {}\ntrees: trees\n")
    return str(cfg)


def test_run_prints_progress_and_outputs(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "run", "demo_patrol", "--arg", "rounds=1", "--arg", "pause=0"]) == 0
    out = capsys.readouterr().out
    assert "demo_patrol: started (rounds=1, pause=0.0)" in out
    assert "demo_patrol: active: patrol/rounds/round/drive to kitchen" in out
    assert "patrol/report/report deadline halted" in out
    lines = out.strip().splitlines()
    assert lines[-2] == "SUCCESS {'last': 'bedroom'}"  # the outputs, once
    assert out.count("bedroom'}") == 1
    assert re.fullmatch(r"sim time 6\.5 s, wall time \d+\.\d s \(\d+\.\dx real time\)", lines[-1])


def test_run_quiet_json(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "run", "demo_patrol", "--quiet", "--json"]) == 0
    assert capsys.readouterr().out.strip() == '{"last": "bedroom"}'


def test_run_a_failing_tree_exits_1(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "run", "fails", "--quiet"]) == 1
    assert "tree fails failed at sequence/too small: n > 5: false" in capsys.readouterr().err


def test_run_errors_are_one_line(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "run", "demo_patrl"]) == 2
    assert "unknown tree 'demo_patrl' (did you mean 'demo_patrol'?)" in capsys.readouterr().err
    assert main(["--config", config, "run", "demo_patrol", "--arg", "round=2"]) == 2
    assert "has no input 'round' (did you mean 'rounds'?)" in capsys.readouterr().err


def test_run_a_file_record_replay_and_plot(config: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    mission = tmp_path / "extra.yaml"
    mission.write_text("name: extra\nroot: {sequence: [{wait: 1}, {do: demo_patrol, with: {rounds: 1}}]}\n")
    trace = tmp_path / "run.jsonl"
    assert main(["--config", config, "run", str(mission), "--quiet", "--record", str(trace)]) == 0
    capsys.readouterr()
    assert main(["--config", config, "replay", str(trace)]) == 0
    assert "replay of extra: OK" in capsys.readouterr().out
    mission.write_text(mission.read_text().replace("wait: 1", "wait: 2"))
    assert main(["--config", config, "replay", str(trace)]) == 1
    out = capsys.readouterr().out
    assert "changed since the recording" in out and "DIVERGED, first divergence at event" in out
    png = tmp_path / "timeline.png"
    assert main(["--config", config, "plot", str(trace), "--out", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_check_files_and_folder(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "check"]) == 0
    assert "2 mission files OK" in capsys.readouterr().out
    bad = [str(REPO / "tests" / "bad_missions" / n) for n in ("07_unknown_node_type.yaml", "20_self_cycle.yaml")]
    assert main(["--config", config, "check", *bad]) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2
    assert lines[0].startswith(f"{bad[0]}:4:3: unknown node type 'sequnce'")
    assert lines[1].startswith(f"{bad[1]}:6:11: subtree cycle self_cycle -> self_cycle")


def test_check_reports_a_broken_tree_in_the_folder(config: str, capsys: pytest.CaptureFixture) -> None:
    folder = Path(config).parent / "trees"
    (folder / "broken.yaml").write_text("name: broken\nroot: {do: demo_patrol, with: {rounds: many}}\n")
    assert main(["--config", config, "check"]) == 1
    err = capsys.readouterr().err
    assert "broken.yaml:2:40: argument 'rounds' of actor 'demo_patrol' expects an int, got str 'many'" in err


def test_show_ascii_and_drawings(config: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    dot = tmp_path / "tree.dot"
    assert main(["--config", config, "show", "demo_patrol", "--out", str(dot)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("demo_patrol(rounds: int = 2, pause: float = 0.5) -> {last}")
    assert "│       ├── drive to kitchen  [do sleep(seconds=1.5)]" in out
    source = dot.read_text()
    assert source.startswith("digraph demo_patrol {")
    assert 'label="drive to kitchen\\ndo sleep(seconds=1.5)"' in source
    if shutil.which("dot"):
        svg = tmp_path / "tree.svg"
        assert main(["--config", config, "show", "demo_patrol", "--out", str(svg)]) == 0
        assert "<svg" in svg.read_text()
    assert main(["--config", config, "show", "demo_patrol", "--out", str(tmp_path / "x.bmp")]) == 2
    assert "unknown format 'bmp'" in capsys.readouterr().err


def test_show_draws_any_text_literally(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    mission = tmp_path / "odd.yaml"
    mission.write_text("name: odd\nroot: {sequence: [{name: 'say \"hi\" \\l <b>', set: {a: '<i>'}}], name: '<seq>'}\n")
    dot = tmp_path / "odd.dot"
    assert main(["show", str(mission), "--out", str(dot)]) == 0
    source = dot.read_text()
    assert 'label="say \\"hi\\" \\\\l <b>\\nset a=<i>"' in source  # quotes and \\ escaped
    assert 'label="→ <seq>\\nsequence"' in source  # <...> is text, not an HTML label
    if shutil.which("dot"):
        svg = tmp_path / "odd.svg"
        assert main(["show", str(mission), "--out", str(svg)]) == 0
        assert "say &quot;hi&quot; \\l &lt;b&gt;" in svg.read_text()
    capsys.readouterr()


def test_show_without_graphviz_says_what_to_do(
    config: str, tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no dot here
    assert main(["--config", config, "show", "demo_patrol", "--out", str(tmp_path / "t.png")]) == 2
    assert "Graphviz 'dot' is not installed, so t.png cannot be drawn" in capsys.readouterr().err


def test_run_ending_like_demo(config: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    trace = tmp_path / "run.jsonl"
    assert main(["--config", config, "run", "demo_patrol", "--arg", "rounds=1", "--json", "--record", str(trace)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-3] == 'SUCCESS {"last": "bedroom"}'
    assert lines[-2].startswith("sim time 7.5 s, wall time ")
    assert lines[-1] == f"trace:     {trace}"
    assert trace.is_file()


def test_run_failure_ending(config: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["--config", config, "run", "fails"]) == 1
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-2] == "FAILURE at sequence/too small: n > 5: false"
    assert lines[-1].startswith("sim time 0.0 s, wall time ")
    assert not any(
        line.endswith("fails: FAILURE: tree fails failed at sequence/too small: n > 5: false") for line in lines
    )  # said once, on the outcome line


def test_nested_runs_still_show_their_outcome(config: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    mission = tmp_path / "outer.yaml"
    mission.write_text("name: outer\nroot: {do: demo_patrol, with: {rounds: 1, pause: 0}}\n")
    assert main(["--config", config, "run", str(mission)]) == 0
    out = capsys.readouterr().out
    assert "  demo_patrol: SUCCESS {'last': 'bedroom'}" in out  # the nested run, indented
    assert out.strip().splitlines()[-2] == "SUCCESS {}"  # outer has no outputs


def _world_config(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A config with a fake simulator, so that starting a world logs its INFO line."""
    (tmp_path / "fake_sim_for_cli.py").write_text("def start(rt, name, seed=0, gui=False):\n    return None\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems: {}\ntrees: null\nworld: {name: flat, seed: 4}\nsimulator: fake_sim_for_cli:start\n")
    return str(cfg)


def test_quiet_by_default_info_with_v(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture, caplog: pytest.LogCaptureFixture
) -> None:
    cfg = _world_config(tmp_path, monkeypatch)
    caplog.set_level(logging.NOTSET)  # the handler takes all; the root level decides
    assert main(["--config", cfg, "call", "sleep", "0.1"]) == 0
    assert logging.getLogger().level == logging.WARNING
    assert "world flat (seed 4) started" not in caplog.text
    out, err = capsys.readouterr()
    assert "INFO" not in out + err
    assert main(["--config", cfg, "-v", "call", "sleep", "0.1"]) == 0
    assert logging.getLogger().level == logging.INFO
    assert "world flat (seed 4) started" in caplog.text
    assert main(["--config", cfg, "-vv", "list"]) == 0
    assert logging.getLogger().level == logging.DEBUG
    logging.getLogger().setLevel(logging.WARNING)
