"""A recorded episode as an animation (GIF; MP4 through ffmpeg) and as one static picture.

Each frame: the goals, the agents (by group), their recent trails, and whom each agent hears at this step, drawn
as an arrow from the heard agent to the listener: coloured by the rule that chose it for a program, with the
attention weight as opacity for soft attention, plain for the other masks. Agents that collide are ringed in
red. The title line counts steps and gives the running loss and the max in- and out-degree of the step.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np

from ..episode import EpisodeRecord
from ..tasks.base import COST_WORDS
from ..utils.io import atomic_file
from .crowd import CrowdScene
from .draw import (COLLISION_COLOR, DIRECTION, EDGE_COLOR, RULE_COLORS, BlitScene, Links, edge_handles, edge_segments,
                   group_color, head_size, matplotlib_agg, save_figure, view_limits, window_note, wrap_title)

def edge_style(rec: EpisodeRecord, baseline) -> str:
    """How a frame draws a provider's edges: "rules" (coloured by rule, programs), "weights" (opacity = attention
    weight, soft attention) or "mask" (plain); ``baseline`` is the episode's scheme (``cfg.baseline``)."""
    if baseline.has_program and rec.picks is not None:
        return "rules"
    return "weights" if baseline.soft_attention else "mask"


def _edges(rec: EpisodeRecord, t: int, r: int, style: str):
    """Segments (E, 2, 2) and RGBA colours (E, 4) of step t, round r."""
    from matplotlib.colors import to_rgba

    i, j, w = rec.edges.at(t, r)
    seg = edge_segments(rec.pos[t], i, j)
    if not len(seg):
        return seg, np.zeros((0, 4))
    if style == "rules":
        k = rec.edges.rule_at(t, r)
        assert k is not None
        colors = np.array([to_rgba(RULE_COLORS[int(x) % len(RULE_COLORS)], 0.85) for x in k])
    else:
        colors = np.tile(to_rgba(EDGE_COLOR, 0.6), (len(seg), 1))
        if style == "weights":  # soft attention: what fraction of i's attention goes to j
            colors[:, 3] = np.clip(w, 0.02, 1.0)
    return seg, colors


