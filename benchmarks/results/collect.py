"""The run directories' artifacts -> the small result files of docs/results/ (what the page is rendered from)."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

from neurosym_cli.run.layout import ORACLE_DIR, RunFolder, episode_stem
from neurosym_cli.schemes.searched import program_tag, tag_prefixes

from .files import FIGURES, KEEP_SELECT, METRICS, RESULTS, TRAINING, VARIANTS, entry, has_program, write


def collect(root: Path, budget: str = "paper", seed: int = 0) -> None:
    """The artifacts of the paper protocol under ``root`` -> one small JSON file per variant, and run.json."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    for name, (task, lam, objective) in VARIANTS.items():
        exp = RunFolder(root / task / budget / f"seed{seed}")
        out: dict = {"task": task, "objective": objective, "baselines": {}, "programs": {}}
        tags: set[str] = set()  # the programs evaluated here (their tags as schemes/searched.py names them)
        for f in exp.metrics_files():
            m = json.loads(f.read_text())
            c = m["config"]
            if has_program(m):
                if (c["lam"] != (c["task"]["lam"] if lam is None else lam) or c["synth"]["objective"] != objective
                        or not c["synth"].get("own_scores", True) or c.get("program")):
                    continue  # another variant's programs, or a hand-written one
                out["lam"], out["rules"], out["features"] = c["lam"], c["rules"], c["features"]
                tags.add(program_tag(rules=c["rules"], lam=c["lam"], features=c["features"], synth=c["synth"]))
            out["baselines"][m["baseline"]] = entry(m)
            out["seeds"] = m["seeds"]
        if "lam" not in out:
            print(f"no program evaluations for {name} under {exp.root}; skipped", file=sys.stderr)
            continue
        named = {prefix + tag for prefix in tag_prefixes() for tag in tags}  # prog's and det-prog's
        for p in exp.programs():
            if p.parent.name in named:
                out["programs"][p.parent.name] = p.read_text().strip()
        timing = exp.timings_file
        if name == task and timing.exists():
            out["timings"] = json.loads(timing.read_text())
        write(RESULTS / f"{name}.json", out)
        print(f"wrote {RESULTS / (name + '.json')}: {len(out['baselines'])} baselines")
    logs = root / "logs" / "paper"
    run = {}
    if (logs / "jobs.json").exists():
        jobs = json.loads((logs / "jobs.json").read_text())
        run["wall_min"] = jobs["wall_s"] / 60
        run["worker_min"] = sum(s or 0 for s in jobs["stages"].values()) / 60
    if (logs / "followups.json").exists():
        fol = json.loads((logs / "followups.json").read_text())
        run["followups_min"] = max(v["seconds"] for v in fol.values()) / 60
    write(RESULTS / "run.json", run)


def collect_select(exp: Path) -> None:
    """<exp>/select/selection.json (and the pick's test evaluations) -> docs/results/select-<task>.json."""
    run = RunFolder(exp)
    sel = json.loads(run.selection_file().read_text())
    keep = (*KEEP_SELECT, "search_seconds")
    out = {k: sel[k] for k in ("task", "name", "rules", "lam", "features", "synth", "val_seeds", "grid",
                               "finalists", "seconds", "jobs", "rule")}
    out["programs"] = [{k: r.get(k) for k in keep} for r in sel["programs"]]
    out["retrained"] = [{k: r.get(k) for k in ("name", "loss", "degree", "max_in", "max_out")}
                        for r in sel["retrained"]]
    out["test"] = {}
    for f in run.metrics_files(f"*-{sel['name']}"):
        m = json.loads(f.read_text())
        out["test"][m["baseline"]] = entry(m)
    out["program"] = run.synthesized_as(sel["name"]).read_text().strip()
    path = RESULTS / f"select-{sel['task']}.json"
    write(path, out)
    print(f"wrote {path}")


def collect_stress(exp: Path) -> None:
    """<exp>/stress/stress.json -> docs/results/stress-<task>.json (without the config)."""
    st = json.loads(RunFolder(exp).stress_file().read_text())
    cfg = st.pop("config")
    st.update(budget=cfg["budget"]["name"], seed=cfg["seed"], rules=cfg["rules"], lam=cfg["lam"],
              features=cfg["features"])
    path = RESULTS / f"stress-{st['task']}.json"
    write(path, st)
    print(f"wrote {path}")


def collect_rl(exp: Path) -> None:
    """<exp>/rl/grid.json, the picks' test evaluations and the training manifests -> docs/results/rl-<task>.json."""
    run = RunFolder(exp)
    grid = json.loads(run.rl_grid_file().read_text())
    out = {k: grid[k] for k in ("task", "budget", "seed", "val_seeds", "rl1", "rl2", "rule", "settings", "seconds",
                                "jobs")}
    out["test"] = {}
    for label in ("rl1", "rl2"):
        m = json.loads(run.metrics_of(label).read_text())
        out["test"][label] = entry({**m, "label": label}, setting=grid[label]["name"])
    out["extra"] = {}  # rl models evaluated outside the grid (a setting from scratch, too costly for the grid)
    names = {s["name"] for s in grid["settings"]}
    for f in run.metrics_files("rl-*"):
        m = json.loads(f.read_text())
        if m["label"] in names:
            continue
        man = json.loads(run.manifest_of(m["label"]).read_text())
        out["extra"][m["label"]] = entry(m, training={k: man[k] for k in TRAINING})
    oracle = json.loads(run.manifest_of(ORACLE_DIR).read_text())
    out["oracle_training"] = {k: oracle[k] for k in TRAINING}
    path = RESULTS / f"rl-{grid['task']}.json"
    write(path, out)
    print(f"wrote {path}")


