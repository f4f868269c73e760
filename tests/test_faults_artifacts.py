"""Faults and hostile input, artifacts truncated, emptied, of the wrong type, a pickle with code, non-finite numbers,
results keyed by what they are of: every bad input is one line and a non-zero exit, and no result is lost
silently. docs/reliability.md lists the promises and what tests each; the other classes of fault are the other
tests/test_faults_*.py files (shared helpers: tests/fault_helpers.py)."""

import os

import pytest

from fault_helpers import one_line_error, run
from neurosym_cli.utils.io import ArtifactError, read_json, write_text


# ------------------------------------------------------------------------------------------ artifacts
@pytest.mark.parametrize("content", [b"", b"{", b"[1, 2]", b'{"label": 3}', b"\xff\xfe", None])
def test_malformed_metrics_are_one_line(tmp_path, content):
    from neurosym_cli.seeds import from_run_dir
    from neurosym_cli.stages.results import collect

    f = tmp_path / "eval" / "tf-full" / "metrics.json"
    if content is None:
        f.mkdir(parents=True)  # a directory where the file should be
    else:
        f.parent.mkdir(parents=True)
        f.write_bytes(content)
    with pytest.raises(ArtifactError):
        collect(tmp_path)
    with pytest.raises(ArtifactError):
        from_run_dir(tmp_path)  # the same file read across training seeds (`neurosym report`)


def test_read_json_maps_every_failure_to_one_error(tmp_path):
    for content in (b"", b"\xff", b"{]"):
        (tmp_path / "x.json").write_bytes(content)
        with pytest.raises(ArtifactError, match="cannot read"):
            read_json(tmp_path / "x.json")
    with pytest.raises(ArtifactError):
        read_json(tmp_path)


@pytest.mark.parametrize("content", [b"", b"not a checkpoint", b"PK\x03\x04" + b"\x00" * 100, None])
def test_corrupt_torch_files_are_artifact_errors(tmp_path, content):
    from neurosym_cli.run.checkpoints import load_checkpoint

    f = tmp_path / "model.pt"
    if content is None:
        f.mkdir()
    else:
        f.write_bytes(content)
    with pytest.raises(ArtifactError, match="model.pt"):
        load_checkpoint(f, "neurosym train ...")


def test_a_pickle_with_code_is_refused(tmp_path):
    """Checkpoints load with weights_only=True: a pickle that would run code on load is a corrupt file."""
    import pickle

    from neurosym_cli.run.checkpoints import load_checkpoint

    class Boom:
        def __reduce__(self):
            return (os.system, ("echo pwned > " + str(tmp_path / "pwned"),))

    f = tmp_path / "model.pt"
    f.write_bytes(pickle.dumps({"format": "neurosym-policy/1", "x": Boom()}))
    with pytest.raises(ArtifactError, match="corrupt"):
        load_checkpoint(f, "neurosym train ...")
    assert not (tmp_path / "pwned").exists()


def test_writes_follow_the_umask(tmp_path):
    write_text(tmp_path / "a.txt", "x")
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o666 & ~mask


