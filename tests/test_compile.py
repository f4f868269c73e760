"""compile=auto|on|fused|off (utils/compiling.py, step.py, policy/edge_kernels.py): the compiled step and the fused
kernels give eager's losses and gradients up to float rounding on the paper's tasks, fall back to the eager step in one line where it cannot compile, is recorded
in every artifact's runtime, and a resume under another compile mode is refused."""

import pytest
import torch

from neurosym_cli import step as stepmod
from neurosym_cli.config import ConfigError, ModelConfig, RunConfig
from neurosym_cli.policy import CommTransformer
from neurosym_cli.policy import edge_kernels
from neurosym_cli.policy.comm import CommBase, FullComm, NearestComm
from neurosym_cli.rollout import rollout
from neurosym_cli.run.checkpoints import refuse_other_modes
from neurosym_cli.tasks import make_task
from neurosym_cli.tasks.base import Rng
from neurosym_cli.tasks.random_cross import CrossConfig
from neurosym_cli.tasks.random_grid import GridConfig
from neurosym_cli.tasks.swarm import SwarmConfig
from neurosym_cli.tasks.unlabeled_goals import UnlabeledConfig
from neurosym_cli.utils import compiling
from neurosym_cli.utils.cpu import runtime

TASKS = {"random-cross": lambda: CrossConfig(name="random-cross"),
         "two-groups-cross": lambda: CrossConfig(name="two-groups-cross", num_groups=2),
         "random-grid": lambda: GridConfig(name="random-grid"),
         "unlabeled-goals": lambda: UnlabeledConfig(name="unlabeled-goals"),
         "swarm": lambda: SwarmConfig(name="swarm", agents_per_group=6),
         "ring": lambda: _ring()}
"""the paper's four tasks, the swarm (a small one: the dense path) and the README's own example, examples/ring"""


def _ring():
    """examples/ring's config, its module importable as a user's task module is (its folder on sys.path)."""
    import sys

    from conftest import ROOT

    folder = str(ROOT / "examples" / "ring")
    if folder not in sys.path:
        sys.path.append(folder)
    from ring import RingConfig

    return RingConfig()

CPU_CFG = RunConfig(cmd="train", exp_dir="outputs/x", cpu_kernels="avx2")
"""a run under cpu_kernels=avx2 (the resume refusals compare a checkpoint with it)"""


@pytest.fixture(autouse=True)
def _eager_after():
    """Each test leaves the process as it found it: eager, no compiled steps kept."""
    saved = dict(compiling._state)
    yield
    compiling._state.clear()
    compiling._state.update(saved)
    stepmod.reset_compiled()


