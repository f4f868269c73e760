"""What an exported baseline costs in messages (degrees.BANDWIDTH): manifest.json's ``bandwidth`` and the README's
lines. Measured on the golden episodes' picks, and read from the run's evaluation of the same label when there is
one (the evaluated degree, over every evaluation seed)."""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ..degrees import BANDWIDTH, FLOAT_BITS


def heard(arrays: Mapping[str, np.ndarray]) -> tuple[float, float]:
    """(messages one agent hears per step, every round, mean over agents, steps and episodes; links used / N (N - 1)
    per round, mean) of the golden episodes' ``e<k>_picks`` (T, R, N, K), -1 = nobody, an agent in two slots
    heard once."""
    per_step, shares = [], []
    for key in sorted(k for k in arrays if k.endswith("_picks")):
        picks = np.asarray(arrays[key])
        t, r, n, _ = picks.shape
        got = np.zeros((t, r, n, n + 1), bool)  # slot n: nobody
        np.put_along_axis(got, np.where(picks < 0, n, picks), True, axis=-1)
        links = got[..., :n].sum(-1)  # (T, R, N): agents heard by each agent in each round
        per_step.append(links.sum(1).mean(-1))  # (T,) summed over rounds, mean over agents
        shares.append(links.sum(-1) / (n * (n - 1)) if n > 1 else np.zeros((t, r)))
    if not per_step:
        return 0.0, 0.0
    return float(np.concatenate(per_step).mean()), float(np.concatenate([s.ravel() for s in shares]).mean())


def bandwidth_json(*, width: int, arrays: Mapping[str, np.ndarray], evaluation: Mapping[str, Any] | None,
                   source: str = "") -> dict:
    """manifest.json's ``bandwidth``: the message width (``width`` floats of FLOAT_BITS), the golden episodes'
    messages heard, bits and link share, and ``evaluation`` (a metrics.json of `neurosym eval`, from ``source``)'s
    means of the same, when it holds them."""
    msgs, share = heard(arrays)
    out: dict[str, Any] = {
        "message_floats": width, "bits_per_message": width * FLOAT_BITS,
        "golden": {"messages_heard_per_agent_step": msgs, "bits_per_agent_step": msgs * width * FLOAT_BITS,
                   "link_share": share},
        "evaluated": None,
    }
    summary = (evaluation or {}).get("summary") or {}
    if all(isinstance(summary.get(m), Mapping) and isinstance(summary[m].get("mean"), (int, float))
           for m in BANDWIDTH):
        out["evaluated"] = {"file": source, "seeds": summary["bits"].get("n"),
                            "bits_per_agent_step": summary["bits"]["mean"],
                            "link_share": summary["link_share"]["mean"]}
    return out


def readme_lines(bw: Mapping[str, Any]) -> list[str]:
    """The README's section on what the messages cost, from manifest.json's ``bandwidth``."""
    d, g, ev = bw["message_floats"], bw["golden"], bw["evaluated"]
    out = ["## Bandwidth", "",
           f"- One message is D = {d} float32 values: {bw['bits_per_message']} bits. An agent receives one per agent "
           "it hears per round (the request to those agents and the position beacons are not counted).",
           f"- The golden episodes: each agent hears {g['messages_heard_per_agent_step']:.3g} messages per step "
           f"(every round), {g['bits_per_agent_step']:.6g} bits per agent per step; {g['link_share']:.3g} of the "
           "N (N - 1) possible directed links are used."]
    if ev is not None:
        out.append(f"- At the evaluated degree (`{ev['file']}`, {ev['seeds']} evaluation seeds): "
                   f"{ev['bits_per_agent_step']:.6g} bits per agent per step, link share {ev['link_share']:.3g}.")
    return out + [""]


def of_run(cfg: Any, policy: Any, arrays: Mapping[str, np.ndarray]) -> dict:
    """``bandwidth_json`` of an export of ``cfg``'s baseline: the policy's message width (model.width for a program
    alone), the golden ``arrays`` and the run's evaluation of the same label when it exists and reads."""
    import json

    from ..run import RunDir

    run = RunDir(cfg)
    path = run.metrics_of(run.label)
    try:
        evaluation = json.loads(path.read_text())
    except (OSError, ValueError):  # not evaluated (or unreadable): the golden episodes alone
        evaluation = None
    try:
        source = path.relative_to(cfg.exp_dir).as_posix()
    except ValueError:
        source = str(path)
    width = policy.message_dim if policy is not None else cfg.model.width
    return bandwidth_json(width=width, arrays=arrays, evaluation=evaluation if isinstance(evaluation, dict) else None,
                          source=source)
