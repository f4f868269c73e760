"""Pictures from a run directory alone (no retraining): `neurosym render` draws one evaluation episode of one
baseline as an animation and a static picture; `neurosym figures` draws the paper's figures (``figures.py``)."""

from __future__ import annotations

import dataclasses

from ..baselines import run_args
from ..schemes import with_run
from ..config import ConfigError, RunConfig, UserError
from ..episode import EpisodeRecord, protocol_episode, record_episode
from ..policy.protocol import unwrap
from ..tasks import make_task
from ..utils.console import Parts, log, say
from ..utils.io import ArtifactError
from ..utils.device import resolve_device
from ..utils.seeding import seed_everything
from . import RunInfo
from ..run import RunDir
from ..run.layout import ATTENTION, FIGURE1, FIGURE5, RULES, TRAJECTORIES, episode_stem, frames_file
from ..run.models import baseline_comm, load_baseline


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
    title = (f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed}): {RunDir(cfg).label}, "
             f"episode {k} (eval seed {eval_seed}), N = {rec.n_agents}")
    return rec, title


def check_episode(cfg: RunConfig) -> None:
    """Refuse an ``episode=`` beyond the evaluation protocol's (``budget.eval_seeds`` seeds of the task's test
    episodes each): it was drawn from seeds no evaluation ran, without a word."""
    per_seed = len(cfg.task.test_settings) or cfg.task.eval_episodes
    total = per_seed * cfg.budget.eval_seeds
    if cfg.episode >= total:
        raise ConfigError(f"episode={cfg.episode} is beyond the evaluation's {total} episodes ({cfg.budget.eval_seeds} "
                          f"seeds of {per_seed}); choose episode=0..{total - 1}")


def check_in_episode(cfg: RunConfig, rec: EpisodeRecord) -> None:
    """Refuse ``render.agent`` and ``render.step`` beyond the episode drawn (they were clamped to its last agent
    and step, without a word)."""
    if cfg.render.agent >= rec.n_agents:
        raise ConfigError(f"render.agent={cfg.render.agent}, but episode {cfg.episode} has {rec.n_agents} agents; "
                          f"choose render.agent=0..{rec.n_agents - 1}")
    if cfg.render.step >= rec.steps:
        raise ConfigError(f"render.step={cfg.render.step}, but episode {cfg.episode} has {rec.steps} steps; choose "
                          f"render.step=0..{rec.steps - 1}")


def render_episode(cfg: RunConfig, info: RunInfo) -> dict:
    """`neurosym render`: <exp_dir>/render/<label>/episode<k>.gif (or .mp4), episode<k>.png (the whole episode)
    and episode<k>-frames.png (four frames of the animation); with render.window=[x0,x1,y0,y1] (a zoom) the names
    are episode<k>-window<x0>_<x1>_<y0>_<y1>.*, so a zoom never replaces the whole picture."""
    from ..tasks.base import cost_words
    from ..viz.animate import animate, edge_style, episode_png
    from ..viz.crowd import window_receivers

    if cfg.render.round > cfg.task.rounds:
        raise ConfigError(f"render.round={cfg.render.round}, but {cfg.task.name} has {cfg.task.rounds} round(s)")
    check_episode(cfg)
    rec, title = record(cfg)
    window = cfg.render.window
    if window is not None and not window_receivers(rec, window).any():  # no agent ever enters it
        lo, hi = rec.pos.reshape(-1, 2).min(0), rec.pos.reshape(-1, 2).max(0)
        raise ConfigError(f"no agent of episode {cfg.episode} enters render.window={window}; its agents move in x in "
                          f"[{lo[0]:.1f}, {hi[0]:.1f}], y in [{lo[1]:.1f}, {hi[1]:.1f}]: choose a window there, or "
                          f"render.window=null for the whole episode")
    out = RunDir(cfg).render_dir
    stem = episode_stem(cfg.episode, window)
    stills = out / frames_file(stem)
    style = edge_style(rec, cfg.baseline)
    round_note = f", round {cfg.render.round} edges" if cfg.task.rounds > 1 else ""
    try:
        anim, frames = animate(rec, out / f"{stem}.{cfg.render.format}", title + round_note, style,
                               every=cfg.render.every, fps=cfg.render.fps, trail=cfg.render.trail,
                               round_=cfg.render.round - 1, crowd_from=cfg.render.crowd_from,
                               receivers=cfg.render.receivers, seed=cfg.seed,
                               stills=stills, window=window)
    except FileNotFoundError as e:
        raise ConfigError(str(e)) from None
    png = episode_png(rec, out / f"{stem}.png", title, window, cost_words=cost_words(cfg.task))
    log.info("episode %d: loss %.3f (time-averaged), %d steps, %d agents", cfg.episode, rec.cost.mean(), rec.steps,
             rec.n_agents)
    say(f"[green]rendered[/] {anim} ({frames} frames), {png} and {stills}")
    return {"animation": str(anim), "frames": frames, "png": str(png), "stills": str(stills),
            "loss": float(rec.cost.mean())}


def _with_baseline(cfg: RunConfig, name: str) -> RunConfig:
    from .front_select import program_for

    return dataclasses.replace(cfg, baseline=with_run(cfg, name), program=program_for(cfg, name))