def _losses_and_grads(task, mode, comm=None, steps=3, batch=3):
    """Train-mode rollout of one bucket (dropout on) under compile=mode -> (loss, per-parameter gradients)."""
    compiling.configure(mode)
    env = make_task(task, horizon=steps)
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig())
    gen = torch.Generator().manual_seed(3)
    bucket = env.reset(batch, gen)[0]
    traj = rollout(env, policy, comm or FullComm(), bucket, Rng(gen), steps, stats=False)
    loss = traj.cost.sum() / (batch * steps)
    loss.backward()
    return float(loss.detach()), [p.grad.clone() for p in policy.parameters()]


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(TASKS))
def test_compiled_gradients_agree_with_eager(name):
    # three steps: t=0 (a state without grad) and t=1 run eager and record the draws, t=2 runs compiled
    loss_e, grads_e = _losses_and_grads(TASKS[name](), "off")
    loss_c, grads_c = _losses_and_grads(TASKS[name](), "on")
    assert compiling.record()["in_effect"] == "on" and compiling.record()["shapes_compiled"] == 1
    assert loss_c == pytest.approx(loss_e, rel=1e-5)
    for ge, gc in zip(grads_e, grads_c):
        torch.testing.assert_close(gc, ge, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("name", sorted(TASKS))
def test_fused_kernels_give_eager_gradients(name, monkeypatch):
    monkeypatch.setattr(edge_kernels, "FUSED_FROM", 2)  # every team size here, the small ones too
    calls = []
    for fn in ("key_logits", "edge_messages"):
        real = getattr(edge_kernels, fn)
        monkeypatch.setattr(edge_kernels, fn, lambda *a, _f=real, _n=fn: calls.append(_n) or _f(*a))
    loss_e, grads_e = _losses_and_grads(TASKS[name](), "off")
    assert not calls  # compile=off never reaches the kernels
    loss_f, grads_f = _losses_and_grads(TASKS[name](), "fused")
    assert compiling.record()["in_effect"] == "fused"
    assert {"key_logits", "edge_messages"} <= set(calls)  # every task here has a dense round
    assert loss_f == pytest.approx(loss_e, rel=1e-5)
    for ge, gf in zip(grads_e, grads_f):
        torch.testing.assert_close(gf, ge, rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("pair_dim", [2, 4])
def test_fused_kernels_match_the_torch_round_with_their_own_backward(pair_dim):
    """The kernels against the torch expressions they replace, at a pair width other than 2 too, with weights
    that are zero where nobody is heard (the inputs' and the linears' gradients)."""
    torch.manual_seed(0)
    b, n, d = 3, 7, 16
    q, rel = torch.randn(b, n, d, requires_grad=True), torch.randn(b, n, n, pair_dim, requires_grad=True)
    w = (torch.softmax(torch.randn(b, n, n), -1) * (torch.rand(b, n, n) > 0.3)).requires_grad_()
    key, msg = torch.nn.Linear(pair_dim, d), torch.nn.Linear(pair_dim, d)
    leaves = [q, rel, w, *key.parameters(), *msg.parameters()]
    g_logits, g_agg = torch.randn(b, n, n), torch.randn(b, n, d)

    def grads(logits, agg):
        torch.autograd.backward([logits, agg], [g_logits, g_agg])
        out = [t.grad.clone() for t in leaves]
        for t in leaves:
            t.grad = None
        return logits.detach(), agg.detach(), out

    ref = grads((torch.relu(key(rel)) * q.unsqueeze(2)).sum(-1),
                (w.unsqueeze(-1) * torch.relu(msg(rel.transpose(1, 2)))).sum(2))
    got = grads(edge_kernels.key_logits(q, rel, key), edge_kernels.edge_messages(w, rel, msg))
    torch.testing.assert_close(got[0], ref[0], rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(got[1], ref[1], rtol=1e-5, atol=1e-5)
    for r, g in zip(ref[2], got[2]):
        torch.testing.assert_close(g, r, rtol=1e-4, atol=1e-5)


def test_fused_without_numba_or_off_a_cpu_is_one_line_and_eager(monkeypatch, capsys):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "numba" else real(name, *a))
    assert compiling.configure("fused", "cpu") is False
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compile=fused" in err[0] and "numba is not installed" in err[0] and "eager" in err[0]
    assert compiling.record()["in_effect"] == "off" and not edge_kernels.serves(torch.zeros(1, 30, 30, 2))
    monkeypatch.setattr(importlib.util, "find_spec", real)
    compiling.configure("fused", "cpu")
    n = edge_kernels.FUSED_FROM
    assert edge_kernels.serves(torch.zeros(1, n, n, 2)) and not edge_kernels.serves(torch.zeros(1, n, n, 2).double())
    assert not edge_kernels.serves(torch.zeros(1, n - 1, n - 1, 2))  # a small team: the eager round is faster


def test_off_and_auto_run_the_eager_step(monkeypatch):
    monkeypatch.setattr(stepmod, "_compile", lambda *a: pytest.fail("compile=off must not compile"))
    for mode in ("off", "auto"):
        assert compiling.configure(mode) is False
        _losses_and_grads(TASKS["random-cross"](), mode)
        assert compiling.record()["asked"] == mode and compiling.record()["in_effect"] == "off"


def test_failed_compilation_says_one_line_and_gives_eager_numbers(monkeypatch, capsys):
    loss_e, grads_e = _losses_and_grads(TASKS["random-cross"](), "off")

    def broken(*_):
        def fn(*_a):
            raise RuntimeError("InductorError: no compiler here\nmore lines")
        return fn

    monkeypatch.setattr(stepmod, "_compile", broken)
    loss_c, grads_c = _losses_and_grads(TASKS["random-cross"](), "on")
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compile=on" in err[0] and "no compiler here" in err[0] and "eager" in err[0]
    assert loss_c == loss_e  # the same draws handed to the eager step: bit for bit
    assert all(torch.equal(a, b) for a, b in zip(grads_e, grads_c))
    assert compiling.record()["in_effect"] == "off" and "did not compile" in compiling.record()["why_off"]


def test_no_cxx_compiler_is_one_line_and_eager(monkeypatch, capsys):
    monkeypatch.setattr(compiling, "compiler", lambda: None)
    assert compiling.configure("on", "cpu") is False
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no C++ compiler" in err[0]
    rec = runtime()["compile"]
    assert rec["asked"] == "on" and rec["in_effect"] == "off" and "no C++ compiler" in rec["why_off"]


def test_a_provider_that_reads_the_time_step_runs_eager(monkeypatch):
    class Timed(CommBase):
        name = "timed"

        def picks(self, ctx, round):
            n = ctx.obs.agent.shape[1]
            b = ctx.obs.agent.shape[0]
            return ((torch.arange(n) + 1 + ctx.step) % n).view(1, n, 1).expand(b, n, 1)

    monkeypatch.setattr(stepmod, "_compile", lambda *a: pytest.fail("a time-dependent provider must stay eager"))
    loss_e, _ = _losses_and_grads(TASKS["random-cross"](), "off", comm=Timed())
    timed = Timed()
    loss_c, _ = _losses_and_grads(TASKS["random-cross"](), "on", comm=timed)
    assert loss_c == loss_e
    shapes = stepmod._COMPILED.shapes_of(timed)
    assert shapes and all(s.fn is None for s in shapes.values())


def test_recorded_draws_are_replayed_in_order():
    gen = torch.Generator().manual_seed(5)
    rec = stepmod._Recording(Rng(gen))
    a, b = rec.randn(2, 3), rec.rand(2, 4)
    assert rec.plan == [("randn", 2, (3,)), ("rand", 2, (4,))]
    replay = stepmod._Replay([a, b])
    assert replay.randn(2, 3) is a and replay.rand(2, 4) is b


def test_compile_key_is_typed():
    assert RunConfig.__dataclass_fields__["compile"].default == "auto"
    with pytest.raises(ConfigError, match="unknown compile 'fast'"):
        RunConfig(cmd="train", exp_dir="outputs/x", compile="fast")


@pytest.mark.parametrize("was,now", [("on", "off"), ("off", "on"), ("fused", "off"), ("off", "fused")])
def test_resume_under_another_compile_mode_is_refused(was, now, monkeypatch):
    monkeypatch.setattr(compiling, "compiler", lambda: "g++")
    compiling.configure(now)
    payload = {"runtime": {"compile": {"asked": was, "in_effect": was}}}
    with pytest.raises(ConfigError, match=f"7 steps under compile={was}, this run has compile={now}: resume it with "
                                          f"compile={was}"):
        refuse_other_modes(payload, "model.pt", steps=7, cfg=CPU_CFG)
    refuse_other_modes({"runtime": {"compile": {"asked": now, "in_effect": now}}}, "model.pt", steps=7, cfg=CPU_CFG)


def test_both_resume_refusals_have_one_shape():
    """cpu_kernels (read from the checkpoint's config) and compile (its runtime) are refused by one table."""
    compiling.configure("off")
    payload = {"config": {"cpu_kernels": "native"}, "runtime": {"compile": {"asked": "off", "in_effect": "off"}}}
    with pytest.raises(ConfigError, match="3 steps under cpu_kernels=native, this run has cpu_kernels=avx2: resume "
                                          "it with cpu_kernels=native, or pass overwrite=true"):
        refuse_other_modes(payload, "model.pt", steps=3, cfg=CPU_CFG)
    refuse_other_modes({"config": {"cpu_kernels": "avx2"}}, "model.pt", steps=3, cfg=CPU_CFG)


def test_a_checkpoint_from_before_the_key_resumes_eager_only(monkeypatch):
    compiling.configure("off")
    refuse_other_modes({"runtime": {"cpu_kernels": "avx2"}}, "model.pt", steps=3, cfg=CPU_CFG)  # no record: eager
    monkeypatch.setattr(compiling, "compiler", lambda: "g++")
    compiling.configure("on")
    with pytest.raises(ConfigError, match="compile=off"):
        refuse_other_modes({}, "model.pt", steps=3, cfg=CPU_CFG)


def test_nearest_provider_records_its_plan_without_compiling(monkeypatch):
    """The sparse path (picks before any logit) records its draws like the dense one: one noise draw a step."""
    monkeypatch.setattr(stepmod, "_compile", lambda *a: (lambda *b: pytest.fail("not called at two steps")))
    nearest = NearestComm(2)
    _losses_and_grads(TASKS["random-cross"](), "on", comm=nearest, steps=2)
    shapes = stepmod._COMPILED.shapes_of(nearest)
    assert shapes and all(s.plan == [("randn", (key[3], key[3], 2))] for key, s in shapes.items())


def test_the_time_step_note_is_said_once_per_process(monkeypatch, caplog):
    class Timed(CommBase):
        name = "timed"

        def picks(self, ctx, round):
            n, b = ctx.obs.agent.shape[1], ctx.obs.agent.shape[0]
            return ((torch.arange(n) + 1 + ctx.step) % n).view(1, n, 1).expand(b, n, 1)

    monkeypatch.setattr(stepmod, "_compile", lambda *a: pytest.fail("a time-dependent provider must stay eager"))
    with caplog.at_level("INFO", logger=stepmod.log.name):
        for _ in range(2):  # two providers, two policies, train- and no-grad shapes: one note
            _losses_and_grads(TASKS["random-cross"](), "on", comm=Timed(), steps=3)
    assert sum("reads the time step" in r.getMessage() for r in caplog.records) == 1


def test_compiled_steps_do_not_keep_their_provider_alive(monkeypatch):
    """A compiled step closes over its task, policy and provider; a process-wide table of them kept every
    provider of a select grid alive."""
    import gc
    import weakref

    def fake_compile(env, policy, comm):  # holds all three, as torch.compile's closure does
        return lambda state, drawn: stepmod.eager_step(env, policy, comm, state, stepmod._Replay(drawn), 0)

    monkeypatch.setattr(stepmod, "_compile", fake_compile)
    comm = FullComm()
    _losses_and_grads(TASKS["random-cross"](), "on", comm=comm, steps=3)
    assert any(s.fn is not None for s in stepmod._COMPILED.shapes_of(comm).values())  # something was cached
    gone = weakref.ref(comm)
    del comm
    gc.collect()
    assert gone() is None


def test_tf32_is_off_where_a_gpu_runs():
    """Issue 39: on a GPU float32 matmuls keep full precision (no TF32), as on the CPU."""
    import torch

    from neurosym_cli.utils.device import full_precision, resolve_device

    before = torch.get_float32_matmul_precision(), torch.backends.cudnn.allow_tf32
    try:
        torch.set_float32_matmul_precision("high")
        torch.backends.cudnn.allow_tf32 = True
        full_precision()
        assert torch.get_float32_matmul_precision() == "highest" and not torch.backends.cudnn.allow_tf32
        assert resolve_device("cpu").type == "cpu"
    finally:
        torch.set_float32_matmul_precision(before[0])
        torch.backends.cudnn.allow_tf32 = before[1]


def test_fused_kernels_step_aside_for_a_tracer():
    """An export (torch.jit.trace, torch.export) or torch.compile records torch ops: the eager round serves it."""
    compiling.configure("fused")
    n = edge_kernels.FUSED_FROM
    rel = torch.zeros(1, n, n, 2)
    assert edge_kernels.serves(rel)
    seen = []
    torch.jit.trace(lambda r: seen.append(edge_kernels.serves(r)) or r + 1, (rel,), check_trace=False)
    assert seen == [False]


def test_fused_mode_exports_a_policy_with_a_free_team_size():
    """torch.export with N free under compile=fused: the eager round is traced and N stays symbolic (comparing it
    with FUSED_FROM before asking for a tracer pinned it: ConstraintViolationError)."""
    compiling.configure("fused")
    layer = CommTransformer.for_task(make_task(CrossConfig(name="random-cross"), horizon=2), ModelConfig()).rounds[0]

    class Logits(torch.nn.Module):
        def forward(self, h, rel):
            return layer.logits(h, rel)

    n = torch.export.Dim("n", min=2, max=64)
    for size in (8, 30):  # below and above FUSED_FROM
        h, rel = torch.randn(1, size, 16), torch.randn(1, size, size, 2)
        prog = torch.export.export(Logits(), (h, rel), dynamic_shapes=({1: n}, {1: n, 2: n}), strict=False)
        h2, rel2 = torch.randn(1, 40, 16), torch.randn(1, 40, 40, 2)
        torch.testing.assert_close(prog.module()(h2, rel2), Logits()(h2, rel2), rtol=1e-4, atol=1e-5)


def test_a_numba_that_fails_to_compile_is_one_line_and_the_eager_round(monkeypatch, capsys):
    compiling.configure("fused")
    monkeypatch.setattr(edge_kernels, "_WARM", [])
    monkeypatch.setattr(edge_kernels, "_warm", lambda p: (_ for _ in ()).throw(RuntimeError("LLVM says no\nmore")))
    n = edge_kernels.FUSED_FROM
    assert not edge_kernels.serves(torch.zeros(1, n, n, 2))
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did not compile (RuntimeError: LLVM says no)" in err[0] and "eager" in err[0]
    assert compiling.record()["in_effect"] == "off"


def test_fused_on_teams_below_the_kernels_size_resumes_as_eager(monkeypatch):
    """compile=fused on a task of at most 10 agents served no round (FUSED_FROM = 16): its checkpoint resumes under
    compile=off and the other way round; on random-cross (up to 40 agents) the two stay apart."""
    from neurosym_cli.commands.apps import compose_config

    small = compose_config("train", ["task=unlabeled-goals", "cpu_kernels=avx2"])
    large = compose_config("train", ["task=random-cross", "cpu_kernels=avx2"])
    fused = {"runtime": {"compile": {"asked": "fused", "in_effect": "fused"}}}
    off = {"runtime": {"compile": {"asked": "off", "in_effect": "off"}}}
    compiling.configure("off")
    refuse_other_modes(fused, "model.pt", steps=7, cfg=small)
    with pytest.raises(ConfigError, match="compile=fused, this run has compile=off"):
        refuse_other_modes(fused, "model.pt", steps=7, cfg=large)
    monkeypatch.setattr(compiling, "_configure_fused", lambda device: False)  # numba or not: the mode is asked
    compiling.configure("fused")
    refuse_other_modes(off, "model.pt", steps=7, cfg=small)
    with pytest.raises(ConfigError, match="compile=off, this run has compile=fused"):
        refuse_other_modes(off, "model.pt", steps=7, cfg=large)
    compiling.configure("off")


def test_the_profile_benchmark_splits_a_step_by_part(tmp_path):
    """benchmarks/bench_compile.py --profile on a small case: every part's seconds are >= 0, the named parts hold
    most of the step (the functions they name exist and are found), and the fused kernels' backward is counted
    under fused only."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "p.json"
    cmd = [sys.executable, str(root / "benchmarks/bench_compile.py"), "--profile", "--modes", "eager,fused",
           "--batch", "8", "--horizon", "3", "--steps", "1", "--threads", "1", "--fused-from", "0", "--json", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, cwd=tmp_path)
    eager, fused = json.loads(out.read_text())
    for row in (eager, fused):
        parts = row["parts_s_per_step"]
        assert all(v >= 0 for v in parts.values())
        named = {k: v for k, v in parts.items() if not k.startswith("the rest")}
        assert all(named[k] > 0 for k in ("observe (the task's observation and noise)", "task dynamics and cost",
                                          "transformer forward (rounds, read-out)", "backward: autograd's own ops"))
        assert sum(named.values()) > 0.5 * row["total_s_per_step"]
    assert eager["parts_s_per_step"]["backward: fused pair kernels"] == 0
    assert fused["parts_s_per_step"]["backward: fused pair kernels"] > 0
