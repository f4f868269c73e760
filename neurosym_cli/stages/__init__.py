"""What each verb does to a run directory, as a library: the commands in ``commands/`` parse the config, call one
of these and print; ``neurosym pipeline`` calls them in the order of the stage graph (``graph.py``).

    train.py     train or retrain a model, resuming from its checkpoint (paper sections 3.1, 3.5)
    synth.py     collect or reuse the oracle dataset D, search a program per round, or fit a tree (3.2-3.4, app. B)
    evaluate.py  the evaluation protocol for one baseline, written to eval/<label>/metrics.json (section 4)
    results.py   read every evaluation of a run directory (or of many training seeds) back, in the paper's order
    comm.py      the communication provider of a baseline, with its program or tree loaded
    pipeline.py  every stage the listed baselines need, in dependency order, pipeline.jobs at once
    flow.py      the scheduler under it: a dependency graph of jobs, run in worker processes or in this one
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class RunInfo:
    """What a stage needs to know about the command that runs it, besides its typed config (which is the only
    config: what is saved beside an artifact is ``RunConfig.record()`` of the config that made it)."""

    multirun: bool = False
    """part of a sweep or of the pipeline: plain log lines, no intermediate tables"""
    log_dir: str = ""
    """the command's log directory (Hydra's output directory of this job)"""