class _Scene(BlitScene):
    """One figure whose artists are updated frame by frame (drawn once, then only moved: fast)."""

    def __init__(self, rec: EpisodeRecord, title: str, style: str, *, round_: int, trail: int, size: float = 5.6,
                 dpi: int = 90, window: list[float] | None = None):
        from matplotlib.collections import LineCollection
        from matplotlib.lines import Line2D

        plt = matplotlib_agg()
        self.rec, self.style, self.round, self.trail = rec, style, round_, trail
        self.deg_in, self.deg_out = rec.degrees()
        xlim, ylim, ratio = view_limits(window, rec.pos, rec.goal)
        self.fig, ax = plt.subplots(figsize=(max(size, size * ratio ** 0.5), size / ratio ** 0.5 + 1.2), dpi=dpi)
        self.ax = ax
        colors = group_color(rec.group) if rec.labelled else ["#4e79a7"] * rec.n_agents
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        goal_colors = colors if rec.labelled else ["#555555"] * len(rec.goal)
        ax.scatter(rec.goal[:, 0], rec.goal[:, 1], marker="x", s=22, c=goal_colors, lw=1.0, zorder=1)
        # the moving parts are "animated": left out of the background, drawn over it frame by frame (blitting)
        self.trails = LineCollection([], colors=colors, lw=0.8, alpha=0.45, zorder=2, animated=True)
        ax.add_collection(self.trails)
        self.links = Links(ax, lw=1.1, zorder=3, head=head_size(xlim, ylim))
        self.agents = ax.scatter(rec.pos[0, :, 0], rec.pos[0, :, 1], s=26, c=colors, edgecolors="white",
                                 linewidths=0.5, zorder=4, animated=True)
        self.rings = ax.scatter([], [], s=90, facecolors="none", edgecolors=COLLISION_COLOR, linewidths=1.4,
                                zorder=5, animated=True)
        self.text = ax.text(0.5, 1.015, "", transform=ax.transAxes, ha="center", va="bottom", fontsize=8,
                            family="monospace", animated=True)
        self.moving = (self.trails, *self.links.artists, self.agents, self.rings, self.text)
        self.fig.suptitle(wrap_title(title) + f"\n{DIRECTION}" + window_note(window), fontsize=8)
        handles = [Line2D([], [], marker="o", ls="", color=colors[0], ms=5, label="agent"),
                   Line2D([], [], marker="x", ls="", color=goal_colors[0], ms=5, label="goal"),
                   Line2D([], [], marker="o", ls="", mfc="none", mec=COLLISION_COLOR, ms=8, label="collision")]
        handles += edge_handles(style, rec.picks)
        ncol = min(len(handles), 4)
        rows = -(-len(handles) // ncol)
        self.fig.legend(handles=handles, fontsize=6.5, loc="lower center", ncol=ncol, frameon=False)
        height = self.fig.get_size_inches()[1]
        self.fig.tight_layout(rect=(0, (0.08 + 0.16 * rows) / height, 1, 0.97))  # room for the legend's rows
        self.keep_background()

    def draw(self, t: int) -> None:
        """Show the state after ``t`` steps (t = 0: the start) with the edges used at step t (the last step's at
        the end)."""
        rec = self.rec
        s = min(t, rec.steps - 1)  # communication of the step being taken (the last one at the end)
        lo = max(0, t - self.trail)
        self.trails.set_segments([rec.pos[lo:t + 1, i] for i in range(rec.n_agents)] if t > 0 else [])
        self.links.set(*_edges(rec, s, self.round, self.style))
        self.agents.set_offsets(rec.pos[t])
        hit = rec.collide[t - 1] if t > 0 else np.zeros(rec.n_agents, bool)
        self.rings.set_offsets(rec.pos[t][hit] if hit.any() else np.zeros((0, 2)))
        loss = f"{rec.cost[:t].mean():7.2f}" if t > 0 else "      -"
        self.text.set_text(f"step {t:>3}/{rec.steps}  loss so far {loss}  "
                           f"max in {self.deg_in[s]:.0f}  max out {self.deg_out[s]:.0f}  "
                           f"colliding {int(hit.sum())}")


def animate(rec: EpisodeRecord, path: Path, title: str, style: str, *, every: int = 1, fps: int = 20,
            trail: int = 25, round_: int = 0, crowd_from: int = 200, receivers: int = 40, seed: int = 0,
            stills: Path | None = None, window: list[float] | None = None) -> tuple[Path, int]:
    """Write the episode as a GIF (path ending .gif) or MP4 (.mp4, needs ffmpeg): frames at steps 0, every,
    2 every, ..., T; from ``crowd_from`` agents on as crowd frames (crowd.py: the edges of ``receivers`` sampled
    from ``seed``). ``stills``: also a PNG of four of the frames (start, two middle, end). ``window``: [x0, x1, y0,
    y1], the region the frames show (all of the episode when None). Returns the path and the number of frames."""
    from PIL import Image

    if path.suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise FileNotFoundError("MP4 needs ffmpeg on the PATH; render.format=gif needs nothing more")
    steps = list(range(0, rec.steps + 1, max(1, every)))
    if steps[-1] != rec.steps:
        steps.append(rec.steps)
    scene = (CrowdScene(rec, title, style, round_=round_, trail=trail, receivers=receivers, seed=seed, window=window)
             if rec.n_agents >= crowd_from else _Scene(rec, title, style, round_=round_, trail=trail, window=window))
    try:
        frames = []
        for t in steps:
            scene.draw(t)
            frames.append(scene.frame())
    finally:
        scene.close()
    if stills is not None:
        _stills(frames, stills)
    with atomic_file(path) as tmp:
        if path.suffix == ".mp4":
            h, w, _ = frames[0].shape
            h2, w2 = h - h % 2, w - w % 2  # yuv420p needs even sizes
            cmd = ["ffmpeg", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w2}x{h2}",
                   "-r", str(fps), "-i", "-", "-pix_fmt", "yuv420p", "-vcodec", "libx264", str(tmp)]
            subprocess.run(cmd, input=b"".join(f[:h2, :w2].tobytes() for f in frames), check=True)
        else:
            # one palette for every frame (the first frame's colours plus the edge colours): fast, small, no flicker
            # the palette comes from a mosaic of frames across the episode, by octree (keeps small areas of distinct
            # colour, the agents, that a pixel-count method gives to the background's shades)
            sample = frames[:: max(1, len(frames) // 6)]
            palette = Image.fromarray(np.concatenate(sample)).quantize(colors=255, method=Image.Quantize.FASTOCTREE)
            quant = [Image.fromarray(f).quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
            quant[0].save(tmp, format="GIF", save_all=True, append_images=quant[1:], duration=int(1000 / fps), loop=0)
    return path, len(frames)


def _stills(frames: list[np.ndarray], path: Path) -> Path:
    """Four frames of the animation (the first, two in between, the last) as one 2 x 2 PNG."""
    from PIL import Image

    picks = sorted({round(q * (len(frames) - 1)) for q in (0, 1 / 3, 2 / 3, 1)})
    h, w, _ = frames[0].shape
    grid = np.full((2 * h, 2 * w, 3), 255, dtype=np.uint8)
    for n, k in enumerate(picks):
        grid[(n // 2) * h:(n // 2 + 1) * h, (n % 2) * w:(n % 2 + 1) * w] = frames[k]
    with atomic_file(path) as tmp:
        Image.fromarray(grid).save(tmp, format="PNG")
    return path


def episode_png(rec: EpisodeRecord, path: Path, title: str, window: list[float] | None = None, *,
                cost_words: str = COST_WORDS) -> Path:
    """The whole episode in one picture: every agent's path from start (open circle) to end (dot) with the goals
    (in ``window`` [x0, x1, y0, y1] only, when given), and beside it the loss and the max in- and out-degree of
    every step (of the whole team); ``cost_words``: how the task's loss combines its agents (tasks.base.cost_words)."""
    plt = matplotlib_agg()
    colors = group_color(rec.group) if rec.labelled else ["#4e79a7"] * rec.n_agents
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.8), dpi=110, gridspec_kw={"width_ratios": [1, 1.15]})
    xlim, ylim, _ = view_limits(window, rec.pos, rec.goal)
    for i in range(rec.n_agents):
        a.plot(rec.pos[:, i, 0], rec.pos[:, i, 1], color=colors[i], lw=0.8, alpha=0.8)
    a.scatter(rec.pos[0, :, 0], rec.pos[0, :, 1], s=16, facecolors="none", edgecolors=colors, lw=0.8,
              label="start")
    a.scatter(rec.pos[-1, :, 0], rec.pos[-1, :, 1], s=16, c=colors, label="end")
    goal_colors = colors if rec.labelled else ["#555555"] * len(rec.goal)
    a.scatter(rec.goal[:, 0], rec.goal[:, 1], marker="x", s=22, c=goal_colors, lw=1.0, label="goal")
    hits = np.argwhere(rec.collide)
    if len(hits):
        a.scatter(rec.pos[hits[:, 0] + 1, hits[:, 1], 0], rec.pos[hits[:, 0] + 1, hits[:, 1], 1], s=50,
                  facecolors="none", edgecolors=COLLISION_COLOR, lw=1.0, label="collision")
    a.set_xlim(*xlim)
    a.set_ylim(*ylim)
    a.set_aspect("equal")
    a.set_title("paths (colour: group)", fontsize=9)
    a.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=4, frameon=False)
    a.tick_params(labelsize=7)
    steps = np.arange(1, rec.steps + 1)
    b.plot(steps, rec.cost, color="#333333", lw=1.2, label="loss of the step (left axis)")
    b.set_xlabel("step", fontsize=8)
    b.set_ylabel(f"loss of the step, {cost_words}", fontsize=8)
    b.set_yscale("log")
    b2 = b.twinx()
    din, dout = rec.degrees()
    b2.step(steps, din, where="mid", color="#4e79a7", lw=1.0, label="max in-degree (right axis)")
    b2.step(steps, dout, where="mid", color="#e15759", lw=1.0, ls="--", label="max out-degree (right axis)")
    b2.set_ylabel("agents (max in-, out-degree)", fontsize=8)
    b2.set_ylim(0, max(1.0, float(max(din.max(), dout.max()))) * 1.15)
    h1, l1 = b.get_legend_handles_labels()
    h2, l2 = b2.get_legend_handles_labels()
    b.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper right", frameon=False)
    b.set_title(f"loss {rec.cost.mean():.2f} (time-averaged); collisions {int(rec.collide.sum())} agent-steps",
                fontsize=9)
    for ax in (b, b2):
        ax.tick_params(labelsize=7)
    fig.suptitle(wrap_title(title) + window_note(window), fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)
