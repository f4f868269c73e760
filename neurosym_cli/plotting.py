"""Figures: the paper's Figure 2 (loss and max in/out-degree per baseline, mean ± std; section 4) and training
curves. One colour per baseline in every figure (``color``)."""

from __future__ import annotations

import math

from pathlib import Path
from typing import Mapping, Sequence

from .tasks.base import COST_WORDS
from .viz.draw import save_figure


def baseline_of(label: str) -> str:
    """The baseline an evaluation label belongs to (``prog-retrained-k2-lam0.5-v1`` -> ``prog-retrained``, the picks
    ``rl1``, ``rl2`` -> ``rl``)."""
    from .schemes import SCHEMES

    names = [b for b in SCHEMES if label == b or label.startswith(b + "-")
             or (label.startswith(b) and label[len(b):].isdigit())]
    return max(names, key=len) if names else label


def short_labels(labels: Sequence[str]) -> list[str]:
    """A name per label that tells it from the others: its baseline alone when no other label has that baseline,
    else the baseline and the parts of its label the others lack (``prog-k2-lam0.5-v1``, ``prog-k3-lam0.5-v1`` ->
    ``prog-k2``, ``prog-k3``)."""
    base = [baseline_of(lbl) for lbl in labels]
    out = []
    for lbl, b in zip(labels, base):
        peers = [p for p, pb in zip(labels, base) if pb == b]
        if len(peers) == 1 or not lbl.startswith(b + "-"):  # alone, or a name of its own (rl1, rl2)
            out.append(b if len(peers) == 1 else lbl)
            continue
        mine = lbl[len(b):].strip("-").split("-")
        shared = set.intersection(*(set(p[len(b):].strip("-").split("-")) for p in peers))
        out.append("-".join([b, *[x for x in mine if x and x not in shared]]) or lbl)
    return out if len(set(out)) == len(out) else list(labels)

def place_labels(ax, xs, ys, names: Sequence[str], colors: Sequence[str], fontsize: float = 7,
                 avoid: Sequence[tuple[float, float]] = ()) -> None:
    """Label each point (xs[k], ys[k]) right of it; labels that would overprint another label or marker (the
    points, and ``avoid``: other markers drawn, as (x, y)) are moved up, with a leader line to their point. Call
    after the axes limits are final."""
    import numpy as np

    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    gap, placed = 0.045 * (y1 - y0), []  # placed: (x, label y, label width) of the labels so far

    def clash(k: int, w: float, ly: float) -> float | None:
        """The y of a label or another marker that point k's label [x, x + w] at height ly would overprint."""
        x = xs[k]
        boxes = placed + [(px, py, 0.0) for i, (px, py) in enumerate(zip(xs, ys)) if i != k] + \
            [(px, py, 0.0) for px, py in avoid]
        hits = [py for px, py, pw in boxes if px - 0.02 * (x1 - x0) <= x + w and x <= px + pw + 0.02 * (x1 - x0)
                and abs(ly - py) < gap]
        return max(hits) if hits else None

    for k in np.argsort(ys):
        w = (0.03 + 0.0019 * fontsize * len(names[k])) * (x1 - x0)  # characters of this size on a ~5 inch panel
        ly = ys[k]
        for _ in range(len(names)):
            hit = clash(k, w, ly)
            if hit is None:
                break
            ly = max(ly, hit) + gap
        placed.append((xs[k], ly, w))
        ax.annotate(names[k], (xs[k], ys[k]), xytext=(xs[k] + 0.03 * (x1 - x0), ly), fontsize=fontsize,
                    color=colors[k], va="center",
                    arrowprops={"arrowstyle": "-", "color": colors[k], "lw": 0.5} if ly != ys[k] else None)


