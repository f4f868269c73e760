"""Pictures of whom agents talk to: recorded episodes, animations, attention maps, rule regions, the CLI verbs."""

import json
import shutil

import numpy as np
import pytest
import torch

from conftest import PAPER_METHOD
from test_cli import run

PROGRAM = "argmax(map(-1.0*d, filter(theta >= -1.85, l)))\nrandom(filter(d >= 3.41, l))\n"


def _setup(test_settings=("0", "0-1"), horizon=12):
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.tasks.random_cross import CrossConfig
    from neurosym_cli.tasks import make_task
    from neurosym_cli.policy import CommTransformer

    task = CrossConfig(name="two-groups-cross", _target_="neurosym_cli.tasks.two_groups_cross.TwoGroupsCrossTask",
                       num_groups=2,
                       agents_per_group=4, test_settings=list(test_settings))
    env = make_task(task, horizon)
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig(width=16, ffn=32))
    return env, policy


def _program():
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.policy.comm import ProgramComm

    from fixtures import feature_map

    return ProgramComm(parse(PROGRAM), feature_map("formation"))


def test_recorded_episodes_are_the_evaluation_protocols_episodes():
    """The loss of the recorded episodes of eval seed 0 averages to what `neurosym eval` reports for that seed."""
    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.evaluation import evaluate

    env, policy = _setup()
    comm = _program()
    row = evaluate(env, policy, comm, [0], torch.device("cpu"))[0]
    losses = []
    for k in range(2):  # seed 0 has one episode per test setting
        state, gen, seed = protocol_episode(env, k)
        assert seed == 0
        losses.append(record_episode(env, policy, comm, state, gen, torch.device("cpu")).cost.mean())
    assert np.mean(losses) == pytest.approx(row["cost"], rel=1e-5)
    assert protocol_episode(env, 2)[2] == 1  # episode 2 is the first of eval seed 1


def test_soft_attention_rows_sum_to_one_and_program_rows_have_at_most_k():
    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.policy import FullComm

    env, policy = _setup()
    state, gen, _ = protocol_episode(env, 1)  # both groups: N = 8
    full = record_episode(env, policy, FullComm(), state, gen, torch.device("cpu"))
    assert full.steps == 12 and full.rounds == 1 and full.edges.rule is None
    attn = np.stack([full.edges.weights(t, 0) for t in range(12)])  # (T, N, N)
    assert attn.shape == (12, 8, 8)
    assert np.allclose(attn.sum(-1), 1.0, atol=1e-5)
    assert np.all(np.diagonal(attn, axis1=-2, axis2=-1) == 0)
    state, gen, _ = protocol_episode(env, 1)
    prog = record_episode(env, policy, _program(), state, gen, torch.device("cpu"))
    attn = np.stack([prog.edges.weights(t, 0) for t in range(12)])
    nonzero = (attn > 0).sum(-1)
    assert nonzero.max() <= 2 and nonzero.max() >= 1
    assert np.allclose(attn.sum(-1)[nonzero > 0], 1.0, atol=1e-5)
    # every edge is named by the rule whose pick it is, and a rule's pick is an edge
    for t in range(12):
        i, j, _ = prog.edges.at(t, 0)
        k = prog.edges.rule_at(t, 0)
        assert set(k.tolist()) <= {0, 1}
        assert np.array_equal(prog.picks[t, 0, i, k], j)
        picked = prog.picks[t, 0]
        ii, kk = np.nonzero(picked >= 0)
        assert prog.edges.mask(t, 0)[ii, picked[ii, kk]].all()
    din, dout = prog.degrees()
    assert np.all(din <= 2) and din.shape == (12,)


