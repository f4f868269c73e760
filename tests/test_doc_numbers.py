"""Numbers the docs state, each checked against the file or default it comes from (issue 40: a number a doc states
is generated or checked by a test). One row of CHECKS per statement: the doc, a pattern whose groups are the
numbers as the doc writes them (matched on the doc's text with its line breaks made spaces), how many times the
doc must state it (so a rewording that the pattern misses fails too), and the source that says what they are.
A doc that states a number with a source gets a row here."""

from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAIN_JOB = ROOT / "docs" / "results" / "main-job" / "seeds.json"
PAPER_METHOD_JOB = ROOT / "docs" / "results" / "main-job-paper-method" / "seeds.json"


def _far_thresholds() -> list[float]:
    """Per training seed of the main job under the paper's method (docs/results/main-job-paper-method/seeds.json),
    the threshold of the test `d >= c` in the first rule of its program: how far away the random agent it asks is
    at least."""
    from neurosym_cli.dsl.ast import And, Test
    from neurosym_cli.dsl.parser import parse

    def tests(c):
        return tests(c.left) + tests(c.right) if isinstance(c, And) else [c] if isinstance(c, Test) else []

    seeds = json.loads(PAPER_METHOD_JOB.read_text())["seeds"]
    out = []
    for k in sorted(seeds, key=int):
        rule = parse(seeds[k]["programs"]["k2-lam0.5-v1"][0] + "\n").rounds[0][0]
        out.append(next(t.threshold for t in tests(rule.cond) if t.lhs.terms == (("d", 1.0),)))
    return out


def gif_threshold() -> tuple[str, ...]:
    """README's animated episode (docs/figures/two-groups-episode2.gif, seed 0 of the main job): its first rule's
    distance, as the program prints it."""
    return (repr(_far_thresholds()[0]),)


def _main_job_costs() -> dict[str, tuple[float, float, float]]:
    """Per training seed of the README's main job (docs/results/main-job/seeds.json): tf-full's and prog-retrained's
    mean loss and prog-retrained's mean max in-degree."""
    seeds = json.loads(MAIN_JOB.read_text())["seeds"]

    def of(b: dict, name: str) -> dict:
        return next(v for k, v in b.items() if k == name or k.startswith(name + "-"))

    return {k: (of(r["baselines"], "tf-full")["cost"]["mean"], of(r["baselines"], "prog-retrained")["cost"]["mean"],
                of(r["baselines"], "prog-retrained")["max_in"]["mean"])
            for k, r in sorted(seeds.items(), key=lambda kv: int(kv[0]))}


def within_five() -> tuple[str, ...]:
    """How many of the main job's training seeds have prog-retrained within 5 % of tf-full, and of how many."""
    c = _main_job_costs()
    return (str(sum(p <= 1.05 * t for t, p, _ in c.values())), str(len(c)))


def per_seed_gaps() -> tuple[str, ...]:
    """Per training seed, prog-retrained's loss above tf-full's in %, one decimal, as the README lists them: all
    but the last seed joined by commas, then the last."""
    gaps = [f"{100 * (p / t - 1):.1f}" for t, p, _ in _main_job_costs().values()]
    return ", ".join(gaps[:-1]), gaps[-1]


def select_finalists() -> tuple[str, ...]:
    """`neurosym select`'s default select.finalists (conf/select.yaml, what the command line composes)."""
    from omegaconf import OmegaConf

    return (str(OmegaConf.load(ROOT / "conf" / "select.yaml").select.finalists),)


def grad_clip() -> tuple[str, ...]:
    """optim.grad_clip's default (config.OptimConfig)."""
    from neurosym_cli.config import OptimConfig

    return (repr(float(OptimConfig().grad_clip)),)


def parser_limits() -> tuple[str, ...]:
    """What the program parser refuses: rules in a round, nesting of a filter, characters in a line."""
    from neurosym_cli.dsl.parser import MAX_DEPTH, MAX_LINE, MAX_RULES

    return (str(MAX_RULES), str(MAX_DEPTH), f"{MAX_LINE:,}")