def figure2(rows: Sequence[tuple[str, Mapping[str, Mapping[str, float]]]], title: str, path: Path,
            err: str = "std", cost_words: str = COST_WORDS) -> Path:
    """The paper's Figure 2, one panel more: rows (baseline label, summary with the mean and ``err``, the error bar
    the title names, of cost, max_in, max_out) -> PNG with (a) loss per baseline, (b) max in- and out-degree per
    baseline, tf-full's drawn as what it is
    (every other agent) and marked so, (c) loss against max in-degree, the trade-off the method is about.
    ``cost_words``: how the task's loss combines its agents (tasks.base.cost_words); "" when it is not known."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    labels = [r[0] for r in rows]
    colors = [color(baseline_of(lbl)) for lbl in labels]
    y = np.arange(len(rows))[::-1]  # the paper's order from the top
    get = lambda m, k: np.array([r[1][m][k] for r in rows], dtype=float)
    from .schemes import SCHEMES

    hears_all = [getattr(SCHEMES.get(baseline_of(lbl)), "soft_attention", False) for lbl in labels]
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(13.5, 0.34 * len(rows) + 2.6), dpi=120,
                                  gridspec_kw={"width_ratios": [1, 1, 1.25]})
    a.barh(y, get("cost", "mean"), xerr=get("cost", err), color=colors, capsize=2)
    a.set_yticks(y, labels, fontsize=8)
    a.set_xlabel(f"loss (time-averaged{', ' + cost_words if cost_words else ''}; lower is better)", fontsize=8)
    a.set_title("(a) loss", fontsize=9)
    h = 0.38
    b.barh(y + h / 2, get("max_in", "mean"), h, xerr=get("max_in", err), color=colors, capsize=2,
           label="max in-degree (solid)")
    b.barh(y - h / 2, get("max_out", "mean"), h, xerr=get("max_out", err), color=colors, capsize=2, alpha=0.55,
           hatch="///", label="max out-degree (hatched)")
    for yy, v, alltalk in zip(y, np.maximum(get("max_in", "mean"), get("max_out", "mean")), hears_all):
        if alltalk:
            b.annotate(" all: hears every other agent", (v, yy), va="center", fontsize=7)
        elif v == 0:
            b.annotate(" none", (0, yy), va="center", fontsize=7)
    b.set_yticks(y, [])
    b.set_xlim(0, 1.6 * max(float(get("max_in", "mean").max()), float(get("max_out", "mean").max()), 1.0))
    b.set_xlabel("agents, max over agents and steps (mean over episodes)", fontsize=8)
    b.set_title("(b) max in- and out-degree", fontsize=9)
    b.legend(fontsize=7, frameon=False, loc="lower right")
    xs, ls = get("max_in", "mean"), get("cost", "mean")
    for col, x, xe, l, le in zip(colors, xs, get("max_in", err), ls, get("cost", err)):
        c.errorbar(x, l, xerr=xe, yerr=le, fmt="o", color=col, ms=6, capsize=2)
    c.margins(x=0.25, y=0.12)
    x0, x1 = c.get_xlim()
    c.set_xlim(max(x0, -0.06 * x1), x1)  # a degree is never negative: no axis left of zero beyond the markers
    place_labels(c, xs, ls, short_labels(labels), colors)
    c.set_xlabel("max in-degree (whom an agent hears)", fontsize=8)
    c.set_ylabel("loss", fontsize=8)
    c.set_title("(c) loss against max in-degree: lower left is better", fontsize=9)
    c.grid(alpha=0.3, lw=0.5)
    for ax in (a, b, c):
        ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


_PALETTE = ("#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7", "#9c755f",
            "#7f7f7f", "#17becf", "#393b79", "#bcbd22", "#8c564b")


def color(baseline: str) -> str:
    """One colour per baseline, the same in every figure (by its place in the paper's order)."""
    from .schemes import rank

    return _PALETTE[rank(baseline) % len(_PALETTE)]


def _smooth(y, window: int):
    """Trailing moving average over ``window`` steps (the first points average what exists)."""
    import numpy as np

    c = np.cumsum(np.insert(np.asarray(y, dtype=float), 0, 0.0))
    n = np.arange(1, len(y) + 1)
    lo = np.maximum(n - window, 0)
    return (c[n] - c[lo]) / (n - lo)


def training_curves(runs: Sequence[tuple[str, str, bool, Sequence[Sequence[tuple[float, float]]]]], title: str,
                    path: Path, window: int = 5) -> Path:
    """Training loss against rollouts, one line per model.

    runs: (label, baseline name, retrained?, one [(rollouts, loss)] history per training seed). Models trained from
    scratch and models retrained from the oracle get a panel each; a line is the mean over seeds of the moving
    average over ``window`` optimizer steps, the band the spread (min to max) across seeds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np

    panels = [("trained from scratch (paper 3.1)", [r for r in runs if not r[2]]),
              ("retrained from the oracle under a program or tree (3.5)", [r for r in runs if r[2]])]
    panels = [p for p in panels if p[1]]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 3.9), dpi=120, squeeze=False)
    for ax, (name, group) in zip(axes[0], panels):
        for label, baseline, _, histories in group:
            n = min(len(h) for h in histories)
            x = np.asarray([p[0] for p in histories[0][:n]])
            ys = np.stack([_smooth([p[1] for p in h[:n]], window) for h in histories])
            ax.plot(x, ys.mean(0), color=color(baseline), lw=1.6,
                    label=label + (f" ({len(histories)} seeds)" if len(histories) > 1 else ""))
            if len(histories) > 1:
                ax.fill_between(x, ys.min(0), ys.max(0), color=color(baseline), alpha=0.2, lw=0)
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.tick_params(axis="y", which="minor", labelsize=7)
        ax.set_xlabel("training rollouts" if "scratch" in name else "retraining rollouts")
        ax.set_ylabel(f"training loss (moving average of {window} steps)")
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3, which="both", lw=0.5)
        ax.legend(fontsize=7, frameon=False)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def pareto_plot(points: Sequence[tuple[str, float, float]], front: Sequence[int], ref: tuple[float, float],
                area: float, title: str, path: Path) -> Path:
    """Loss against max degree of every evaluated baseline or program (label, degree, loss), the non-dominated
    ones joined as a staircase and ringed, and the area they dominate up to the reference point shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.2, 5.0), dpi=120)
    f = sorted((points[i][1], points[i][2]) for i in front)
    stairs_x, stairs_y = [f[0][0]], [ref[1]]
    for k, (x, y) in enumerate(f):
        stairs_x += [x, x]
        stairs_y += [stairs_y[-1], y]
        if k + 1 < len(f):
            stairs_x.append(f[k + 1][0])
            stairs_y.append(y)
    stairs_x.append(ref[0])
    stairs_y.append(f[-1][1])
    ax.fill_between(stairs_x, stairs_y, ref[1], step=None, color="#59a14f", alpha=0.12, lw=0,
                    label=f"dominated area {area:.4g} (up to the reference point)")
    ax.plot(stairs_x, stairs_y, color="#59a14f", lw=1.2)
    cols = [color(baseline_of(label)) for label, _, _ in points]
    for k, (label, x, y) in enumerate(points):
        ax.scatter(x, y, s=30, color=cols[k], zorder=3)
        if k in front:
            ax.scatter(x, y, s=110, facecolors="none", edgecolors="black", lw=1.0, zorder=4)
    ax.scatter(*ref, marker="+", s=80, color="black", label=f"reference point ({ref[0]:.3g}, {ref[1]:.4g})")
    ax.scatter([], [], s=110, facecolors="none", edgecolors="black", label="non-dominated (ringed)")
    ax.set_xlabel("max in+out (the paper's deg: max over agents of in + out; mean over episodes and seeds)",
                  fontsize=8)
    ax.set_ylabel("loss (lower is better)", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, lw=0.5)
    ax.margins(x=0.12, y=0.08)
    place_labels(ax, [p[1] for p in points], [p[2] for p in points], [p[0] for p in points], cols, 6.5)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, frameon=False)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