def test_rule_regions_equal_the_evaluators_filter():
    """The shaded region of a rule is exactly where the DSL evaluator lets a real agent pass its filter."""
    from neurosym_cli.dsl.interpret import cond
    from neurosym_cli.dsl.parser import parse
    from fixtures import feature_map
    from neurosym_cli.viz.figures import rule_grid

    program = parse("random(filter(dx <= -1.0 and gd >= 2.0 or theta >= 1.0, l))\nargmax(map(-1.0*d, filter(d >= 1.5, l)))\n")
    s_i = np.array([1.5, -2.0], dtype=np.float32)  # x - g: the goal vector is (-1.5, 2.0), gd = 2.5
    origin = np.array([0.3, -0.4])
    xs, ys = np.linspace(-4, 4, 23), np.linspace(-3, 5, 19)
    regions = rule_grid(program, 0, feature_map("formation"), pair_dim=2, agent_input=s_i, origin=origin, xs=xs, ys=ys)
    gx, gy = np.meshgrid(xs, ys)
    pts = torch.tensor(np.stack([gx.ravel(), gy.ravel()], -1), dtype=torch.float32)
    n = 1 + len(pts)  # one real bucket: the asking agent and an agent at every grid point
    pos = torch.cat([torch.tensor(origin, dtype=torch.float32)[None], pts])[None]  # (1, N, 2)
    rel = pos[:, None, :, :] - pos[:, :, None, :]
    agent = torch.tensor(s_i).expand(1, n, 2)
    feats = feature_map("formation").view(agent, rel)
    for rule, (keep, score) in zip(program.rounds[0], regions):
        truth = cond(rule.cond, feats)[0, 0, 1:].reshape(gy.shape).numpy()
        assert np.array_equal(keep, truth)
        assert 0 < keep.sum() < keep.size  # the test has both sides
    assert regions[0][1] is None and regions[1][1] is not None
    assert np.allclose(regions[1][1], -np.hypot(gx - origin[0], gy - origin[1]), atol=1e-5)


def test_animation_frames_and_static_picture(tmp_path):
    from PIL import Image

    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.viz.animate import animate, episode_png

    env, policy = _setup(horizon=10)
    state, gen, _ = protocol_episode(env, 1)
    rec = record_episode(env, policy, _program(), state, gen, torch.device("cpu"))
    path, frames = animate(rec, tmp_path / "ep.gif", "test: prog", "rules", every=3)
    assert frames == 5  # steps 0, 3, 6, 9 and the last, 10
    im = Image.open(path)
    assert im.n_frames == 5 and im.size[0] > 300 and im.size[1] > 300
    pix = []
    for k in (0, 4):
        im.seek(k)
        pix.append(np.asarray(im.convert("RGB"), dtype=float))
    assert np.abs(pix[0] - pix[1]).mean() > 0.5  # the agents moved
    png = episode_png(rec, tmp_path / "ep.png", "test: prog")
    assert Image.open(png).size[0] > 600
    if shutil.which("ffmpeg") is None:
        with pytest.raises(FileNotFoundError, match="ffmpeg"):
            animate(rec, tmp_path / "ep.mp4", "test", "rules")
    else:  # MP4 through ffmpeg, where it is installed
        mp4, n = animate(rec, tmp_path / "ep.mp4", "test", "rules", every=3)
        assert n == 5 and mp4.stat().st_size > 1000 and mp4.read_bytes()[4:8] == b"ftyp"


TINY = ["task=two-groups-cross", "budget=tiny", *PAPER_METHOD]


