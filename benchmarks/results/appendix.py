"""The sections beyond paper section 4: `neurosym rl` (appendix D), link failure (appendix E), VMAS scenarios."""

from __future__ import annotations

from neurosym_cli.dsl import parse

from .claims import Claim, of_family
from .collect import VMAS_SEARCH
from .figures import vmas_order
from .files import DOCS, FIGURES, ORDER, RESULTS, read, with_selected
from .tables import EVAL_PM, gap, mean, ms, paired, pm, readings, shown, verdict


def lines(claims: list[Claim]) -> list[str]:
    """Claims as the sections list them: '- <line> -> <verdict>[<what follows a failure>]'."""
    return [f"- {c.long} -> {verdict(c.holds)}{c.after}" for c in claims]


def rl(task: str, variants: dict[str, dict]) -> str:
    """{{rl T}} (paper appendix D): the grid, the picks' test rows beside the main baselines and the selected
    program, and the paper's claims (rl-T.json)."""
    r = read(f"rl-{task}")
    v = variants[task]
    has_sel = (RESULTS / f"select-{task}.json").exists()
    vs = with_selected(v, read(f"select-{task}")) if has_sel else v
    extra = r.get("extra", {})
    vs = {**vs, "baselines": {**vs["baselines"], **r["test"], **extra}}
    which = "selected" if has_sel else "default"
    out = [f"Grid: cost weight {sorted({s['cost'] for s in r['settings']})}, reward to go or whole episode, "
           f"from {sorted({s['init'] for s in r['settings']})} ({len(r['settings'])} settings), each trained for "
           f"{r['settings'][0]['rollouts']} rollouts on the oracle of the {task} section; {r['val_seeds']} "
           f"validation seeds; {r['jobs']} setting(s) trained at a time.", "",
           "| setting | cost weight | reward | val loss ± 95 % | max in | max out | max in+out | rollouts/s | pick |",
           "|---|---|---|---|---|---|---|---|---|"]
    for s in sorted(r["settings"], key=lambda s: s["val_loss"]):
        out.append(f"| {s['name']} | {s['cost']:g} | {'to go' if s['shaped'] else 'episode'} | "
                   f"{s['val_loss']:.2f} ± {s['val_loss_ci']:.2f} | {s['max_in']:.2f} | {s['max_out']:.2f} | "
                   f"{s['max_degree']:.2f} | {s['rollouts_per_second']:.1f} | {s['pick']} |")
    out += ["", f"Test seeds ({v['seeds']}, the same episodes as every table of this page; {EVAL_PM}):", "",
            "| baseline | loss | max in | max out | max in+out |", "|---|---|---|---|---|"]
    rows = [b for b in ("tf-full", "hard-attn", "dist", "prog-retrained", "no-comm") if b in vs["baselines"]]
    for b in rows + ["rl1", "rl2"] + sorted(extra):
        name = f"prog-retrained ({which} program)" if b == "prog-retrained" else \
            (f"**{b}** ({r['test'][b]['setting']})" if b in r["test"] else
             (f"{b} (outside the grid)" if b in extra else b))
        out.append(f"| {name} | {ms(vs, b, 'cost')} | {ms(vs, b, 'max_in')} | {ms(vs, b, 'max_out')} | "
                   f"{ms(vs, b, 'max_degree')} |")
    out += ["", "The paper's claims (appendix D):", "", *lines(of_family("appendix-d", vs))]
    t = r["oracle_training"]
    rl_rate = sum(s["rollouts_per_second"] for s in r["settings"]) / len(r["settings"])
    out += ["", f"Cost: an rl setting trained at {rl_rate:.1f} rollouts/s (mean over the settings, {r['jobs']} "
            f"one-thread job(s) at a time), the oracle's BPTT at {t['rollouts_per_second']:.1f} rollouts/s when it "
            f"was trained (one thread, another job beside it); from the oracle, a setting is "
            f"{r['settings'][0]['rollouts']} rollouts ({sum(s['train_seconds'] for s in r['settings']) / len(r['settings']) / 60:.1f} "
            f"min), the oracle itself {t['rollouts']} ({t['seconds_this_run'] / 60:.1f} min); docs/performance.md "
            "section 11."]
    for b, e in sorted(extra.items()):
        tr = e["training"]
        out += ["", f"Outside the grid, `{b}` trained from a fresh transformer for the oracle's whole budget "
                f"({tr['rollouts']} rollouts in {tr['seconds_this_run'] / 60:.1f} min, {tr['rollouts_per_second']:.1f} "
                f"rollouts/s, final training loss {tr['final_loss']:.2f} against the oracle's "
                f"{t['final_loss']:.2f}); on the test seeds: loss {mean(vs, b):.2f} (against tf-full {pm(paired(vs, b, 'tf-full'))}, "
                f"paired) at max in+out {mean(vs, b, 'max_degree'):.2f}."]
    return "\n".join(out)