def collect_noisy(exp: Path) -> None:
    """Appendix E: every test evaluation of a link-failure run directory (where `neurosym pipeline selected=true`
    ran) -> docs/results/<task>.json, the variant format, programs of the selected configuration only."""
    run = RunFolder(exp)
    sel = json.loads(run.selected_file.read_text())
    out: dict = {"task": sel["task"], "objective": "paper", "baselines": {}, "programs": {}, "rules": sel["rules"],
                 "lam": sel["lam"], "features": sel["features"]}
    for f in run.metrics_files():
        m = json.loads(f.read_text())
        if has_program(m) and not m["label"].endswith("-" + sel["name"]):
            continue  # programs of other configurations
        out["baselines"][m["baseline"]] = entry(m)
        out["seeds"] = m["seeds"]
        out["link_failure"] = m["config"]["task"]["link_failure"]
    out["programs"][sel["name"]] = run.synthesized_as(sel["name"]).read_text().strip()
    path = RESULTS / f"{sel['task']}.json"
    write(path, out)
    print(f"wrote {path}: {len(out['baselines'])} baselines")


VMAS_METRICS = METRICS + ("on_goal", "covered", "success")
VMAS_SEARCH = "lam=0.5 synth.objective=paper"
"""the search of the committed VMAS runs: the paper's objective at lambda-tilde 0.5 (their task YAMLs set it then;
today a task without its own gets synth.objective=scaled at 0.25), so every command reaching their programs names it"""
VMAS_COMMAND = ("neurosym pipeline task={task} budget=vmas threads=1 plots=false " + VMAS_SEARCH + " "
                "\"baselines=[tf-full,hard-attn,dist,prog,prog-retrained,expo,comm-range,no-comm]\" "
                "baseline=comm-range baseline.radius=0.5")
"""the command whose run a VMAS result file holds (docs/vmas.md, 'Results')"""


def collect_vmas(exp: Path, wall: float | None = None) -> None:
    """A VMAS scenario's run directory (docs/vmas.md, 'Results') -> docs/results/vmas-<scenario>.json: every
    baseline's summary (mean, std, 95 % t half-width over the evaluation seeds) and per-seed losses, the program,
    each trained model's training (loss every 10 steps, seconds), the stage times and the measured wall time."""
    run = RunFolder(exp)
    out: dict = {"baselines": {}, "training": {}}
    for f in run.metrics_files():
        m = json.loads(f.read_text())
        c = m["config"]
        out.update(task=f"vmas/{c['task']['name'].removeprefix('vmas-')}", seeds=m["seeds"],
                   episodes_per_seed=m["episodes_per_seed"], training_seed=c["seed"], budget=c["budget"],
                   horizon=c["task"]["horizon"], comm_range_radius=0.5)
        out["baselines"][m["baseline"]] = entry(m, metrics=VMAS_METRICS, stats=("mean", "std", "ci95"),
                                                optional=True)
        if has_program(m):
            out["program"] = run.synthesized_as(m["label"].removeprefix(m["baseline"] + "-")).read_text().strip()
    for f in run.manifests():
        man = json.loads(f.read_text())
        with open(run.history_of(f.parent.name)) as h:
            losses = [float(r["loss"]) for r in csv.DictReader(h)]
        out["training"][f.parent.name] = {
            "steps": len(losses), "rollouts": man["rollouts"], "seconds": round(man["seconds_this_run"], 1),
            "loss_every_10_steps": [round(sum(losses[i:i + 10]) / len(losses[i:i + 10]), 3)
                                    for i in range(0, len(losses), 10)]}
    out["command"] = VMAS_COMMAND.format(task=out["task"])
    out["stage_seconds"] = json.loads(run.timings_file.read_text())
    if wall is not None:
        out["wall_seconds"] = wall
    path = RESULTS / f"vmas-{out['task'].split('/')[-1]}.json"
    write(path, out)
    print(f"wrote {path}: {len(out['baselines'])} baselines")
    heard = {e["label"]: e["summary"]["max_in"]["mean"] for e in out["baselines"].values()}
    stem = episode_stem(0)
    for gif in run.renders(stem):  # what `neurosym render ... episode=0` drew
        if heard.get(gif.parent.name):  # an episode without edges says nothing about whom agents hear
            vmas_episode_figures(gif, FIGURES / f"{path.stem}-{gif.parent.name}-{stem}")


def vmas_episode_figures(gif: Path, stem: Path, frames: int = 4) -> None:
    """`neurosym render`'s animation -> <stem>.gif (a copy) and <stem>.png: ``frames`` of its frames in a 2-column
    grid (the start, evenly spaced steps, the end), each with the edges used at that step."""
    import shutil

    from PIL import Image

    gif_out, png_out = Path(f"{stem}.gif"), Path(f"{stem}.png")  # labels hold dots (lam0.5): no with_suffix
    shutil.copyfile(gif, gif_out)
    with Image.open(gif) as im:
        picks = [round(k * (im.n_frames - 1) / (frames - 1)) for k in range(frames)]
        shots = []
        for k in picks:
            im.seek(k)
            shots.append(im.convert("RGB"))
    w, h, cols = max(x.width for x in shots), max(x.height for x in shots), 2  # a 2-column grid stays readable
    grid = Image.new("RGB", (cols * w, -(-len(shots) // cols) * h), "white")
    for k, x in enumerate(shots):
        grid.paste(x, ((k % cols) * w, (k // cols) * h))
    grid.save(png_out)
    print(f"drew {png_out} (frames {picks} of {gif})")
