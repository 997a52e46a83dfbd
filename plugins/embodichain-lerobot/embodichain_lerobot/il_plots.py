"""The imitation pipeline's plots: the success curve (validation rates per checkpoint) and the
visual-randomization table (:func:`plot_rate_table`), every rate with its 95% interval.

Drawn with matplotlib (a dependency of this plugin) on its file backend (``Agg``), so it
needs no display.

Example:
    >>> val = [{"step": 1000, "success_rate": 0.3, "ci95": [0.2, 0.4]}]  # doctest: +SKIP
    >>> plot_success_curve(val, None, Path("curve.png"), "PickFork-v1")  # doctest: +SKIP
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

__all__ = ["plot_success_curve", "plot_rate_table"]


def _errors(rows: Sequence[Mapping[str, Any]]) -> list[list[float]]:
    """matplotlib's asymmetric error bars (below, above) from each row's ``ci95``."""
    below = [r["success_rate"] - r["ci95"][0] for r in rows]
    above = [r["ci95"][1] - r["success_rate"] for r in rows]
    return [below, above]


def _save(fig: Any, path: Path) -> Path:
    """Write ``fig`` to ``path`` with the interval-bar footnote, and close it."""
    import matplotlib.pyplot as plt

    fig.text(0.99, 0.01, "bars: 95% Wilson interval", ha="right", va="bottom", fontsize=7, color="0.4")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_success_curve(
    validation: Sequence[Mapping[str, Any]],
    test: Optional[Mapping[str, Any]],
    path: Path,
    title: str,
    label: str = "validation",
) -> Path:
    """Success rate over training steps, each point with its 95% Wilson interval.

    Args:
        validation: one row per checkpoint: ``step``, ``success_rate``, ``ci95``,
            ``episodes`` (the validation episodes).
        test: the chosen checkpoint's test row (same keys), drawn as a separate marker;
            ``None`` when the test episodes were not run.
        path: the PNG to write.
        title: the plot's title.
        label: what the per-checkpoint episodes were (the legend's word for them).

    Returns:
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    if validation:
        steps = [r["step"] for r in validation]
        n = validation[0]["episodes"]
        ax.errorbar(
            steps,
            [r["success_rate"] for r in validation],
            yerr=_errors(validation),
            fmt="o-",
            capsize=4,
            label=f"{label} ({n} episodes per checkpoint)",
        )
    if test is not None:
        ax.errorbar(
            [test["step"]],
            [test["success_rate"]],
            yerr=_errors([test]),
            fmt="s",
            color="tab:red",
            capsize=6,
            markersize=8,
            label=f"test, chosen checkpoint ({test['episodes']} episodes)",
        )
    ax.set(xlabel="training step", ylabel="success rate", ylim=(-0.02, 1.02), title=title)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    return _save(fig, path)


def plot_rate_table(cells: Mapping[str, Mapping[str, Any]], path: Path, title: str) -> Path:
    """Grouped bars of a table of rates: one group per scene, one bar per trained policy.

    Args:
        cells: ``"<policy>/<scene>"`` -> a rate summary (``success_rate``, ``ci95``,
            ``episodes``), as ``table.json``'s ``cells``.
        path: the PNG to write.
        title: the plot's title.

    Returns:
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    policies = list(dict.fromkeys(key.split("/")[0] for key in cells))
    scenes = list(dict.fromkeys(key.split("/")[1] for key in cells))
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    width = 0.8 / len(policies)
    for k, policy in enumerate(policies):
        rows = [cells[f"{policy}/{scene}"] for scene in scenes]
        xs = [i + (k - (len(policies) - 1) / 2) * width for i in range(len(scenes))]
        bars = ax.bar(xs, [r["success_rate"] for r in rows], width, yerr=_errors(rows), capsize=5, label=policy)
        ax.bar_label(bars, labels=[f"{r['success_rate']:.2f}" for r in rows], label_type="center", fontsize=8)
    ax.set_xticks(range(len(scenes)), [f"{scene} scene" for scene in scenes])
    episodes = next(iter(cells.values()))["episodes"]
    ax.set(ylabel=f"success rate ({episodes} test episodes)", ylim=(0, 1.05), title=title)
    ax.legend(title="trained on data", loc="upper left", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    return _save(fig, path)