def _records(cfg: RunConfig, names: list[str], episode: int,
             memo: dict | None = None) -> list[tuple[str, EpisodeRecord]]:
    """(label, record) of each baseline that exists in the run directory; the missing ones are logged. ``memo``:
    (name, episode) -> what was recorded before (None: missing), so that a figure reuses another's episode (a
    recording is the same each time: the protocol's episode, from the seed)."""
    memo = {} if memo is None else memo
    out = []
    for name in names:
        if (name, episode) not in memo:
            try:
                b = _with_baseline(cfg, name)  # a family's pick may be gone: drawn without it, as a missing model
                memo[name, episode] = (RunDir(b).label, record(b, episode)[0])
            except UserError as e:
                log.info("figures: no %s here, drawn without it (%s)", name, e)
                memo[name, episode] = None
        if memo[name, episode] is not None:
            out.append(memo[name, episode])
    return out


def _setting_episodes(cfg: RunConfig) -> tuple[int, int] | None:
    """(the test episode of eval seed 0 with the most groups, one with a single group), by the task's named test
    settings ("0-1-2-3", "0"); None for tasks without them."""
    names = list(cfg.task.test_settings)
    if not names:
        return None
    most = max(range(len(names)), key=lambda k: names[k].count("-"))
    single = next((k for k, nm in enumerate(names) if "-" not in nm), 0)
    return most, single


def make_figures(cfg: RunConfig, info: RunInfo) -> dict:
    """`neurosym figures`: the paper's figures that this run directory has the models for, in <exp_dir>/figures/,
    named after the program they show (k5-lam0.5-v1, ...):
    attention maps (render.baselines side by side, episode=, render.step=), trajectories of prog-retrained vs dist
    (formation tasks: the test episode with the most groups and one with a single group), Figure 1
    (two-groups-cross), rule regions of the program (render.agent=), Figure 5 (unlabeled-goals)."""
    from ..viz import figures as fig

    check_episode(cfg)
    run = RunDir(cfg)
    head = f"{cfg.task.name} ({cfg.budget.name} budget, train seed {cfg.seed})"
    made: dict[str, str] = {}
    step = cfg.render.step
    task = make_task(cfg.task, cfg.horizon)
    tag = RunDir(_with_baseline(cfg, "prog")).program_tag  # the pictures of programs name the program they show
    settings = _setting_episodes(cfg)
    figure1 = bool(getattr(task, "figure1", False)) and settings is not None  # the task asks for the paper's Figure 1
    parts = Parts(f"figures {cfg.task.name}", 2 + (settings is not None) + figure1)  # recording episodes is most
    memo: dict = {}  # (baseline, episode) -> its recorded episode, shared by the figures
    parts.begin(f"attention maps, episode {cfg.episode} of {', '.join(cfg.render.baselines)}")
    recs = _records(cfg, list(cfg.render.baselines), cfg.episode, memo)
    # the program's rules, drawn on the episode of the retrained model (else of the oracle under the program)
    prog = _records(cfg, ["prog-retrained"], cfg.episode, memo) or _records(cfg, ["prog"], cfg.episode, memo)
    if recs or prog:  # before anything is drawn
        check_in_episode(cfg, (recs or prog)[0][1])
    if recs:
        made["attention"] = str(fig.attention_maps(recs, step, run.figure_file(ATTENTION, tag, episode=cfg.episode),
                                                   f"{head}: attention at episode {cfg.episode}"))
    if settings is not None:
        parts.begin(f"trajectories of prog-retrained and dist, episodes {', '.join(map(str, dict.fromkeys(settings)))}")
        panels = []
        for k in dict.fromkeys(settings):  # the two episodes (one if they coincide)
            pair = _records(cfg, ["prog-retrained", "dist"], k, memo)
            if pair:
                groups = len(set(pair[0][1].group.tolist()))
                panels.append((f"episode {k}: {groups} group(s), N = {pair[0][1].n_agents}", pair))
        if panels:
            made["trajectories"] = str(fig.trajectories(panels, run.figure_file(TRAJECTORIES, tag),
                                                        f"{head}: group paths, prog-retrained solid, dist dashed"))
    if figure1:
        parts.begin(f"Figure 1, episode {settings[0]}")
        full = _records(cfg, ["tf-full"], settings[0], memo)
        prog1 = _records(cfg, ["prog-retrained"], settings[0], memo)  # its own name: prog stays cfg.episode's
        if full and prog1:
            made["figure1"] = str(fig.figure1(full[0], prog1[0], run.figure_file(FIGURE1, tag),
                                              f"{head}: Figure 1, episode {settings[0]}"))
    parts.begin(f"the program's rule regions, episode {cfg.episode}")
    if prog:
        prog_cfg = _with_baseline(cfg, "prog-retrained" if prog[0][0].startswith("prog-retrained") else "prog")
        label, rec = prog[0]
        comm = unwrap(baseline_comm(prog_cfg, task))  # the program under any link failure
        program = comm.program  # type: ignore[attr-defined]
        agent = cfg.render.agent  # within the episode (check_in_episode)
        for r in range(program.n_rounds):
            path = run.figure_file(RULES, tag, episode=cfg.episode, round_=r + 1 if program.n_rounds > 1 else None)
            made[f"rules{r + 1}"] = str(fig.rule_regions(
                program, comm.fmap, task.pair_dim, rec, agent=agent, step=step, round_=r, path=path,
                title=f"{head}: rules of {label}" + (f", round {r + 1}" if program.n_rounds > 1 else "")))
        if not rec.labelled:  # a shared goal set: the paper's Figure 5 (unlabeled goals)
            made["figure5"] = str(fig.unlabeled_scene(label, rec, step, run.figure_file(FIGURE5, tag, episode=cfg.episode),
                                                      f"{head}: Figure 5, episode {cfg.episode}"))
    if not made:
        raise ArtifactError(f"no trained baselines to draw in {cfg.exp_dir}; run `neurosym pipeline "
                            f"{run_args(cfg)}` first")
    for name, p in made.items():
        say(f"[green]figure[/] {name}: {p}")
    return made