def test_render_and_figures_from_a_tiny_run(tmp_path):
    """The paper's method (PAPER_METHOD) throughout: render's and figures' own baseline, prog-retrained, is the
    searched program's retraining, which a pipeline under pipeline.select=front (the front's pick) does not make."""
    base = "baselines=[tf-full,hard-attn,dist,prog,prog-retrained]"
    run(["pipeline", *TINY, base], tmp_path)
    p = run(["render", *TINY, "episode=1", "render.every=2"], tmp_path)
    out = tmp_path / "two-groups-cross/tiny/seed0/render/prog-retrained-k2-lam0.5-v1"
    from PIL import Image

    assert Image.open(out / "episode1.gif").n_frames == 5  # tiny horizon 8: steps 0, 2, 4, 6, 8
    assert (out / "episode1.png").stat().st_size > 5000 and "rendered" in p.stdout
    run(["render", *TINY, "baseline=tf-full"], tmp_path)
    assert (tmp_path / "two-groups-cross/tiny/seed0/render/tf-full/episode0.gif").exists()
    # a zoom is its own picture, beside the whole one, not over it
    p = run(["render", *TINY, "episode=1", "render.window=[5,7.5,-1,1]"], tmp_path)
    assert Image.open(out / "episode1-window5_7.5_-1_1.gif").n_frames == 9 and "window" in p.stdout
    assert Image.open(out / "episode1.gif").n_frames == 5
    p = run(["show-program", *TINY], tmp_path)
    assert "fires" in p.stdout and "if removed" in p.stdout and "%" in p.stdout  # rule statistics from summary
    summary = json.loads((tmp_path / "two-groups-cross/tiny/seed0/synth/k2-lam0.5-v1/summary.json").read_text())
    stats = summary["rounds"][0]["rule_stats"]
    assert len(stats) == len(summary["program"].strip().splitlines())
    assert all(0.0 <= s["fires"] <= 1.0 and 0.0 <= s["edge_share"] <= 1.0 for s in stats)
    p = run(["figures", *TINY, "render.agent=3"], tmp_path)
    figs = tmp_path / "two-groups-cross/tiny/seed0/figures"
    for name in ("attention-k2-lam0.5-v1-episode0.png", "trajectories-k2-lam0.5-v1.png", "figure1-k2-lam0.5-v1.png",
                 "rules-k2-lam0.5-v1-episode0.png"):
        assert (figs / name).stat().st_size > 5000, name
    # bad values are one line each
    for args, needle in ((["render.format=avi"], "render.format must be gif or mp4"),
                         (["render.round=2"], "has 1 round(s)"),
                         (["episode=-1"], "episode must be >= 0"),
                         (["render.window=[1,0,0,1]"], "x0 < x1 and y0 < y1"),
                         (["render.window=[1,2,3]"], "render.window must be [x0, x1, y0, y1]"),
                         (["render.window=[1000,1001,0,1]"], "no agent of episode 0 enters render.window")):
        p = run(["render", *TINY, *args], tmp_path, check=False)
        assert p.returncode != 0 and needle in p.stderr and "Traceback" not in p.stderr, p.stderr
    p = run(["render", *TINY, "baseline=no-comm"], tmp_path, check=False)
    assert p.returncode != 0 and "neurosym train" in p.stderr  # names the command that makes the model


def test_figures_need_a_trained_run(tmp_path):
    p = run(["figures", "task=random-grid", "budget=tiny"], tmp_path, check=False)
    assert p.returncode != 0 and "neurosym pipeline task=random-grid budget=tiny" in p.stderr