def stress_plot(results: Sequence[Mapping], cfg, path: Path, cost_words: str = COST_WORDS) -> Path:
    """`neurosym stress`: loss, max in-degree and max out-degree (mean ± 95 % interval over the test seeds) of every
    baseline against the team size (top row, no link failure) and against the link failure rate (bottom row, the
    task's team size); the trained team size is marked. ``cost_words``: as figure2's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .viz.draw import save_figure

    axes_of = [("agents", "max_agents", "agents in the largest episode, N (log scale)"),
               ("failure", "link_failure", "link failure rate (each directed link, every step)")]
    rows = [a for a in axes_of if any(r["axis"] == a[0] for r in results)]
    metrics = [("cost", f"loss ({cost_words}; lower is better)"), ("max_in", "max in-degree"),
               ("max_out", "max out-degree")]
    fig, axes = plt.subplots(len(rows), 3, figsize=(14, 3.9 * len(rows)), dpi=110, squeeze=False)
    trained_n = [r["max_agents"] for r in results if r["axis"] == "failure"]
    for row, (axis, key, xlabel) in zip(axes, rows):
        pts = [r for r in results if r["axis"] == axis]
        for ax, (m, ylabel) in zip(row, metrics):
            for label in dict.fromkeys(r["label"] for r in pts):
                mine = sorted((r for r in pts if r["label"] == label), key=lambda r: r[key])
                x = [r[key] for r in mine]
                y = [r[m]["mean"] for r in mine]
                e = [r[m]["ci95"] for r in mine]
                ax.errorbar(x, y, yerr=e, marker="o", ms=4, capsize=2, label=label, color=color(baseline_of(label)))
            if axis == "agents":
                ax.set_xscale("log")
                xs = sorted({r[key] for r in pts} | set(trained_n[:1]))
                ax.set_xticks(xs, [str(v) for v in xs])
                ax.minorticks_off()
                if trained_n:
                    ax.axvline(trained_n[0], color="0.6", ls=":", lw=1)
                    ax.annotate(" trained here", (trained_n[0], 1), xycoords=("data", "axes fraction"),
                                va="top", fontsize=7, color="0.4")
            if m == "max_in" and cfg.rules:
                ax.axhline(cfg.rules, color="0.6", ls="--", lw=1)
                ax.annotate(f" K = {cfg.rules}: a program's in-degree bound", (0, cfg.rules),
                            xycoords=("axes fraction", "data"), va="bottom", fontsize=7, color="0.4")
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel(ylabel, fontsize=8)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(6, len(labels)), fontsize=8, frameon=False)
    fig.suptitle(f"zero-shot stress on {cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}; trained at "
                 f"{cfg.task.agents_per_group} per group with no link failure), mean ± 95 % interval over "
                 f"{cfg.stress.seeds} test seeds", fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    return save_figure(fig, path)


_SEED_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def seeds_plane(points: Mapping[str, Sequence[tuple[int, float, float]]], across: Mapping[str, tuple],
                title: str, path: Path) -> Path:
    """Loss against max degree over training seeds: per baseline one small marker per training seed (its model's
    mean over the evaluation seeds; marker shape = seed) and the across-seed mean with its 95 % t-interval on both
    axes as error bars (none for one seed). ``points``: baseline -> [(seed, max degree, loss)]; ``across``:
    baseline -> (mean degree, degree half-width or None, mean loss, loss half-width or None)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, ax = plt.subplots(figsize=(8.2, 5.6), dpi=120)
    seeds = sorted({s for pts in points.values() for s, _, _ in pts})
    marker = {s: _SEED_MARKERS[k % len(_SEED_MARKERS)] for k, s in enumerate(seeds)}
    names, xs, ys, cols = [], [], [], []
    for b, pts in points.items():
        col = color(baseline_of(b))
        for s, x, y in pts:
            ax.scatter(x, y, s=22, marker=marker[s], facecolors="none", edgecolors=col, lw=0.9, zorder=3)
        mx, hx, my, hy = across[b]
        ax.errorbar(mx, my, xerr=hx, yerr=hy, fmt="o", ms=7, color=col, capsize=3, lw=1.2, zorder=4)
        names.append(b), xs.append(mx), ys.append(my), cols.append(col)
    # the frame holds the markers, not the intervals: with 2 or 3 seeds a t-interval (t = 12.7 at 1 degree of
    # freedom) can span many times the spread of the points and would squeeze them into a corner
    px = [x for x in [x for pts in points.values() for _, x, _ in pts] + xs if math.isfinite(x)] or [0.0]
    py = [y for y in [y for pts in points.values() for _, _, y in pts] + ys if math.isfinite(y)] or [0.0]
    (x0, x1), (y0, y1) = (min(px), max(px)), (min(py), max(py))
    # a span of one value (one baseline, one seed) still gets a readable frame around it
    wx, wy = (hi - lo if hi - lo > 1e-9 * max(1.0, abs(hi)) else 0.2 * max(abs(hi), 1.0)
              for lo, hi in ((x0, x1), (y0, y1)))
    x0, x1, y0, y1 = x0 - 0.3 * wx, x1 + 0.3 * wx, y0 - 0.12 * wy, y1 + 0.12 * wy
    if min(px) >= 0:
        x0 = max(x0, -0.06 * x1)  # a degree is never negative
    if min(py) >= 0:
        y0 = max(y0, -0.02 * y1)  # nor is a loss here
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    cut = [b for b, (mx, hx, my, hy) in across.items()
           if (hx is not None and (mx - hx < x0 or mx + hx > x1))
           or (hy is not None and (my - hy < y0 or my + hy > y1))]
    if cut:
        ax.text(0.99, 0.01, "intervals beyond the frame are cut: " + ", ".join(cut), transform=ax.transAxes,
                ha="right", va="bottom", fontsize=6.5, color="0.35", wrap=True)
    place_labels(ax, xs, ys, names, cols, avoid=[(x, y) for pts in points.values() for _, x, y in pts])
    handles = [Line2D([], [], ls="", marker="o", ms=7, color="0.3",
                      label="mean over training seeds ± 95 % t-interval")]
    handles += [Line2D([], [], ls="", marker=marker[s], ms=5, mfc="none", mec="0.3", label=f"training seed {s}")
                for s in seeds]
    ax.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=min(4, len(handles)),
              frameon=False)
    ax.set_xlabel("max in+out (the paper's deg; mean over steps, episodes and evaluation seeds)",
                  fontsize=8)
    ax.set_ylabel("loss (lower is better)", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, lw=0.5)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


