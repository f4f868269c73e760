"""docs/results.md is generated: the committed page is exactly what its template and result files give, and the
generator's statistics and verdicts behave on a hand-made case."""

import importlib.util
import subprocess
import sys

import pytest

from conftest import ROOT

spec = importlib.util.spec_from_file_location("results_doc", ROOT / "benchmarks" / "results_doc.py")
results_doc = importlib.util.module_from_spec(spec)
spec.loader.exec_module(results_doc)


def test_committed_results_page_is_the_render_of_its_files():
    p = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "results_doc.py"), "--check"], capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    text = (ROOT / "docs" / "results.md").read_text()
    assert "{{" not in text and "## random-cross" in text and "Claims at a glance" in text


def _variant(costs: dict[str, list[float]], **degrees) -> dict:
    base = {}
    for b, xs in costs.items():
        summary = {k: {"mean": degrees.get(f"{b}:{k}", 1.0), "std": 0.0} for k in results_doc.METRICS}
        summary["cost"] = {"mean": sum(xs) / len(xs), "std": 0.0}
        base[b] = {"summary": summary, "cost_per_seed": {str(s): x for s, x in enumerate(xs)}}
    return {"task": "random-cross", "lam": 0.5, "rules": 5, "objective": "paper", "seeds": 3, "baselines": base,
            "programs": {}}


def test_paired_difference_and_verdicts():
    names = ["tf-full", "hard-attn", "dist", "prog", "prog-retrained", "det-prog-retrained", "dt"]
    costs = {b: [10.0, 11.0, 12.0] for b in names}
    costs["prog-retrained"] = [10.2, 11.3, 12.1]  # +1.7 % over tf-full
    costs["dist"] = [11.0, 12.0, 13.5]  # prog-retrained lower on every seed
    costs["prog"] = [15.0, 16.0, 18.0]
    v = _variant(costs, **{"hard-attn:max_out": 9.0, "prog-retrained:max_out": 3.0, "det-prog-retrained:max_out": 6.0,
                           "dt:max_in": 9.0})
    d, h = results_doc.paired(v, "prog-retrained", "dist")
    assert d == pytest.approx(-(0.8 + 0.7 + 1.4) / 3) and h > 0
    verdicts = {c.short: c.holds for c in results_doc.claims("random-cross", v)}
    assert all(verdicts.values()), verdicts
    costs["dist"] = [10.0, 11.4, 12.0]  # now no better on average: the claim must fail
    v = _variant(costs, **{"hard-attn:max_out": 9.0, "prog-retrained:max_out": 3.0})
    verdicts = {c.short: c.holds for c in results_doc.claims("random-cross", v)}
    assert not verdicts["prog-retrained better than dist"]
    assert not verdicts["det-prog-retrained has a worse max out-degree"]  # 1.0 vs 3.0


def test_unknown_placeholder_is_an_error_not_text():
    with pytest.raises(SystemExit, match="unknown placeholder"):
        results_doc.render("x {{nope 1}}", {}, {})
    with pytest.raises(SystemExit, match="KeyError"):
        results_doc.render("{{mean random-cross tf-full cost 2}}", {}, {})