def test_a_swarm_size_render_samples_the_edges_it_draws(tmp_path):
    """From render.crowd_from agents on, a frame draws the edges of the sampled receivers only: exactly their
    edges, at most K per receiver, and far fewer than the step has."""
    from PIL import Image

    from neurosym_cli.config import ModelConfig
    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.tasks import make_task
    from neurosym_cli.tasks.swarm import SwarmConfig
    from neurosym_cli.viz.animate import animate
    from neurosym_cli.viz.crowd import CrowdScene

    env = make_task(SwarmConfig(name="swarm", agents_per_group=150), 3)  # N = 300
    torch.manual_seed(0)
    policy = CommTransformer(env.obs_dim, env.action_dim, 1, ModelConfig(width=16, ffn=32))
    state, gen, _ = protocol_episode(env, 0)
    rec = record_episode(env, policy, _program(), state, gen, torch.device("cpu"))
    assert rec.n_agents == 300 and rec.steps == 3
    scene = CrowdScene(rec, "test: swarm", "rules", round_=0, trail=2, receivers=25, seed=1)
    try:
        assert len(scene.recv) == 25 and len(set(scene.recv.tolist())) == 25
        for t in range(4):
            scene.draw(t)
            s = min(t, 2)
            mask = rec.edges.mask(s, 0)
            assert scene.drawn == mask[scene.recv].sum() <= 25 * 2  # K = 2 rules
            assert scene.total == mask.sum() > 4 * scene.drawn
            assert len(scene.links.lines.get_segments()) == len(scene.links.heads.get_paths()) == scene.drawn
    finally:
        scene.close()
    # a zoom: the axes show the window, and the receivers are sampled among the agents that start in it
    lo, hi = rec.pos[0].min(0), rec.pos[0].max(0)
    mid = (lo + hi) / 2
    window = [float(lo[0]), float(mid[0]), float(lo[1]), float(hi[1])]
    scene = CrowdScene(rec, "test: swarm", "rules", round_=0, trail=2, receivers=25, seed=1, window=window)
    try:
        assert scene.ax.get_xlim() == pytest.approx(window[:2]) and scene.ax.get_ylim() == pytest.approx(window[2:])
        inside = rec.pos[0, scene.recv]
        assert len(scene.recv) == 25 and (inside[:, 0] <= mid[0]).all()
        assert "render.window" in scene.fig._suptitle.get_text()
    finally:
        scene.close()
    path, frames = animate(rec, tmp_path / "swarm.gif", "test: swarm", "rules", receivers=25,
                           stills=tmp_path / "swarm-frames.png")
    im = Image.open(path)
    assert frames == im.n_frames == 4 and im.size[0] > 600
    assert Image.open(tmp_path / "swarm-frames.png").size == (2 * im.size[0], 2 * im.size[1])


def test_the_sparse_and_dense_paths_record_the_same_edges():
    """A large team's round (a ``Heard``: picks, no N x N array) and the same round on the dense path give the same
    edges, weights and rules, and the (N, N) views of the edges are the policy's own mask and weights."""
    from neurosym_cli.config import ModelConfig
    from neurosym_cli.dsl.parser import parse
    from neurosym_cli.episode import round_edges, stack_edges
    from neurosym_cli.policy import CommTransformer
    from neurosym_cli.policy.comm import CommContext, ProgramComm
    from neurosym_cli.policy.transformer import Heard
    from neurosym_cli.tasks.base import Observation, Rng
    from neurosym_cli.tasks.random_cross import CrossConfig, RandomCrossTask

    env = RandomCrossTask(CrossConfig(name="random-cross", group_prob=1.0, sparse_from=0))
    state = env.reset(1, torch.Generator().manual_seed(0))[0]
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, ModelConfig(dropout=0.0))
    comm = ProgramComm(parse("argmax(map(-1.0*d, filter(true, l)))\nargmax(map(1.0*dx, filter(d <= 3.0, l)))\n"),
                       env.features("v1"))
    obs = env.observe(state, Rng(torch.Generator().manual_seed(1)))
    got = []
    for o in (obs, Observation(obs.agent, obs.pairs.dense())):
        ctx = CommContext(env, state, o, Rng(torch.Generator().manual_seed(2)))
        picks = []
        with torch.no_grad():
            out = policy(o, lambda lg, r: comm.select(ctx, lg, r),
                         lambda r: picks.append(comm.picks(ctx, r)) or picks[-1])
        got.append((out, round_edges(out.heard[0], picks[0]), picks[0]))
    (sparse, e_sparse, picks), (dense, e_dense, _) = got
    assert isinstance(sparse.heard[0], Heard) and not isinstance(dense.heard[0], Heard)
    for a, b in zip(e_sparse, e_dense):
        assert np.array_equal(a, b)
    i, j, w, rule = e_sparse
    assert len(i) >= 40 and set(rule.tolist()) == {0, 1}
    assert np.array_equal(picks[0].numpy()[i, rule], j)  # an edge's rule picked it
    edges = stack_edges(40, 1, [e_sparse, e_dense], programs=True)
    assert edges.steps == 2 and edges.count(1, 0) == len(i)
    assert np.array_equal(edges.mask(0, 0), dense.masks[0][0].numpy())
    assert np.array_equal(edges.weights(1, 0), dense.attn[0][0].numpy())
    din, dout = edges.degrees()
    deg = dense.masks[0][0].numpy()
    assert din[0] == deg.sum(1).max() and dout[1] == deg.sum(0).max()
    rows = edges.of(1, 0, np.array([3, 7]))
    assert set(edges.recv[rows].tolist()) == {3, 7} and np.all(rows >= edges.count(0, 0))