def _seed0(name: str) -> dict:
    b = json.loads(MAIN_JOB.read_text())["seeds"]["0"]["baselines"]
    return next(v for k, v in b.items() if k == name or k.startswith(name + "-"))


def seed0_tf_full() -> tuple[str, ...]:
    """Seed 0 of the main job: tf-full's loss, mean ± 95 % half-width over the evaluation seeds, two decimals."""
    c = _seed0("tf-full")["cost"]
    return f"{c['mean']:.2f}", f"{c['ci95']:.2f}"


def seed0_prog_retrained() -> tuple[str, ...]:
    """Seed 0 of the main job: prog-retrained's loss (mean ± half-width) and max in-degree, as the README writes."""
    c = _seed0("prog-retrained")
    return f"{c['cost']['mean']:.2f}", f"{c['cost']['ci95']:.2f}", f"{c['max_in']['mean']:.1f}"


def seed0_dist_no_comm() -> tuple[str, ...]:
    """Seed 0 of the main job: dist's and no-comm's mean loss, one decimal."""
    return f"{_seed0('dist')['cost']['mean']:.1f}", f"{_seed0('no-comm')['cost']['mean']:.1f}"


def nine_seed_gap() -> tuple[str, ...]:
    """The main job's seeds whose oracle learned (tf-full clearly below no-comm): prog-retrained's loss above
    tf-full's in %, mean ± 95 % t half-width over those training seeds, and the degrees of freedom."""
    from neurosym_cli.stats import mean_ci

    seeds = json.loads(MAIN_JOB.read_text())["seeds"]

    def of(b: dict, name: str) -> float:
        return next(v for k, v in b.items() if k == name or k.startswith(name + "-"))["cost"]["mean"]

    gaps = [100 * (of(r["baselines"], "prog-retrained") / of(r["baselines"], "tf-full") - 1)
            for r in seeds.values() if of(r["baselines"], "tf-full") < 0.8 * of(r["baselines"], "no-comm")]
    m, h = mean_ci(gaps)
    return f"{m:.1f}", f"{h:.1f}", str(len(gaps) - 1)


def swarm_retrain() -> tuple[str, ...]:
    """benchmarks/bench_swarm_retrain.py's committed run (docs/results/bench-swarm-retrain.json): CPU seconds a
    rollout before and now, alternated in one process, and their ratio."""
    r = json.loads((ROOT / "docs" / "results" / "bench-swarm-retrain.json").read_text())["alternated_in_one_process"]
    return (f"{r['before']['cpu_s_per_rollout']:.2f}", f"{r['now']['cpu_s_per_rollout']:.2f}",
            f"{r['ratio_cpu']:.2f}", f"{r['ramps-torch']['cpu_s_per_rollout']:.2f}", f"{r['ratio_cpu_ramps']:.2f}")


def collision_cost_ms() -> tuple[str, ...]:
    """The same file's collision cost, forward and backward, ms a call: the previous commit's two runs, then this
    one's."""
    r = json.loads((ROOT / "docs" / "results" / "bench-swarm-retrain.json").read_text())["collision_cost_ms"]
    return tuple(f"{x:.2f}" for x in r["previous"] + r["this"])


def round_ratios() -> tuple[str, ...]:
    """bench_compile.py --round's rows in docs/results/bench-compile-profile.json: eager / fused at N = 20-200."""
    r = json.loads((ROOT / "docs" / "results" / "bench-compile-profile.json").read_text())["round_rows"]
    return tuple(f"{x['ratio']:.2f}" for x in r if x["agents"] >= 20)


def compile_profile() -> tuple[str, ...]:
    """benchmarks/bench_compile.py --profile's committed run (docs/results/bench-compile-profile.json): CPU
    seconds of a training step, eager then fused."""
    r = json.loads((ROOT / "docs" / "results" / "bench-compile-profile.json").read_text())["profile"]
    return tuple(f"{m['total_s_per_step']:.2f}" for m in r)


