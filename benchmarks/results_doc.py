"""docs/results.md from one template (docs/results.template.md) and the small result files beside it (docs/results/).

    python benchmarks/results_doc.py --collect   # outputs/ (the paper protocol's artifacts) -> docs/results/*.json
    python benchmarks/results_doc.py             # docs/results/*.json + the template -> docs/results.md
    python benchmarks/results_doc.py --check     # exit 1 when docs/results.md is not what the files give
    python benchmarks/results_doc.py --figures   # also redraw the Figure-2 pictures from the result files
    python benchmarks/results_doc.py --seeds DIR --out /tmp/page.md --seed-figures /tmp/figs   # preview other seeds

Every number of the document comes from the result files: one per variant of the protocol (a task, with the
lambda and objective of its programs), holding each baseline's summary (mean and std over the evaluation seeds),
its per-seed losses (for paired intervals), the synthesized programs and the stage times; and run.json (wall
times of the whole protocol). The template's placeholders, ``{{op args}}``, are looked up in a table of
functions (benchmarks/results/render.py; never evaluated as code):

    {{section V}}            the table, figure, programs, stage times and claim lines of variant V
    {{glance}}               the claims-at-a-glance tables of every variant
    {{mean V B M D}}         baseline B's mean of metric M in variant V, D digits (M: cost, max_in, max_out, ...)
    {{half V B M D}}         half of it (mean in+out / 2 = edges heard per agent and step)
    {{per V B M1 M2 D}}      mean of M1 / mean of M2
    {{paired V A B D}}       paired loss difference A - B over the evaluation seeds with its 95 % t half-width
    {{gap V A B}}            relative loss difference A vs B, in percent
    {{run KEY D}}            a figure of run.json (minutes)
    {{stress T}}             `neurosym stress` on task T: loss and degrees at other team sizes and under link failure
    {{rl T}}                 `neurosym rl` on task T (appendix D): the grid, rl1 and rl2 beside the others, the claims
    {{noisy T C}}            appendix E: link-failure task T (T.json, select-T.json) against its clean task C
    {{selection T}}          `neurosym select` on task T: the ranked table, the pick, its test numbers, the
                             paper's claims re-checked with it, the loss-degree Pareto front (select-T.json)
    {{seeds}}                every task over its training seeds (docs/results/seeds/*.json): mean ± t-interval
                             and IQM [bootstrap] per baseline, probability of improvement, claims per seed and
                             across seeds ("holds on k/n"), the loss-degree figure; "not yet run" without files
    {{seeds_glance}}         the claims at a glance over training seeds: cells "holds on k/n; mean ± t-interval"
    {{seeds_planned}}        the training seeds the protocol runs (0, 1, 2)

Loss claims use paired differences over the evaluation seeds (every baseline sees the same episodes for a seed)
with a 95 % t-interval.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

# the jobs live in benchmarks/results/ (its __init__ says which module does what); these names are the entry
# point's, and what tests/test_results_doc.py reads
from benchmarks.results.claims import Claim, ClaimSpec, Condition, claims, evaluate  # noqa: E402,F401
from benchmarks.results.collect import (collect, collect_noisy, collect_rl, collect_select,  # noqa: E402
                                        collect_stress, collect_vmas)
from benchmarks.results.figures import (draw_figures, draw_pareto, draw_seed_figures, draw_stress,  # noqa: E402
                                        draw_vmas)
from benchmarks.results.files import DOCS, FIGURES, METRICS, SEEDS, TEMPLATE, VARIANTS, load, load_seeds  # noqa: E402,F401
from benchmarks.results.render import render  # noqa: E402
from benchmarks.results.tables import paired  # noqa: E402,F401


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--collect", action="store_true", help="first write docs/results/ from the artifacts")
    ap.add_argument("--root", default=str(ROOT / "outputs"), help="runs root of the paper protocol's artifacts")
    ap.add_argument("--check", action="store_true", help="exit 1 if docs/results.md differs from the render")
    ap.add_argument("--figures", action="store_true", help="also redraw docs/figures/<task>.png from docs/results/")
    ap.add_argument("--collect-stress", default="", metavar="EXP",
                    help="first write docs/results/stress-<task>.json from a run directory where `neurosym stress` ran")
    ap.add_argument("--collect-select", default="", metavar="EXP",
                    help="first write docs/results/select-<task>.json from a run directory where `neurosym select` ran")
    ap.add_argument("--collect-rl", default="", metavar="EXP",
                    help="first write docs/results/rl-<task>.json from a run directory where `neurosym rl` ran")
    ap.add_argument("--collect-noisy", default="", metavar="EXP",
                    help="first write docs/results/<task>.json from a link-failure run directory (appendix E)")
    ap.add_argument("--collect-vmas", default="", metavar="EXP",
                    help="first write docs/results/vmas-<scenario>.json from a VMAS run directory (docs/vmas.md)")
    ap.add_argument("--wall", type=float, default=None, metavar="S",
                    help="with --collect-vmas: the measured wall seconds of the pipeline")
    ap.add_argument("--seeds", default=str(SEEDS), metavar="DIR",
                    help="the seed files to render the training-seed sections from (default docs/results/seeds)")
    ap.add_argument("--out", default="", metavar="FILE",
                    help="write the page here instead of docs/results.md (a preview; --check still reads the page)")
    ap.add_argument("--seed-figures", default="", metavar="DIR",
                    help="draw the training-seed figures from --seeds into DIR (with --figures: docs/figures)")
    a = ap.parse_args()
    if a.collect:
        collect(Path(a.root))
    if a.collect_select:
        collect_select(Path(a.collect_select))
    if a.collect_stress:
        collect_stress(Path(a.collect_stress))
    if a.collect_rl:
        collect_rl(Path(a.collect_rl))
    if a.collect_noisy:
        collect_noisy(Path(a.collect_noisy))
    if a.collect_vmas:
        collect_vmas(Path(a.collect_vmas), a.wall)
    if a.collect_vmas or a.figures:
        draw_vmas()
    if a.collect or a.figures or a.collect_select or a.collect_stress or a.collect_rl:
        draw_figures()
        for task in VARIANTS:
            draw_pareto(task)
            draw_stress(task)
    by_task = load_seeds(Path(a.seeds))
    if a.seed_figures or a.figures:
        draw_seed_figures(by_task, Path(a.seed_figures) if a.seed_figures else FIGURES)
    text = render(TEMPLATE.read_text(), *load(), by_task)
    target = Path(a.out) if a.out and not a.check else DOCS / "results.md"
    if a.check:
        if target.read_text() != text:
            print("docs/results.md is not what docs/results.template.md and docs/results/ give; "
                  "run python benchmarks/results_doc.py", file=sys.stderr)
            raise SystemExit(1)
        print("docs/results.md matches its template and result files")
        return
    target.write_text(text)
    print(f"wrote {target}")


if __name__ == "__main__":
    main()
