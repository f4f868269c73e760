"""One module per verb, each a thin edge: typed config in, one library call (``stages/``), output. This package is
the only layer that sees Hydra; importing it imports nothing heavy."""

COMMANDS: dict[str, tuple[str, str]] = {
    "train": ("train", "train the transformer oracle (or a baseline's own model) by backprop through the dynamics"),
    "eval": ("eval", "evaluate a baseline over seeds: loss, max in/out-degree, mean degree, collisions"),
    "synth": ("synth", "synthesize a communication program by MCMC (paper sections 3.2, 3.4), or a tree (dt)"),
    "retrain": ("retrain", "fine-tune the oracle under a synthesized program or tree (paper section 3.5)"),
    "show-program": ("show_program", "print a synthesized program in the paper's notation, with its reading"),
    "pipeline": ("pipeline", "every stage for every baseline (train, synth, retrain, eval), then the results table"),
    "select": ("select", "the paper's model selection: a grid of programs, validation seeds, retrained finalists, "
                         "one pick"),
    "stress": ("stress", "trained baselines zero-shot at other team sizes (up to 160 agents) and under link failure"),
    "rl": ("rl", "appendix D: whom to hear as actions, by policy gradient over a grid; picks rl1 and rl2"),
    "report": ("report", "one table, plots, training curves and the loss-degree Pareto front over training seeds"),
    "render": ("render", "one evaluation episode of a baseline as an animation (GIF/MP4) and a picture"),
    "export": ("export", "a baseline's program as JSON, Python and C, its policy as TorchScript and ONNX, golden "
                         "vectors; --check replays them without neurosym"),
    "figures": ("figures", "the paper's figures 1, 3, 4, 5 from a run directory: attention, paths, rule regions"),
}
"""command-line name -> (module and primary config name, one-line help)"""
