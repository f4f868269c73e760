"""The run directory as one object: every artifact's name (``layout``), the policy checkpoints (``checkpoints``),
the models and provider a baseline runs on (``models``), and the commands that remake an artifact (``remake``).

Only ``layout`` and ``remake`` are imported here: they are stdlib only, so light commands (`neurosym --help`,
`report`, `show-program`) need no torch; ``checkpoints`` and ``models`` are imported by what needs them.
"""

from .remake import pipeline_command, retrain_command, show_command, synth_command, train_command
from .layout import RunDir

__all__ = ["RunDir", "pipeline_command", "retrain_command", "show_command", "synth_command", "train_command"]