def profile_plot(curves: Mapping[str, tuple], taus: Sequence[float], title: str, note: str, path: Path) -> Path:
    """Performance profiles (rliable's score distributions): per baseline the fraction of (task, training seed)
    runs whose normalized score exceeds tau, with its 95 % stratified bootstrap band. ``curves``: baseline ->
    (profile, lower, upper), each len(taus); ``note``: a line under the axes (the runs counted, those left out)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.2, 5.4), dpi=120)
    for b, (prof, lo, hi) in curves.items():
        col = color(baseline_of(b))
        ax.plot(taus, prof, color=col, lw=1.5, label=b, drawstyle="steps-post")
        ax.fill_between(taus, lo, hi, color=col, alpha=0.12, step="post", lw=0)
    for x, what, y in ((0.0, "no-comm = 0", 0.97), (1.0, "tf-full = 1", 0.91)):  # staggered: never overprinted
        ax.axvline(x, color="0.5", ls=":", lw=1)
        ax.annotate(f" {what}", (x, y), xycoords=("data", "axes fraction"), va="top", fontsize=7, color="0.35",
                    bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 0.5})
    ax.set_ylim(-0.02, 1.05)
    ax.set_xlabel("normalized score tau = (no-comm loss - loss) / (no-comm loss - tf-full loss), per task and "
                  "training seed (higher is better)", fontsize=8)
    ax.set_ylabel("fraction of runs (task, training seed) with score > tau", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, lw=0.5)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    import textwrap

    lines = textwrap.wrap(note, 150)
    fig.text(0.01, 0.01, "\n".join(lines), fontsize=7, color="0.3", ha="left", va="bottom")
    fig.tight_layout(rect=(0, 0.025 + 0.02 * len(lines), 1, 1))
    return save_figure(fig, path)
