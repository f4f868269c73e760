"""Figure-2-style plot: loss and max in/out-degree per baseline, mean ± std over seeds (paper section 4)."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence


def figure2(rows: Sequence[tuple[str, Mapping[str, Mapping[str, float]]]], title: str, path: Path) -> Path:
    """rows: (baseline label, summary) -> PNG with loss bars (left axis) and max in/out-degree bars (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    labels = [r[0] for r in rows]
    x = np.arange(len(rows))
    get = lambda m, k: [r[1][m][k] for r in rows]
    fig, ax = plt.subplots(figsize=(max(5.0, 1.3 * len(rows) + 2), 3.6), dpi=120)
    w = 0.27
    ax.bar(x - w, get("cost", "mean"), w, yerr=get("cost", "std"), color="#f2c14e", capsize=3, label="loss")
    ax.set_ylabel("loss (time-averaged, summed over agents)")
    ax2 = ax.twinx()
    # tf-full talks to everybody: like the paper, its degrees are not drawn
    deg = [0.0 if lbl == "tf-full" else v for lbl, v in zip(labels, get("max_in", "mean"))]
    dego = [0.0 if lbl == "tf-full" else v for lbl, v in zip(labels, get("max_out", "mean"))]
    ax2.bar(x, deg, w, yerr=[0 if l == "tf-full" else s for l, s in zip(labels, get("max_in", "std"))],
            color="#4e79a7", capsize=3, label="max in-degree")
    ax2.bar(x + w, dego, w, yerr=[0 if l == "tf-full" else s for l, s in zip(labels, get("max_out", "std"))],
            color="#e15759", capsize=3, label="max out-degree")
    ax2.set_ylabel("degree")
    ax.set_xticks(x, labels, rotation=20, ha="right")
    ax.set_title(title, fontsize=9)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    fig.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower center", ncol=3, frameon=False)
    fig.tight_layout(rect=(0, 0.07, 1, 1))  # room for the legend below the bars
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(path)
    return path
