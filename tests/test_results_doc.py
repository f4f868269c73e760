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


def _spec(**over):
    fields = dict(family="formation", name="x below y", quantity="paired", a="x", b="y", test="ci_below",
                  threshold=0.0, paper="x has a lower loss than y", source="Figure 2", unit="loss difference x - y",
                  long="x below y: {a:.2f} vs {b:.2f} (paired difference {d0:+.2f} ± {d1:.2f}){weak}",
                  cell="{d0:+.2f}{ns}", weak="lower on average")
    return results_doc.ClaimSpec(**{**fields, **over})


def test_a_claim_record_holds_or_fails_by_its_test_and_threshold():
    spec = _spec()
    c = results_doc.evaluate(spec, _variant({"x": [1.0, 2.0, 3.0], "y": [2.0, 3.1, 3.9]}))
    assert c.holds and c.value == pytest.approx(-1.0) and c.name == "x below y"
    assert c.cell == "−1.00" and c.long.startswith("x below y: 2.00 vs 3.00 (paired difference -1.00 ± ")
    # lower on average, but the 95 % interval of the paired difference crosses 0: fails, and says why
    c = results_doc.evaluate(spec, _variant({"x": [1.0, 2.0, 3.0], "y": [1.5, 1.9, 3.2]}))
    assert not c.holds and c.value == pytest.approx(-0.2)
    assert c.long.endswith(" (lower on average, not significant)") and c.cell == "−0.20, not significant"
    # the same numbers against a threshold on the mean alone (a `below` test) hold; a stricter threshold fails
    assert results_doc.evaluate(_spec(test="below"), _variant({"x": [1.0, 2.0, 3.0], "y": [1.5, 1.9, 3.2]})).holds
    gap = _spec(quantity="gap", test="abs_at_most", threshold=5.0, cell="{q:+.1f} %")
    near, far = _variant({"x": [10.2, 10.2], "y": [10.0, 10.0]}), _variant({"x": [11.0, 11.0], "y": [10.0, 10.0]})
    assert results_doc.evaluate(gap, near).cell == "+2.0 %" and results_doc.evaluate(gap, near).holds
    assert not results_doc.evaluate(gap, far).holds and results_doc.evaluate(gap, far).value == pytest.approx(10.0)
    with pytest.raises(KeyError, match="y"):  # a baseline the numbers lack is named (the seed tables say so)
        results_doc.evaluate(spec, _variant({"x": [1.0, 2.0]}))
    with pytest.raises(ValueError, match="test 'most'"):
        _spec(test="most")


def test_the_paper_claims_are_records_with_their_source():
    from benchmarks.results.claims import load

    specs = load()
    families = {s.family for s in specs}
    assert families == {"formation", "unlabeled-goals", "appendix-d", "appendix-e", "vmas"}
    for fam in families:  # a claim's name is its row: unique within its family
        names = [s.name for s in specs if s.family == fam]
        assert len(set(names)) == len(names), fam
    assert sum(s.family in ("formation", "unlabeled-goals") for s in specs) == 10
    assert all(s.paper and any(w in s.source for w in ("Figure", "Table", "Appendix")) for s in specs)
    assert next(s for s in specs if "4.13" in s.name).threshold == pytest.approx(0.9 * 4.13)


def test_claim_records_of_the_appendices_read_optional_baselines_second_tests_and_named_numbers():
    # requires: a claim on a baseline a run may lack is checked only where it is there
    opt = _spec(requires=("z",), b="z", long="x below {b_label}: {d_pm}{weak}", digits=3)
    assert not opt.applies(_variant({"x": [1.0, 2.0]}))
    v = _variant({"x": [1.0, 2.0, 3.0], "z": [2.0, 3.1, 3.9]})
    c = results_doc.evaluate(opt, v)
    assert opt.applies(v) and c.holds and c.long == "x below z: −1.000 ± " + c.long.split(" ± ")[1]
    # also: the loss gap holds, but the second test (a lower degree) fails, and so does the claim
    gap = _spec(quantity="gap", test="abs_at_most", threshold=5.0, metrics=("cost", "max_degree"),
                also=results_doc.Condition(quantity="diff", test="below", threshold=0.0, metrics=("max_degree",)),
                long="{q:+.1f} % at {a_max_degree:.0f} vs {b_max_degree:.0f}")
    near = {"x": [10.2, 10.2], "y": [10.0, 10.0]}
    assert results_doc.evaluate(gap, _variant(near, **{"x:max_degree": 3.0, "y:max_degree": 4.0})).holds
    c = results_doc.evaluate(gap, _variant(near, **{"x:max_degree": 5.0, "y:max_degree": 4.0}))
    assert not c.holds and c.long == "+2.0 % at 5 vs 4"
    # dominated: how many of `among` are at most b's on every metric, named after the verdict when any is
    dom = _spec(quantity="dominated", a="", among=("p", "q"), b="y", metrics=("cost", "max_degree"), test="below",
                threshold=1.0, long="neither beats y", after=" ({who} does)", cell="")
    v = _variant({"p": [1.0, 1.0], "q": [5.0, 5.0], "y": [2.0, 2.0]}, **{"p:max_degree": 2.0, "y:max_degree": 3.0})
    c = results_doc.evaluate(dom, v)
    assert not c.holds and c.value == 1 and c.after == " (p does)"
    v = _variant({"p": [1.0, 1.0], "q": [5.0, 5.0], "y": [2.0, 2.0]}, **{"p:max_degree": 4.0, "y:max_degree": 3.0})
    assert results_doc.evaluate(dom, v).holds and results_doc.evaluate(dom, v).after == ""
    # value: a number the section computes, tested by equality, with words after a failure
    k = _spec(quantity="value", a="", b="", field="k", test="equals", threshold=4.0, long="K = {k} on {where}",
              after="; {k} against {other}", cell="")
    assert results_doc.evaluate(k, _variant({}), {"k": 4, "where": "noisy", "other": 2}).holds
    c = results_doc.evaluate(k, _variant({}), {"k": 5, "where": "noisy", "other": 2})
    assert not c.holds and c.long == "K = 5 on noisy" and c.after == "; 5 against 2"
    with pytest.raises(ValueError, match="among goes with quantity dominated"):
        _spec(quantity="dominated", a="")



def test_the_paper_tasks_under_the_defaults_mark_a_claim_lost(tmp_path):
    """benchmarks/results/paper_defaults.py: a defaults seed file equal to the paper method's loses nothing; one
    whose prog-retrained is 50 % worse loses 'close to tf-full' on that seed and says so."""
    import json

    from benchmarks.results.paper_defaults import paper_defaults

    src = json.loads((ROOT / "docs/results/seeds/random-grid-seed0.json").read_text())
    (tmp_path / "random-grid-seed0.json").write_text(json.dumps(src))
    page = paper_defaults(tmp_path)
    rows = [ln for ln in page.split("### random-grid")[1].split("###")[0].splitlines() if ln.startswith("| ")]
    assert len(rows) > 3 and all(ln.endswith("| no |") for ln in rows[1:]), rows
    assert "Not yet run under the defaults" in page.split("### random-grid")[0]  # random-cross: no file
    for row in src["baselines"]["prog-retrained"]["per_seed"]:
        row["cost"] *= 1.5
    (tmp_path / "random-grid-seed0.json").write_text(json.dumps(src))
    page = paper_defaults(tmp_path)
    lost = [ln for ln in page.splitlines() if ln.endswith("| **yes** |")]
    assert any("close to tf-full" in ln for ln in lost), lost
