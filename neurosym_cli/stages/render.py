"""Pictures from a run directory alone (no retraining): `neurosym render` draws one evaluation episode of one
baseline as an animation and a static picture; `neurosym figures` draws the paper's figures (``figures.py``)."""

from __future__ import annotations

from .. import paths
from ..config import ConfigError, RunConfig
from ..episode import EpisodeRecord, protocol_episode, record_episode
from ..utils.console import log, say
from ..utils.device import resolve_device
from ..utils.seeding import seed_everything
from . import RunInfo
from .comm import load_baseline


def record(cfg: RunConfig, episode: int | None = None) -> tuple[EpisodeRecord, str]:
    """Episode ``episode`` (default ``cfg.episode``) of the evaluation protocol under ``cfg.baseline``, and a
    title naming it."""
    device = resolve_device(cfg.device)
    seed_everything(cfg.seed)
    policy, env, comm = load_baseline(cfg, device)
    k = cfg.episode if episode is None else episode
    try:
        state, gen, eval_seed = protocol_episode(env, k)
    except ValueError as e:
        raise ConfigError(str(e)) from None
    rec = record_episode(env, policy, comm, state, gen, device)
    title = (f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): {paths.baseline_label(cfg)}, "
             f"episode {k} (eval seed {eval_seed}), N = {rec.n_agents}")
    return rec, title


def render_episode(cfg: RunConfig, info: RunInfo) -> dict:
    """`neurosym render`: <exp_dir>/render/<label>/episode<k>.gif (or .mp4) and episode<k>.png."""
    from ..viz.animate import animate, edge_style, episode_png

    if cfg.render.round > cfg.task.rounds:
        raise ConfigError(f"render.round={cfg.render.round}, but {cfg.task.name} has {cfg.task.rounds} round(s)")
    rec, title = record(cfg)
    out = paths.render_dir(cfg)
    style = edge_style(rec, cfg.baseline.comm)
    round_note = f", round {cfg.render.round} edges" if cfg.task.rounds > 1 else ""
    try:
        anim, frames = animate(rec, out / f"episode{cfg.episode}.{cfg.render.format}", title + round_note, style,
                               cfg.render.every, cfg.render.fps, cfg.render.trail, cfg.render.round - 1)
    except FileNotFoundError as e:
        raise ConfigError(str(e)) from None
    png = episode_png(rec, out / f"episode{cfg.episode}.png", title)
    log.info("episode %d: loss %.3f (time-averaged), %d steps, %d agents", cfg.episode, rec.cost.mean(), rec.steps,
             rec.n_agents)
    say(f"[green]rendered[/] {anim} ({frames} frames) and {png}")
    return {"animation": str(anim), "frames": frames, "png": str(png), "loss": float(rec.cost.mean())}