def compile_growth() -> tuple[str, ...]:
    """The same file's fused / eager training rollouts/s at B = 10, 50, 200."""
    r = json.loads((ROOT / "docs" / "results" / "bench-compile-profile.json").read_text())["growth_with_batch"]
    return tuple(f"{g['ratio']:.2f}" for g in r)


def cross_seed2_det() -> tuple[str, ...]:
    """random-cross under the defaults, training seed 2 (docs/results/seeds-defaults/random-cross-seed2.json):
    det-prog-retrained's test loss and max out-degree, and prog-retrained's max out-degree."""
    b = json.loads((ROOT / "docs" / "results" / "seeds-defaults" / "random-cross-seed2.json").read_text())["baselines"]
    return (f"{b['det-prog-retrained']['summary']['cost']['mean']:.2f}",
            f"{b['det-prog-retrained']['summary']['max_out']['mean']:.2f}",
            f"{b['prog-retrained']['summary']['max_out']['mean']:.2f}")


def margin_claim_counts() -> tuple[str, ...]:
    """benchmarks/front_margin.py's committed run (docs/results/front-margin.json): the paper's claims held over the
    nine task-seeds at margin 0.01, per task (random-cross, random-grid, unlabeled-goals), then at 0.02 in all and
    for the two formation tasks, at 0.005 and 0 (one number: the doc states them as equal) and at null."""
    rows = json.loads((ROOT / "docs" / "results" / "front-margin.json").read_text())

    def held(margin, task=None) -> str:
        return str(sum(sum(r["holds"].values()) for r in rows if r["margin"] == margin and task in (None, r["task"])))

    return (held(0.01), held(0.01, "random-cross"), held(0.01, "random-grid"), held(0.01, "unlabeled-goals"),
            held(0.02), held(0.02, "random-cross"), held(0.02, "random-grid"),
            held(0.005) if held(0.005) == held(0.0) else f"{held(0.005)} and {held(0.0)}", held(None))


def main_job_across_vendors() -> tuple[str, ...]:
    """The README's main job on an AMD EPYC (docs/results/main-job/seeds.json) and on an Intel Xeon
    (docs/results/main-job-intel/seeds.json): on how many of the seeds every baseline's summary, program and front
    pick is alike, and of how many; each file must name its vendor."""
    amd = json.loads(MAIN_JOB.read_text())
    intel = json.loads((ROOT / "docs" / "results" / "main-job-intel" / "seeds.json").read_text())
    assert (amd["machine"]["cpu_vendor"], intel["machine"]["cpu_vendor"]) == ("AuthenticAMD", "GenuineIntel")
    keys = ("baselines", "programs", "front_picks")
    alike = [s for s in amd["seeds"] if all(amd["seeds"][s][k] == intel["seeds"].get(s, {}).get(k) for k in keys)]
    return str(len(alike)), str(len(amd["seeds"]))


@dataclass(frozen=True)
class Check:
    doc: str  # path from the repository root
    pattern: str  # a regular expression; its groups are the numbers
    source: Callable[[], tuple[str, ...]]  # what the groups must read
    times: int = 1  # how many times the doc states it


