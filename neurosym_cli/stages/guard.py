"""The one line that says a program threw communication away: where hearing everybody (tf-full) clearly beats
hearing nobody (no-comm), yet the program the search chose is silent or no better than no-comm (issue 37). The
usual cause is a lam that prices the degree above what communication buys on this task; the line says what to try."""

from __future__ import annotations

PROGRAM_PREFIXES = ("prog-retrained", "prog")
"""the labels of the searched program's evaluations, the retrained one first (what the paper reports)"""
SILENT = 1e-6
"""a max in+out below this over the evaluation is silence"""


def _mean(summary: dict, metric: str) -> float | None:
    st = summary.get(metric) if isinstance(summary, dict) else None
    v = st.get("mean") if isinstance(st, dict) else None
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _half(summary: dict, metric: str) -> float:
    st = summary.get(metric) if isinstance(summary, dict) else None
    v = st.get("ci95", 0.0) if isinstance(st, dict) else 0.0
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else 0.0


def communication_guard(rows: list[tuple[str, dict]], rerun: str = "") -> str | None:
    """rows: (label, summary) per evaluated baseline, as results.collect gives them (summary: metric -> mean, ci95).
    One line when tf-full beats no-comm beyond both 95 % intervals and the program (prog-retrained, else prog) is
    silent or its loss is no lower than no-comm's; else None. ``rerun``: the synth command to extend."""
    by = dict(rows)
    tf, nc = by.get("tf-full"), by.get("no-comm")
    if tf is None or nc is None:
        return None
    tf_cost, nc_cost = _mean(tf, "cost"), _mean(nc, "cost")
    if tf_cost is None or nc_cost is None or not tf_cost + _half(tf, "cost") < nc_cost - _half(nc, "cost"):
        return None  # communication does not clearly help here: silence may well be right
    for prefix in PROGRAM_PREFIXES:
        # -k...: a searched program's; -file-...: one given as program= (pipeline.select=front's pick)
        found = [(label, s) for label, s in rows if label == prefix or label.startswith((prefix + "-k",
                                                                                         prefix + "-file-"))]
        if found:
            break
    else:
        return None
    label, prog = found[0]
    cost, degree = _mean(prog, "cost"), _mean(prog, "max_degree")
    if cost is None:
        return None
    silent = degree is not None and degree < SILENT
    if not silent and cost < nc_cost:
        return None
    what = "is silent (max in+out 0)" if silent else f"does no better than no-comm ({cost:.3g})"
    base = rerun or "neurosym synth"
    return (f"communication helps on this task (tf-full {tf_cost:.3g} against no-comm {nc_cost:.3g}), but {label} "
            f"{what}: lam prices the degree above what it buys here; try `{base} synth.front=true` and pick a budget "
            f"from `neurosym show-program` (its front), or a smaller lam, or synth.objective=scaled "
            f"(docs/extending.md, 'The trade-off')")
