"""The template's placeholders -> the page: a table of functions by name (never text evaluated as code)."""

from __future__ import annotations

import re

from .appendix import noisy, rl, vmas
from .beyond import beyond
from .paper_defaults import paper_defaults
from .files import PLANNED_SEEDS, TEMPLATE, load_seeds
from .sections import glance, section, selection, stress
from .seed_sections import seed_mean, seeds_glance, seeds_section
from .tables import gap, mean, minus, paired, pm


def render(template: str, variants: dict[str, dict], run: dict, seed_runs: dict | None = None) -> str:
    """The page: every placeholder of ``template`` replaced (``seed_runs``: the seed files by task, read from
    docs/results/seeds when None); an unknown placeholder or one its files cannot fill is a one-line SystemExit."""
    by_task = load_seeds() if seed_runs is None and "{{seeds" in template else (seed_runs or {})

    def fmt(x: float, digits: str) -> str:
        return minus(f"{x:.{int(digits)}f}")

    ops = {
        "section": lambda n: section(n, variants[n]).rstrip("\n"),
        "glance": lambda: glance(variants).rstrip("\n"),
        "mean": lambda n, b, m, d: fmt(mean(variants[n], b, m), d),
        "half": lambda n, b, m, d: fmt(mean(variants[n], b, m) / 2, d),
        "per": lambda n, b, m1, m2, d: fmt(mean(variants[n], b, m1) / mean(variants[n], b, m2), d),
        "paired": lambda n, a, b, d: pm(paired(variants[n], a, b), int(d)),
        "gap": lambda n, a, b: minus(f"{gap(variants[n], a, b):+.1f} %"),
        "run": lambda key, d: fmt(run[key], d),
        "selection": lambda t: selection(t, variants),
        "stress": lambda t: stress(t),
        "vmas": lambda t: vmas(t),
        "beyond": lambda: beyond(),
        "paper_defaults": lambda: paper_defaults(),
        "rl": lambda t: rl(t, variants),
        "noisy": lambda t, clean: noisy(t, clean),
        "seeds": lambda: seeds_section(by_task),
        "seeds_glance": lambda: seeds_glance(by_task).rstrip("\n"),
        "seeds_planned": lambda: ", ".join(map(str, PLANNED_SEEDS)),
        "seedmean": lambda t, seed, b, m, d: fmt(seed_mean(by_task, t, int(seed), b, m), d),
    }

    def sub(m: re.Match) -> str:
        op, *args = m.group(1).split()
        if op not in ops:
            raise SystemExit(f"{TEMPLATE}: unknown placeholder {{{{{m.group(1)}}}}}")
        try:
            return ops[op](*args)
        except (KeyError, TypeError, ValueError) as e:
            raise SystemExit(f"{TEMPLATE}: placeholder {{{{{m.group(1)}}}}}: {type(e).__name__} {e}") from None

    return re.sub(r"\{\{([^{}]+)\}\}", sub, template)
