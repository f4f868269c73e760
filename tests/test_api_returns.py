"""What the Python API's train and retrain return is what their docstrings say (issue 40): the same keys for a
fresh training and for a model trained before."""

import re

import neurosym as ns
from neurosym_cli.api import TRAINED


def test_train_returns_the_keys_its_docstring_names(tmp_path):
    cfg = ns.compose("train", {"runs_root": str(tmp_path), "threads": 1, "plots": False}, task="random-cross",
                     budget="tiny")
    out = ns.train(cfg)
    assert tuple(out) == TRAINED
    assert out["checkpoint"].endswith("model.pt") and out["steps"] > 0 and out["rollouts"] > 0
    assert isinstance(out["loss"], float) and out["seconds"] > 0
    assert ns.train(cfg) == out  # already trained: the same record, read from its manifest
    documented = re.findall(r"(\w+):\s", ns.train.__doc__.split("Returns {", 1)[1].split("}", 1)[0])
    assert tuple(documented) == TRAINED