CHECKS = [
    Check("README.md", r"a random agent at least ([\d.]+) away", gif_threshold, times=2),  # the GIF's alt and caption
    Check("README.md", r"within 5 % of tf-full on (\d+) of the (\d+) seeds", within_five),
    Check("README.md", r"every program and every front pick alike on (\d+) of the (\d+) seeds",
          main_job_across_vendors),
    Check("docs/reliability.md", r"every program and every front pick is alike on (\d+) of the (\d+) seeds",
          main_job_across_vendors),
    Check("README.md", r"\(tf-full\) has loss ([\d.]+) ± ([\d.]+)", seed0_tf_full),
    Check("README.md", r"\(prog-retrained\) the loss is ([\d.]+) ± ([\d.]+) while the agent that hears most "
          r"hears ([\d.]+)", seed0_prog_retrained),
    Check("README.md", r"\(dist, ([\d.]+)\) or nobody \(no-comm, ([\d.]+)\)", seed0_dist_no_comm),
    Check("README.md", r"prog-retrained is ([\d.]+) ± ([\d.]+) % above tf-full \(mean ± 95 % Student-t "
          r"half-width over training seeds, (\d+) degrees of freedom", nine_seed_gap),
    Check("README.md", r"per seed 0-9 its loss is ([-\d., ]+) and ([-\d.]+) % above", per_seed_gaps),
    Check("README.md", r"`select\.finalists` \((\d+)\)", select_finalists, times=2),
    Check("docs/fidelity.md", r"`select\.finalists` \((\d+)\)", select_finalists),
    Check("docs/extending.md", r"`optim\.grad_clip`, a norm of ([\d.]+)", grad_clip),
    Check("docs/performance.md",
          r"with today's hash\) ([\d.]+) CPU s a rollout against ([\d.]+) now, \*\*([\d.]+)x\*\*, and ([\d.]+) "
          r"now with the ramps as torch ops \(`pairs.COMPILED_RAMPS`\): the ramps' kernels buy ([\d.]+)x",
          swarm_retrain),
    Check("docs/performance.md", r"went from ([\d.]+) and ([\d.]+) ms to ([\d.]+) and ([\d.]+) ms", collision_cost_ms),
    Check("docs/performance.md", r"the `--round` rows, in the same file: ([\d.]+), ([\d.]+), ([\d.]+), ([\d.]+) at",
          round_ratios),
    Check("docs/performance.md", r"\| \*\*total\*\* \| \*\*([\d.]+)\*\* \| \*\*([\d.]+)\*\* \|", compile_profile),
    Check("docs/performance.md", r"\| fused / eager \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|", compile_growth),
    Check("docs/fidelity.md", r"so it now runs b14: test loss ([\d.]+), max out ([\d.]+) against ([\d.]+)",
          cross_seed2_det),
    Check("docs/fidelity.md", r"are (\d+) of 48 at 0\.01 \(random-cross (\d+) of 18, random-grid (\d+) of 18, "
          r"unlabeled-goals (\d+) of 12\), (\d+) at 0\.02 \(random-cross (\d+), random-grid (\d+)\), (\d+) at 0\.005 "
          r"and at 0, which pick denser programs \(random-grid seed 0: [\d.]+ against [\d.]+\), and (\d+) at null",
          margin_claim_counts),
    Check("docs/extending.md", r"at most (\d+) rules in a round, filters nested at most (\d+) deep, ([\d,]+) "
          r"characters a line", parser_limits),
]


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: f"{c.doc}:{c.source.__name__}")
def test_a_number_the_docs_state_is_its_sources(check):
    text = " ".join((ROOT / check.doc).read_text().split())
    found = [m.groups() for m in re.finditer(check.pattern, text)]
    assert len(found) == check.times, (f"{check.doc} states {check.pattern!r} {len(found)} times, expected "
                                       f"{check.times}: reworded? update the row")
    want = check.source()
    for got in found:
        assert got == want, f"{check.doc} says {got}, {check.source.__name__} says {want}: {check.source.__doc__}"


def test_a_wrong_number_fails_its_check(tmp_path, monkeypatch):
    """The mechanism itself: a doc whose number differs from its source fails."""
    def three() -> tuple[str, ...]:
        return ("3",)

    (tmp_path / "doc.md").write_text("retrains the `select.finalists`\n(7) programs\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    check = Check("doc.md", r"`select\.finalists` \((\d+)\)", three)
    with pytest.raises(AssertionError, match=r"says \('7',\), three says \('3',\)"):
        test_a_number_the_docs_state_is_its_sources(check)
    with pytest.raises(AssertionError, match="states .* 1 times, expected 2"):
        test_a_number_the_docs_state_is_its_sources(Check("doc.md", check.pattern, three, times=2))