def noisy(task: str, clean: str) -> str:
    """{{noisy T C}} (appendix E): the baselines under link failure, the selection's best program per K, the
    paper's claims (the pick's K against the one ``clean``'s selection made without failures)."""
    from neurosym_cli.stages.select import choose

    v, sel, sel_clean = read(task), read(f"select-{task}"), read(f"select-{clean}")
    pr = "prog-retrained"
    out = [f"Every directed link fails with probability {v['link_failure']:g} at every step, in training, "
           f"retraining and evaluation, for every baseline. The programs are the pick of `neurosym select` on this "
           f"task's oracle (K = {sel['rules']}, lambda = {sel['lam']:g}, {sel['features']}); {v['seeds']} test "
           f"seeds; degrees count the messages delivered. Loss and degrees: {EVAL_PM}.", "",
           "| baseline | loss | max in | max out | max in+out |", "|---|---|---|---|---|"]
    for b in ORDER:
        if b in v["baselines"]:
            out.append(f"| {b} | {ms(v, b, 'cost')} | {ms(v, b, 'max_in')} | {ms(v, b, 'max_out')} | "
                       f"{ms(v, b, 'max_degree')} |")
    first = choose(sel["programs"])
    out += ["", "The selection by K: the best program of each K on the validation seeds (prog, the oracle under "
            "it), over the lambdas and feature maps of the grid:", "",
            "| K | best program | val loss ± 95 % | Δ to the best ± 95 % | max in+out | similar to the best |",
            "|---|---|---|---|---|---|"]
    for k in sorted({r["rules"] for r in first}):
        r = min((r for r in first if r["rules"] == k), key=lambda r: r["loss_mean"])
        out.append(f"| {k} | {r['name'].split('-coarse')[0]} | {r['loss_mean']:.2f} ± {r['loss_ci']:.2f} | "
                   f"{r['diff']:+.2f} ± {r['diff_ci']:.2f} | {r['degree']:.2f} | {'yes' if r['similar'] else 'no'} |")
    best = next(r for r in first if r["best"])
    text, program, said = shown(sel["program"], sel["task"], sel["features"])
    kept = len(program.rounds[0])
    out += ["", f"The selected program (searched with K = {sel['rules']}; {kept} rules left after simplification "
            "dropped those that never fire on D):", "", "```", text, "```", "", *([*said, ""] if said else [])]
    out += readings(program, sel["task"], sel["features"])
    if "no-comm" in v["baselines"]:
        def vs_none(b: str) -> str:
            return f"{gap(v, b, 'no-comm'):+.1f} %".replace("-", "−")

        out += ["", f"What communication is worth here: no-comm {mean(v, 'no-comm'):.2f}, tf-full "
                f"{vs_none('tf-full')} against it (paired {pm(paired(v, 'tf-full', 'no-comm'))}), prog-retrained "
                f"{vs_none(pr)} (paired {pm(paired(v, pr, 'no-comm'))}), hard-attn {vs_none('hard-attn')}, dist "
                f"{vs_none('dist')}."]
    picks = {"searched_k": sel["rules"], "kept": kept, "best_k": best["rules"], "clean": clean,
             "clean_k": sel_clean["rules"], "clean_kept": len(parse(sel_clean["program"]).rounds[0])}
    out += ["", "The paper's claims (appendix E):", "", *lines(of_family("appendix-e", v, picks))]
    return "\n".join(out)


