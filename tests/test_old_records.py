"""Run directories made before a task stated its search objective (issue 37 added ``task.objective``) stay usable:
the objective and lambda set the search's defaults, not what a model is trained on or evaluated under."""

import torch

from fault_helpers import EXP, TINY, run


def _drop_objective(ckpt):
    payload = torch.load(ckpt, weights_only=True)
    payload["config"]["task"].pop("objective", None)  # as a checkpoint written before the key existed
    torch.save(payload, ckpt)


def test_a_model_recorded_without_the_objective_is_evaluated_and_resumed(tmp_path):
    run(["train", *TINY, "task.objective=scaled"], tmp_path)
    ckpt = tmp_path / EXP / "train" / "oracle" / "model.pt"
    _drop_objective(ckpt)  # now it reads as the schema's default, which the task (random-grid: paper) differs from
    p = run(["eval", *TINY, "baseline=tf-full"], tmp_path, check=False)
    assert p.returncode == 0, p.stderr
    p = run(["train", *TINY, "budget.train_rollouts=16"], tmp_path, check=False)  # extends the same model
    assert p.returncode == 0 and "was trained with" not in p.stderr, p.stderr
