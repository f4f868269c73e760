"""Programs that a sweep of `neurosym synth` left for select's grid, searched with other settings than select's own:
the one line that names the command selecting among them (select never swaps them in by itself)."""

from __future__ import annotations


from ..baselines import run_args
from ..config import RunConfig, UserError
from ..run import RunDir
from ..schemes.searched import SEARCH_KEYS, override, point_tag, recorded_search
from ..utils.io import read_json

__all__ = ["SEARCH_KEYS", "searched_otherwise"]


def searched_otherwise(cfg: RunConfig, points: list[RunConfig]) -> str | None:
    """A line for the grid points whose program is not on disk but one of the same (K, lambda, features) is, searched
    with other settings (a sweep of `neurosym synth` at its own schedule): the command that makes select reuse
    them; None when there are none. Select never swaps in a program of another search silently: the pick would
    then depend on what happened to be on disk."""
    import shlex

    found: dict[str, list[str]] = {}
    for p in points:
        if RunDir(p).synthesized_file.exists():
            continue
        stem = point_tag(rules=p.rules, lam=p.lam, features=p.features)
        for d in RunDir(cfg).summaries(stem):
            if d.parent.name != stem and not d.parent.name.startswith(stem + "-"):
                continue  # k1-lam0.5-v1 is not k1-lam0.5-v10
            try:
                synth = read_json(d)["config"]["synth"]
                key = " ".join(override(k, x) for k, x in recorded_search(synth).items()
                               if x != getattr(cfg.synth, k))
            except (UserError, KeyError, TypeError, AttributeError):
                continue  # not a summary of this version: nothing to offer
            found.setdefault(key, []).append(d.parent.name)
            break
    found.pop("", None)
    if not found:
        return None
    overrides, tags = max(found.items(), key=lambda kv: len(kv[1]))
    grid = [f"select.{k}=[{','.join(f'{x:g}' if isinstance(x, float) else str(x) for x in getattr(cfg.select, k))}]"
            for k in ("lam", "rules", "features")]
    line = f"neurosym select {run_args(cfg)} " + " ".join(shlex.quote(g) for g in grid) + f" {overrides}"
    ours = " ".join(f"synth.{k}={getattr(cfg.synth, k)}" for k in ("coarse", "patience"))
    return (f"{len(tags)} of the {len(points)} grid programs exist searched with other settings ({', '.join(tags[:3])}"
            f"{', ...' if len(tags) > 3 else ''}); select searches them again on its own schedule ({ours}); "
            f"`{line}` selects among those instead")