def test_writing_under_a_file_is_an_artifact_error(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(ArtifactError, match="cannot write"):
        write_text(tmp_path / "f" / "x.json", "{}")


def test_other_corrupt_artifacts(tmp_path):
    """A corrupt tree is one line naming overwrite=true; a corrupt dataset is collected again; a corrupt
    training history counts as no time."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.run.models import baseline_comm
    from neurosym_cli.stages.pipeline import _trained_seconds

    cfg = compose_config("eval", ["baseline=dt", "budget=tiny", f"runs_root={tmp_path}"])
    tree = tmp_path / "random-cross/tiny/seed0/synth/dt-k5-v1/tree.json"
    tree.parent.mkdir(parents=True)
    for content in ('{"rounds": [{"left": 1}]}', '{"rounds": 3}', "[]"):
        tree.write_text(content)
        with pytest.raises(ArtifactError, match="overwrite=true"):
            baseline_comm(cfg)
    (tmp_path / "history.csv").write_text("step,loss\n1,2\n")  # no seconds column
    assert _trained_seconds(tmp_path / "history.csv") == 0.0


def test_corrupt_dataset_is_collected_again(tmp_path):
    import torch

    from neurosym_cli.config import ModelConfig
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.synth.dataset import load_or_collect

    env = make_task(CrossConfig(name="c", horizon=4))
    pol = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig())
    path = tmp_path / "dataset.pt"
    path.write_bytes(b"\x80\x04garbage")
    data = load_or_collect(path, "neurosym synth", env, pol, rollouts=2, stride=2,
                           gen=torch.Generator().manual_seed(0), device=torch.device("cpu"))
    assert data and sum(b.states for b in data) == 2 * 2  # 2 rollouts, every 2nd of 4 steps
    again = load_or_collect(path, "neurosym synth", env, pol, rollouts=2, stride=2,
                            gen=torch.Generator().manual_seed(5), device=torch.device("cpu"))
    assert torch.equal(again[0].target, data[0].target)  # reused, not collected with the other generator


# ------------------------------------------------------------------------------------------ no NaN is a result
@pytest.mark.parametrize("args,needle", [
    (["optim.lr=1e6"], "training diverged at step"),
    (["task.dt=1e30"], "task.dt must lie in"),
    (["task.v_max=1e308"], "task.v_max must lie in"),
    (["lam=inf"], "lam must be a finite number"),
    (["synth.temperature=nan"], "synth.temperature must be a finite number"),
    (["optim.retrain_lr=inf"], "optim.retrain_lr must be a finite number"),
])
def test_a_diverging_or_non_finite_run_is_one_line_and_never_trained(tmp_path, args, needle):
    import torch

    p = run(["train", "budget=tiny", *args], tmp_path, check=False)
    one_line_error(p, needle)
    for ckpt in tmp_path.rglob("model.pt"):  # what a diverged run keeps is finite and not marked trained
        payload = torch.load(ckpt, weights_only=True)
        assert not payload["done"] and all(torch.isfinite(t).all() for t in payload["state_dict"].values())


def test_a_checkpoint_with_non_finite_weights_is_refused(tmp_path):
    """A NaN checkpoint (as a diverged training saved before this check) is refused by eval, synth and resume."""
    import torch

    run(["train", "budget=tiny"], tmp_path)
    ckpt = tmp_path / "random-cross/tiny/seed0/train/oracle/model.pt"
    payload = torch.load(ckpt, weights_only=True)
    next(iter(payload["state_dict"].values())).fill_(float("nan"))
    torch.save(payload, ckpt)
    for verb in (["eval", "baseline=tf-full"], ["synth"], ["train", "budget.train_rollouts=16"]):
        one_line_error(run([*verb, "budget=tiny"], tmp_path, check=False), "non-finite weights")
    assert not (tmp_path / "random-cross/tiny/seed0/eval/tf-full/metrics.json").exists()


# ------------------------------------------------------------------------------------------ keyed results
def test_an_evaluation_is_of_the_condition_and_baseline_it_names(tmp_path):
    """eval refuses an option its baseline ignores (program= for tf-full) and a task condition other than the
    model's training (it would replace the trained condition's metrics); protocol keys may differ."""
    common = ["task=random-grid", "budget=tiny", "plots=false"]
    run(["train", *common], tmp_path)
    run(["eval", *common, "baseline=tf-full"], tmp_path)
    metrics = tmp_path / "random-grid/tiny/seed0/eval/tf-full/metrics.json"
    before = metrics.read_bytes()
    mine = tmp_path / "mine.txt"
    mine.write_text("random(filter(true, l))\nrandom(filter(true, l))\n")
    one_line_error(run(["eval", *common, "baseline=tf-full", f"program={mine}"], tmp_path, check=False),
                   "program= is for the baselines that run under a program")
    p = run(["eval", *common, "baseline=tf-full", "task.noise_std=0.5"], tmp_path, check=False)
    one_line_error(p, "was trained with task.noise_std=0.05, this run has 0.5")
    assert metrics.read_bytes() == before
    # resuming under another condition names the key too (the same comparison)
    one_line_error(run(["train", *common, "task.noise_std=0.5", "budget.train_rollouts=16"], tmp_path, check=False),
                   "was trained with task.noise_std=0.05")
    run(["eval", *common, "baseline=tf-full", "task.eval_episodes=2"], tmp_path)  # the protocol, not the condition
