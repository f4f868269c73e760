"""The page's figures, drawn from the small result files alone (docs/figures/)."""

from __future__ import annotations

import json
from pathlib import Path

from .files import FIGURES, ORDER, RESULTS, VARIANTS, read


def vmas_order(b: dict) -> list[str]:
    """The baselines of a VMAS result file in the paper's order, the others after them by name."""
    return sorted(b, key=lambda k: (ORDER.index(k) if k in ORDER else len(ORDER), k))


def draw_figures() -> None:
    """docs/figures/<task>.png (the paper's Figure 2 with a loss-vs-degree panel) from the result files alone."""
    from neurosym_cli.plotting import figure2

    for task in VARIANTS:
        if VARIANTS[task][0] != task or not (RESULTS / f"{task}.json").exists():
            continue  # one figure per task, from its main variant
        r = read(task)
        rows = [(r["baselines"][b]["label"], r["baselines"][b]["summary"]) for b in ORDER if b in r["baselines"]]
        title = f"{task} (paper budget, train seed 0): mean ± std over {r['seeds']} eval seeds"
        FIGURES.mkdir(exist_ok=True)
        figure2(rows, title.replace(": ", ":\n"), FIGURES / f"{task}.png")
        print(f"drew {FIGURES / (task + '.png')}")


def _stress_cfg(st: dict):
    """What plotting.stress_plot reads of a config, from a stress result file."""
    from types import SimpleNamespace as NS

    return NS(rules=st["rules"], seed=st["seed"], task=NS(name=st["task"], agents_per_group=st["trained_agents_per_group"]),
              budget=NS(name=st["budget"]), stress=NS(seeds=st["seeds"]))


def draw_stress(task: str) -> None:
    """docs/figures/<task>-stress.png from stress-<task>.json, when it exists."""
    from neurosym_cli.plotting import stress_plot

    if (RESULTS / f"stress-{task}.json").exists():
        st = read(f"stress-{task}")
        stress_plot(st["results"], _stress_cfg(st), FIGURES / f"{task}-stress.png")
        print(f"drew {FIGURES / (task + '-stress.png')}")


def draw_vmas() -> None:
    """docs/figures/vmas-<scenario>.png (loss, degrees, loss against max in-degree; 95 % t intervals over the
    evaluation seeds) from the VMAS result files alone."""
    from neurosym_cli.plotting import figure2

    for f in sorted(RESULTS.glob("vmas-*.json")):
        r = json.loads(f.read_text())
        b = r["baselines"]
        rows = [(b[k]["label"], b[k]["summary"]) for k in vmas_order(b)]
        title = (f"{r['task']} ({r['budget']['name']} budget, train seed {r['training_seed']}): "
                 f"mean ± 95 % t interval over {r['seeds']} eval seeds")
        figure2(rows, title.replace(": ", ":\n"), FIGURES / f"{f.stem}.png", err="ci95")
        print(f"drew {FIGURES / (f.stem + '.png')}")


def draw_pareto(task: str) -> None:
    """docs/figures/<task>-pareto-selected.png: loss vs max in+out of every baseline and the selected program."""
    from neurosym_cli.plotting import pareto_plot
    from neurosym_cli.utils.pareto import dominated_area, pareto_front

    if not (RESULTS / f"select-{task}.json").exists():
        return
    sel, v = read(f"select-{task}"), read(task)
    pts = [(v["baselines"][b]["label"], v["baselines"][b]["summary"]["max_degree"]["mean"],
            v["baselines"][b]["summary"]["cost"]["mean"]) for b in ORDER if b in v["baselines"]]
    pts += [(f"{b}-{sel['name'].split('-coarse')[0]} (selected)", m["summary"]["max_degree"]["mean"],
             m["summary"]["cost"]["mean"]) for b, m in sel["test"].items()]
    has_rl = (RESULTS / f"rl-{task}.json").exists()
    if has_rl:  # the appendix-D picks, on the same test seeds
        pts += [(b, m["summary"]["max_degree"]["mean"], m["summary"]["cost"]["mean"])
                for b, m in read(f"rl-{task}")["test"].items()]
    xy = [(d, c) for _, d, c in pts]
    front = pareto_front(xy)
    ref = (1.05 * max(x for x, _ in xy), 1.05 * max(y for _, y in xy))
    pareto_plot(pts, front, ref, dominated_area([xy[i] for i in front], ref),
                f"{task} (paper budget, train seed 0): test loss against max in+out (lower left is better),\n"
                "every baseline, the program chosen by `neurosym select`"
                + (" and the rl picks of `neurosym rl`" if has_rl else ""),
                FIGURES / f"{task}-pareto-selected.png")
    print(f"drew {FIGURES / (task + '-pareto-selected.png')}")


def draw_seed_figures(by_task: dict, out_dir: Path = FIGURES) -> None:
    """seeds-<task>.png and seeds-profile.png from the seed files alone (neurosym_cli.seeds.draw)."""
    from neurosym_cli import seeds

    for f in seeds.draw({t: r for t, r in by_task.items() if r}, out_dir):
        print(f"drew {f}")