def vmas(task: str) -> str:
    """{{vmas S}}: a VMAS scenario's run (docs/results/vmas-<scenario>.json, written by --collect-vmas): the table
    with the 95 % t interval over the evaluation seeds, the loss-degree figure, the program with its reading, the
    rendered episode, the training, and the paper's claims checked the same way as on its tasks."""
    name = f"vmas-{task.split('/')[-1]}"
    f = RESULTS / f"{name}.json"
    if not f.exists():
        return f"Not yet run: no result file `{f.relative_to(DOCS)}`."
    v = read(name)
    b = v["baselines"]
    extra = [m for m in ("on_goal", "covered", "success", "collisions") if m in b["tf-full"]["summary"]]
    out = [f"`{v['command']}` (training seed {v['training_seed']}; {v['seeds']} evaluation seeds of "
           f"{v['episodes_per_seed']} episodes, T = {v['horizon']}). Loss and degrees: mean ± 95 % Student-t "
           "interval over the evaluation seeds of this one trained model; the scenario's own metrics: means.", "",
           "| baseline | loss | max in | max out | " + " | ".join(extra) + " |",
           "|---|---:|---:|---:|" + "---:|" * len(extra)]
    for k in vmas_order(b):
        sm = b[k]["summary"]
        ci = lambda m: f"{sm[m]['mean']:.2f} ± {sm[m]['ci95']:.2f}"  # noqa: E731
        out.append(f"| {b[k]['label']} | {ci('cost')} | {ci('max_in')} | {ci('max_out')} | "
                   + " | ".join(f"{sm[e]['mean']:.3f}" for e in extra) + " |")
    if (FIGURES / f"{name}.png").exists():
        out += ["", f"![{task}: loss vs max in+out](figures/{name}.png)"]
    text, program, said = shown(v["program"], task, "v1")
    out += ["", "The synthesized program (`neurosym show-program` prints it as evaluated):", "", "```", text, "```", "",
            *([*said, ""] if said else [])]
    out += readings(program, task, "v1")
    labels = {b[k]["label"]: k for k in b}
    shots = [p for p in sorted(FIGURES.glob(f"{name}-*-episode0.png"))
             if p.name.removeprefix(f"{name}-").removesuffix("-episode0.png") in labels]
    if b["prog-retrained"]["summary"]["max_in"]["mean"] == 0:
        out += ["", "The program hears nobody, so an episode under prog-retrained has no edges to draw; the "
                "hard-attn episode shows whom the oracle itself picks (its K = 2 largest attention logits)."]
    for png in shots:
        label = png.name.removeprefix(f"{name}-").removesuffix("-episode0.png")
        gif = png.with_suffix(".gif")
        out += ["", f"Evaluation episode 0 under {label} at its start, two evenly spaced steps and its end, each "
                f"frame with the edges used at that step (`neurosym render task={task} budget=vmas {VMAS_SEARCH} "
                f"baseline={labels[label]} episode=0`" + (f"; animated: [{gif.name}](figures/{gif.name})"
                                                         if gif.exists() else "") + "):", "",
                f"![{task}: episode 0 under {label}](figures/{png.name})"]
    tr = v["training"]
    out += ["", "Training loss, mean over each 10 optimizer steps of 8 episodes (the same episodes for every model):",
            "", "| model | steps | seconds | loss every 10 steps |", "|---|---:|---:|---|"]
    out += [f"| {k} | {t['steps']} | {t['seconds']:.0f} | {' '.join(f'{x:.2f}' for x in t['loss_every_10_steps'])} |"
            for k, t in sorted(tr.items())]
    total = sum(v["stage_seconds"].values())
    wall = v.get("wall_seconds", total)
    verbs: dict[str, list[float]] = {}
    for stage, sec in v["stage_seconds"].items():
        verbs.setdefault(stage.split()[0], []).append(sec)
    out += ["", f"Wall time: {wall / 60:.1f} min for the pipeline on one thread of the busy 2-core machine ("
            + ", ".join(f"{verb} {sum(x):.0f} s over {len(x)} stage{'s' * (len(x) > 1)}" for verb, x in verbs.items())
            + ")."]
    return "\n".join(out + ["", "Claims of the paper, checked the same way as on its tasks (paired differences "
                             "over the evaluation seeds, 95 % t interval):", ""]
                     + vmas_claims(v))


def vmas_claims(v: dict) -> list[str]:
    """The paper's claims on a VMAS run (claims.toml, family vmas), each line with its numbers and its verdict;
    failures stay in, with why, and a last line on what they are worth when communication does not help."""
    checked = of_family("vmas", v)
    out = lines(checked)
    comm = next(c for c in checked if c.name.startswith("communication matters")).holds
    d = paired(v, "tf-full", "no-comm")
    if d[0] - d[1] > 0:
        out.append("- here hearing nobody is better than hearing everybody: at this budget the oracle has not learned "
                   "to gain from what it hears (its training loss never went below no-comm's, table above), so the "
                   "claims about the program compare sparse models against an oracle worse than silence "
                   "(docs/vmas.md, 'Results').")
    elif not comm:
        silent = v["baselines"]["prog-retrained"]["summary"]["max_in"]["mean"] == 0
        out.append("- where hearing nobody is as good as hearing everybody, the claims about the program say little "
                   "about the method" + (": the search's best program is then the silent one" if silent else "")
                   + ", and every comparison is within the noise of this small budget (docs/vmas.md, 'Results').")
    return out
