"""Bandwidth beside degree (degrees.BANDWIDTH): bits one agent hears per step (messages heard x message width x 32)
and the share of the N (N - 1) possible links used, in every evaluation, its tables, the report and the export;
evaluations written before them still read."""

import json
import os
import subprocess

import numpy as np
import pytest
import torch

from conftest import neurosym_cmd
from neurosym_cli.commands.apps import compose_config
from neurosym_cli.config import ModelConfig
from neurosym_cli.degrees import BANDWIDTH, FLOAT_BITS, METRICS, bandwidth
from neurosym_cli.evaluation import evaluate, summarize
from neurosym_cli.export.bandwidth import bandwidth_json, heard
from neurosym_cli.policy import CommTransformer
from neurosym_cli.policy.comm import FullComm, NoComm
from neurosym_cli.policy.protocol import CommBase
from neurosym_cli.tasks import make_task

WIDTH = 8


class NextOne(CommBase):
    """Agent i hears agent i + 1 (mod N) only: one link per agent."""

    name = "next-one"

    def select(self, ctx, logits, round):
        n = logits.shape[-1]
        return torch.roll(torch.eye(n, dtype=torch.bool), 1, dims=1).expand_as(logits).clone()


def _rows(task: str, comm):
    cfg = compose_config("eval", [f"task={task}", "budget=tiny", "threads=1"])
    env = make_task(cfg.task, 3)  # three steps are enough: the rule is the same every step
    torch.manual_seed(0)
    pol = CommTransformer.for_task(env, ModelConfig(width=WIDTH, ffn=WIDTH))
    return evaluate(env, pol, comm, [0, 1], torch.device("cpu")), env


@pytest.mark.parametrize("task", ["random-grid", "unlabeled-goals"])  # one and two communication rounds
def test_bits_and_link_share_of_full_none_and_one_link_per_agent(task):
    full, env = _rows(task, FullComm())
    n = int(full[0]["max_in"]) + 1  # every other agent heard
    for r in full:
        assert r["link_share"] == 1.0 and r["bits"] == env.rounds * (n - 1) * WIDTH * 32
    for r in _rows(task, NoComm())[0]:
        assert r["bits"] == 0.0 and r["link_share"] == 0.0 and r["mean_degree"] == 0.0
    for r in _rows(task, NextOne())[0]:
        assert r["bits"] == env.rounds * WIDTH * FLOAT_BITS and r["link_share"] == pytest.approx(1 / (n - 1))
    summary = summarize(full)
    assert list(summary)[:len(METRICS) + 2] == [*METRICS, *BANDWIDTH]  # beside the degrees, before the task's own
    assert summary["bits"]["mean"] == env.rounds * (n - 1) * WIDTH * 32 and summary["link_share"]["std"] == 0.0


def test_bandwidth_follows_mean_in_plus_out():
    assert bandwidth(6.0, agents=4, rounds=1, width=16) == (3 * 16 * 32, 1.0)  # 4 agents hearing all 3 others
    assert bandwidth(0.0, agents=4, rounds=2, width=16) == (0.0, 0.0)
    assert bandwidth(0.0, agents=1, rounds=1, width=16) == (0.0, 0.0)  # one agent: no link is possible


def test_the_export_counts_each_heard_agent_once():
    picks = np.array([[[[1, 1], [-1, -1], [0, 1]]]])  # (T=1, R=1, N=3, K=2): 1 heard twice, nobody, 0 and 1
    assert heard({"e0_picks": picks}) == pytest.approx((1.0, 3 / 6))
    two = np.concatenate([picks, picks], axis=1)  # two rounds: twice the messages, the same share
    bw = bandwidth_json(width=4, arrays={"e0_picks": two}, evaluation=None)
    assert bw["golden"] == pytest.approx({"messages_heard_per_agent_step": 2.0, "bits_per_agent_step": 2 * 4 * 32,
                                          "link_share": 0.5})
    assert bw["bits_per_message"] == 128 and bw["evaluated"] is None
    ev = {"summary": {"bits": {"mean": 256.0, "n": 20}, "link_share": {"mean": 0.5}}}
    assert bandwidth_json(width=4, arrays={}, evaluation=ev, source="eval/x/metrics.json")["evaluated"] == {
        "file": "eval/x/metrics.json", "seeds": 20, "bits_per_agent_step": 256.0, "link_share": 0.5}
    assert bandwidth_json(width=4, arrays={}, evaluation={"summary": {}})["evaluated"] is None  # an old evaluation


def _record(d, seed, label, bits: bool):
    """A metrics.json as `neurosym eval` writes it; ``bits``: with the bandwidth (else as written before it)."""
    d.mkdir(parents=True)
    names = [*METRICS, *(BANDWIDTH if bits else ()), "collisions"]
    rows = [{"seed": s, "episodes": 1, **{m: 2.0 + seed + s for m in names}} for s in range(2)]
    summary = {m: {"mean": sum(r[m] for r in rows) / 2, "std": 0.5} for m in names}
    cfg = {"seed": seed, "task": {"name": "random-grid"}, "budget": {"name": "tiny"}, "exp_dir": str(d.parents[1])}
    (d / "metrics.json").write_text(json.dumps({"baseline": label, "label": label, "per_seed": rows,
                                                "summary": summary, "config": cfg}))


def test_the_report_shows_bits_and_link_share_and_reads_evaluations_without_them(tmp_path):
    root = tmp_path / "random-grid" / "tiny"
    for s in range(2):
        _record(root / f"seed{s}" / "eval" / "tf-full", s, "tf-full", bits=True)
        _record(root / f"seed{s}" / "eval" / "no-comm", s, "no-comm", bits=False)  # written before issue 40
    env = {**os.environ, "NEUROSYM_RUNS": str(tmp_path), "COLUMNS": "250"}
    for args in (["report", "task=random-grid", "budget=tiny", "report.reps=100"],  # across training seeds
                 ["report", f"report_dir={root / 'seed0'}", "report.reps=100"]):  # one run directory
        p = subprocess.run([*neurosym_cmd(), *args, "plots=false"], cwd=tmp_path, env=env, capture_output=True,
                           text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        head = [c.strip() for c in next(ln for ln in p.stdout.splitlines() if "bits/agent/step" in ln).split("┃")]
        bits = head.index("bits/agent/step")
        assert head[bits - 1:bits + 3] == ["mean in+out", "bits/agent/step", "link share", "collisions"]
        cells = {ln.split("│")[1].strip(): [c.strip() for c in ln.split("│")] for ln in p.stdout.splitlines()
                 if ln.count("│") == len(head) - 1}
        assert cells["no-comm"][bits:bits + 2] == ["-", "-"] and cells["no-comm"][bits + 2] != "-"  # written before
        assert cells["tf-full"][bits].startswith(("3.000", "2.500")) and cells["tf-full"][bits + 1] != "-"
        assert "bits/agent/step: messages one agent hears per step" in " ".join(p.stdout.split())
    rows = [r for r in (root / "report.csv").read_text().splitlines() if ",bits," in r or ",link_share," in r]
    assert rows and all(r.startswith("random-grid,tf-full,") for r in rows)
