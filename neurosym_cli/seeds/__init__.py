"""Training seeds as the runs: the evaluations of one task over its training seeds, and their statistics.

Read from run directories (``<root>/seed*/eval/*/metrics.json``, what `neurosym pipeline -m seed=0,1,2` leaves) or
from the committed seed files (``docs/results/seeds/<task>-seed<S>.json``, written by benchmarks/run_seeds.py).
Per baseline and metric, each training seed contributes ONE number, its model's mean over the evaluation seeds;
across those numbers: the mean with its Student-t 95 % interval and the IQM with its stratified bootstrap interval
(stats.py, rliable's definitions); per pair of baselines the probability of improvement on the loss. A single
training seed is reported as such: no interval across one seed. Seeds whose settings differ (budget, task, K,
lambda, features, search settings...) are refused, naming the first differing key, unless mixing is asked for;
K, lambda, features and search settings picked per seed by `neurosym select` are the method's outcome and may
differ. stdlib and numpy only (no torch): the results page is rendered from these.
"""

from .figures import draw, normalized, plane
from .read import (IGNORED, METHOD, METRICS, PAIRS, PICKED, SHARED, Entry, SeedRun, check_same, flatten, from_run_dir,
                   from_runs_root, from_seed_file, from_seed_files)
from .summary import (Summary, caption, csv_rows, fmt_iqm, fmt_mean, fmt_p, improvement_rows, marl_eval, order,
                      step_count, summarize)

__all__ = ["IGNORED", "METHOD", "METRICS", "PAIRS", "PICKED", "SHARED", "Entry", "SeedRun", "Summary", "caption",
           "check_same", "csv_rows", "draw", "flatten", "fmt_iqm", "fmt_mean", "fmt_p", "from_run_dir",
           "from_runs_root", "from_seed_file", "from_seed_files", "improvement_rows", "marl_eval", "normalized",
           "order", "plane", "step_count", "summarize"]
