"""``actorbt plot run.jsonl --out timeline.png``: which node and which actor ran when.

One row per tree node that ran, then one row per actor; bars span the runtime-clock
time a node was RUNNING or a call was in flight, coloured by how it ended. Nodes that
finished within one tick are drawn as ticks marks.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .replay import read_trace

__all__ = ["plot_trace"]

_COLOURS = {
    "SUCCESS": "#4caf50",
    "done": "#4caf50",
    "FAILURE": "#e53935",
    "failed": "#e53935",
    "INVALID": "#9e9e9e",
    "cancelled": "#9e9e9e",
    "open": "#ffb300",
}


def _rows(events: list[dict[str, Any]]) -> tuple[list[str], dict[str, list], dict[str, list], float]:
    trees: dict[int, str] = {}
    order: list[str] = []
    bars: dict[str, list] = {}
    marks: dict[str, list] = {}
    since: dict[str, float] = {}
    calls: dict[int, tuple[str, float]] = {}
    end = 0.0

    def row(label: str) -> str:
        if label not in bars:
            order.append(label)
            bars[label], marks[label] = [], []
        return label

    for e in events:
        t = float(e.get("t", 0.0))
        end = max(end, t)
        kind = e.get("type")
        if kind == "run":
            trees[e["run"]] = e["tree"]
        elif kind == "status":
            label = row(f"{trees.get(e['run'], '?')}: {e['path']}")
            if e["new"] == "RUNNING":
                since[label] = t
            elif e["old"] == "RUNNING" and label in since:
                bars[label].append((since.pop(label), t, e["new"]))
            elif e["new"] in ("SUCCESS", "FAILURE"):
                marks[label].append((t, e["new"]))
        elif kind == "call":
            calls[e["call"]] = (row(f"actor {e['actor']}"), t)
        elif kind == "return" and e.get("call") in calls:
            label, start = calls.pop(e["call"])
            bars[label].append((start, t, e.get("state", "done")))
    for label, start in since.items():
        bars[label].append((start, end, "open"))
    for label, start in calls.values():
        bars[label].append((start, end, "open"))
    order = [r for r in order if not r.startswith("actor ")] + [r for r in order if r.startswith("actor ")]
    if len(set(trees.values())) == 1:  # one tree: its name on every row says nothing
        prefix = f"{next(iter(trees.values()))}: "
        order = [r[len(prefix) :] if r.startswith(prefix) else r for r in order]
        bars = {k[len(prefix) :] if k.startswith(prefix) else k: v for k, v in bars.items()}
        marks = {k[len(prefix) :] if k.startswith(prefix) else k: v for k, v in marks.items()}
    return order, bars, marks, end


def plot_trace(trace: str | Path, out: str | Path, *, title: str | None = None) -> Path:
    """Draw the timeline of a trace to ``out`` (format from its suffix: png, svg, pdf).

    Raises:
        ReplayError: the trace cannot be read.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    header, events = read_trace(trace)
    order, bars, marks, end = _rows(events)
    span = max(end, 1e-3)
    height = 1.2 + 0.28 * max(len(order), 1)
    fig, ax = plt.subplots(figsize=(12, height))
    for y, label in enumerate(order):
        for start, stop, how in bars[label]:
            width = max(stop - start, span * 0.002)
            ax.barh(y, width, left=start, height=0.6, color=_COLOURS.get(how, "#90caf9"), edgecolor="none")
        for t, how in marks[label]:
            ax.plot([t], [y], marker="|", markersize=9, color=_COLOURS[how])
    ax.set_yticks(range(len(order)))
    ax.set_yticklabels(order, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(-span * 0.01, span * 1.02)
    ax.set_xlabel("runtime clock [s]")
    ax.grid(axis="x", alpha=0.3)
    ax.set_title(title or f"{header.get('tree')} ({Path(trace).name})")
    ax.legend(
        handles=[
            Patch(color=_COLOURS[k], label=v)
            for k, v in (
                ("SUCCESS", "succeeded"),
                ("FAILURE", "failed"),
                ("INVALID", "halted / cancelled"),
                ("open", "still running"),
            )
        ],
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=7,
    )
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
