"""The one line that says a program threw communication away: where hearing everybody (tf-full) clearly beats
hearing nobody (no-comm), yet the run's program is silent or no better than no-comm (issue 37); and the rule
"communication helps" itself, which pipeline.select=front (stages/front_select.py) applies on validation."""

from __future__ import annotations

from typing import Mapping, Sequence

from ..stats import mean_ci

PROGRAM_PREFIXES = ("prog-retrained", "prog")
"""the baselines whose evaluation is the searched program's, the retrained one first (what the paper reports)"""
SILENT = 1e-6
"""a max in+out below this over the evaluation is silence"""
LEVERS = (("synth.search", "hybrid", "synth.search=hybrid (a stronger search)"),
          ("synth.objective", "scaled", "synth.objective=scaled (the trade-off in the task's own units)"))
"""(setting, value, words) of each search setting the line may suggest; one already in effect is not suggested
(a hint that leads back to where the user stands)"""


def communication_helps(tf_loss: Sequence[float], nc_loss: Sequence[float]) -> tuple[bool, float, float]:
    """(helps, mean, half-width) of no-comm - tf-full over the same seeds (loss per seed, in seed order): helps when
    the paired 95 % Student-t interval lies above 0 (hearing everybody beats hearing nobody beyond chance)."""
    if len(tf_loss) != len(nc_loss):
        raise ValueError(f"tf-full and no-comm are measured on different seeds: {len(tf_loss)} vs {len(nc_loss)}")
    d, h = mean_ci([n - t for n, t in zip(nc_loss, tf_loss)])
    return d - h > 0, d, h


def _mean(summary: dict, metric: str) -> float | None:
    st = summary.get(metric) if isinstance(summary, dict) else None
    v = st.get("mean") if isinstance(st, dict) else None
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _half(summary: dict, metric: str) -> float:
    st = summary.get(metric) if isinstance(summary, dict) else None
    v = st.get("ci95", 0.0) if isinstance(st, dict) else 0.0
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else 0.0


def _helps(tf: dict, nc: dict, tf_seeds: Mapping[int, float], nc_seeds: Mapping[int, float]) -> bool:
    """communication_helps on the evaluation seeds both were measured on (paired rows, at least 2); without them
    (older or hand-made files) the two summaries' 95 % intervals must not overlap."""
    common = sorted(set(tf_seeds) & set(nc_seeds))
    if len(common) >= 2:
        return communication_helps([tf_seeds[s] for s in common], [nc_seeds[s] for s in common])[0]
    tf_cost, nc_cost = _mean(tf, "cost"), _mean(nc, "cost")
    return tf_cost is not None and nc_cost is not None and tf_cost + _half(tf, "cost") < nc_cost - _half(nc, "cost")


def communication_guard(rows: list[tuple[str, dict]], *, labels: Sequence[str], rerun: str = "", show: str = "",
                        settings: Mapping[str, object] | None = None,
                        per_seed: Mapping[str, Mapping[int, float]] | None = None) -> str | None:
    """rows: (label, summary) per evaluated baseline, as results.collect gives them (summary: metric -> mean, ci95).
    ``labels``: the run's own program labels (prog-retrained's, then prog's; the first evaluated one is judged, never
    another program's that the directory also holds); ``per_seed``: label -> {evaluation seed: loss} (tf-full's and
    no-comm's, for the paired rule); ``settings``: the run's synth.front, synth.search and synth.objective, so that
    no lever already in effect is suggested; ``rerun``: the synth command to extend; ``show``: the show-program
    command that prints the run's front (both run as printed: the run's task, budget, seed and runs root).

    One line when communication helps (communication_helps) and the program is silent or its loss is no lower than
    no-comm's; else None."""
    by = dict(rows)
    tf, nc = by.get("tf-full"), by.get("no-comm")
    per_seed, settings = per_seed or {}, settings or {}
    if tf is None or nc is None or not _helps(tf, nc, per_seed.get("tf-full", {}), per_seed.get("no-comm", {})):
        return None  # communication does not clearly help here: silence may well be right
    label = next((x for x in labels if x in by), None)
    if label is None:
        return None
    tf_cost, nc_cost = _mean(tf, "cost"), _mean(nc, "cost")
    cost, degree = _mean(by[label], "cost"), _mean(by[label], "max_degree")
    if cost is None or nc_cost is None or tf_cost is None:
        return None
    silent = degree is not None and degree < SILENT
    if not silent and cost < nc_cost:
        return None
    what = "is silent (max in+out 0)" if silent else f"does no better than no-comm ({cost:.3g})"
    base, shown = rerun or "neurosym synth", show or "neurosym show-program"
    given = "-file-" in label  # a program= file (pipeline.select=front's pick): no lam chose it
    if str(settings.get("synth.front", "")).lower() == "true":
        tries = [f"a higher budget of its front (`{shown}` prints it) as program="]
    else:
        tries = [f"`{base} synth.front=true` and a budget of its front from `{shown}`"]
    tries += [] if given else ["a smaller lam"]
    tries += [words for key, value, words in LEVERS if str(settings.get(key, "")) != value]
    why = "" if given else ": lam prices the degree above what it buys here"
    return (f"communication helps on this task (tf-full {tf_cost:.3g} against no-comm {nc_cost:.3g}), but "
            f"{label} {what}{why}; try " + ", or ".join(tries) + " (docs/extending.md, 'The trade-off')")
