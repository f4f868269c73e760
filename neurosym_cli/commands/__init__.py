"""One module per verb, each a thin edge: typed config in, one library call (``stages/``), output. This package is
the only layer that sees Hydra; importing it imports nothing heavy."""

COMMANDS: dict[str, tuple[str, str]] = {
    "train": ("train", "train the transformer oracle (or a baseline's own model) by backprop through the dynamics"),
    "eval": ("eval", "evaluate a baseline over seeds: loss, max in, max out, max in+out, mean in+out, collisions"),
    "synth": ("synth", "synthesize a communication program by MCMC (paper sections 3.2, 3.4), or a tree (dt)"),
    "retrain": ("retrain", "fine-tune the oracle under a synthesized program or tree (paper section 3.5)"),
    "show-program": ("show_program", "print a synthesized program in the paper's notation, with its reading"),
    "pipeline": ("pipeline", "every stage for every baseline (train, synth, retrain, eval), then the results table"),
    "select": ("select", "the paper's model selection: a grid of programs, validation seeds, retrained finalists, "
                         "one pick"),
    "tune": ("tune", "select by an Optuna study over lam, K, features and the retraining rate: resumable, shared "
                     "by many processes, pruned"),
    "stress": ("stress", "trained baselines zero-shot at other team sizes (task=swarm: up to 10,000 agents) and under link failure"),
    "rl": ("rl", "appendix D: whom to hear as actions, by policy gradient over a grid; picks rl1 and rl2"),
    "report": ("report", "one table, plots, training curves and the loss-degree Pareto front over training seeds"),
    "render": ("render", "one evaluation episode of a baseline as an animation (GIF/MP4) and a picture"),
    "export": ("export", "a baseline's program as JSON, Python and C, its policy as TorchScript, torch.export (.pt2) "
                         "and ONNX, golden vectors; --check replays them without neurosym"),
    "figures": ("figures", "the paper's figures 1, 3, 4, 5 from a run directory: attention, paths, rule regions"),
}
"""command-line name -> (module and primary config name, one-line help)"""

_RUN = ("seed", "runs_root", "device", "threads", "cpu_kernels", "compile", "progress")
"""what every command that runs models reads"""
USES: dict[str, tuple[str, ...]] = {
    "train": ("task", "budget", "baseline", "rules", *_RUN, "overwrite", "logger", "model", "optim", "rl"),
    "eval": ("task", "budget", "baseline", "rules", "lam", "features", "program", "selected", *_RUN, "plots",
             "logger", "synth", "rl"),
    "synth": ("task", "budget", "baseline", "rules", "lam", "features", "selected", *_RUN, "overwrite", "logger",
              "synth"),
    "retrain": ("task", "budget", "baseline", "rules", "lam", "features", "program", "selected", *_RUN, "overwrite",
                "logger", "optim", "synth"),
    "show-program": ("task", "budget", "baseline", "rules", "lam", "features", "program", "selected", "seed",
                     "runs_root", "synth"),
    "pipeline": ("task", "budget", "baselines", "rules", "lam", "features", "program", "selected", *_RUN, "overwrite", "logger",
                 "plots", "model", "optim", "synth", "select", "rl", "render", "pipeline"),
    "select": ("task", "budget", *_RUN, "overwrite", "logger", "select", "synth", "optim"),
    "tune": ("task", "budget", *_RUN, "overwrite", "logger", "tune", "synth", "optim"),
    "stress": ("task", "budget", "rules", "lam", "features", "selected", *_RUN, "plots", "stress", "synth"),
    "rl": ("task", "budget", *_RUN, "overwrite", "logger", "plots", "rl", "model", "optim"),
    "report": ("task=", "budget=", "report_dir", "runs_root", "plots", "report"),
    "render": ("task", "budget", "baseline", "rules", "lam", "features", "program", "selected", "episode", *_RUN,
               "render", "synth"),
    "export": ("task", "budget", "baseline", "rules", "lam", "features", "program", "selected", *_RUN, "export",
               "synth"),
    "figures": ("task", "budget", "rules", "lam", "features", "selected", "episode", *_RUN, "render", "synth"),
}
"""command-line name -> the config groups, top-level keys and sections it reads (what `neurosym <command> --help`
shows; `--cfg job` prints the whole composed config); ``group=``: the group's choice only, not its settings"""