def test_a_provider_whose_pick_width_changes_records_and_draws(tmp_path):
    """comm-range pads its picks to the degree of the moment, so K changes from step to step: the episode records
    (picks padded with -1 to the widest K) and its edges are exactly the agents within the radius."""
    import dataclasses

    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.schemes import SCHEMES
    from neurosym_cli.viz.animate import animate

    env, policy = _setup(horizon=60)
    scheme = dataclasses.replace(SCHEMES["comm-range"], radius=0.8)
    state, gen, _ = protocol_episode(env, 0)
    rec = record_episode(env, policy, scheme, state, gen, torch.device("cpu"))
    widths = {int((rec.picks[t, 0] >= 0).sum(-1).max()) for t in range(rec.steps)}
    assert len(widths) > 1 and rec.picks.shape[-1] == max(widths)
    for t in (0, rec.steps // 2, rec.steps - 1):
        d = np.linalg.norm(rec.pos[t][:, None] - rec.pos[t][None], axis=-1)  # positions the step observed
        want = (d <= 0.8) & ~np.eye(rec.n_agents, dtype=bool)
        assert np.array_equal(rec.edges.mask(t, 0), want)
        assert np.all(rec.edges.rule_at(t, 0) >= 0)
    path, frames = animate(rec, tmp_path / "range.gif", "test: comm-range", "mask", every=20)
    assert frames == 4 and path.exists()


def test_the_seed_plane_frames_its_markers_and_names_the_cut_intervals(tmp_path, monkeypatch):
    """One seed per baseline on one x value still gets a readable frame; an interval far beyond the markers is
    cut at the frame and named under it; a non-finite value is left out of the frame."""
    from neurosym_cli import plotting

    texts = []
    real = plotting.save_figure

    def keep(fig, path):
        texts.extend(t.get_text() for ax in fig.axes for t in ax.texts)
        lims.append((fig.axes[0].get_xlim(), fig.axes[0].get_ylim()))
        return real(fig, path)

    lims = []
    monkeypatch.setattr(plotting, "save_figure", keep)
    plotting.seeds_plane({"tf-full": [(0, 5.0, 40.0)]}, {"tf-full": (5.0, None, 40.0, None)}, "one point",
                         tmp_path / "a.png")
    (x0, x1), (y0, y1) = lims[-1]
    assert x0 < 5.0 < x1 and y0 < 40.0 < y1 and x1 - x0 > 0.1 and y1 - y0 > 1.0
    pts = {"tf-full": [(0, 40.0, 60.0), (1, 41.0, 62.0)], "no-comm": [(0, 0.0, 90.0), (1, 0.0, float("nan"))]}
    across = {"tf-full": (40.5, 1.0, 61.0, 2.0), "no-comm": (0.0, 0.0, 90.0, 400.0)}
    plotting.seeds_plane(pts, across, "cut", tmp_path / "b.png")
    (x0, x1), (y0, y1) = lims[-1]
    assert 0 <= y0 < 60.0 and 90.0 < y1 < 200.0 and x0 <= 0.0 and x1 > 41.0
    assert any(t.startswith("intervals beyond the frame are cut: no-comm") for t in texts)
    assert (tmp_path / "b.png").stat().st_size > 0
