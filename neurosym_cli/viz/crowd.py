"""Frames of a large team (``render.crowd_from`` agents on, e.g. the swarm task's 1,000): what stays readable.

Every agent is a small point coloured by its group with a short trail that fades with age; goals are faint dots.
Drawing every edge of a thousand agents is a solid smear, so only the edges of a fixed random sample of receivers
(``render.receivers``, drawn once from the seed, ringed in black) are drawn, each from the heard agent to the
listener, coloured by rule for a program as in the small-team frames (animate.py). The line under the title counts
the edges drawn of all the edges of the step.
"""

from __future__ import annotations

import numpy as np

from ..episode import EpisodeRecord
from .draw import (COLLISION_COLOR, DIRECTION, EDGE_COLOR, GROUP_COLORS, RULE_COLORS, BlitScene, Links, edge_handles,
                   edge_segments, group_color, head_size, in_window, matplotlib_agg, view_limits, window_note,
                   wrap_title)


def sample_receivers(n: int, count: int, seed: int, among: np.ndarray | None = None) -> np.ndarray:
    """(S,) sorted agent indices, S = min(count, candidates), drawn without replacement from ``seed``, among the
    agents where ``among`` (N,) bool is true (all when None)."""
    pool = np.arange(n) if among is None else np.flatnonzero(among)
    return np.sort(np.random.default_rng(seed).choice(pool, size=min(count, len(pool)), replace=False))


def window_receivers(rec: EpisodeRecord, window: list[float] | None) -> np.ndarray | None:
    """(N,) bool, the agents a zoomed crowd frame samples its receivers from: those in ``window`` at the start,
    else those that enter it at some step; None without a window."""
    if window is None:
        return None
    start = in_window(window, rec.pos[0])
    if start.any():
        return start
    return np.any([in_window(window, p) for p in rec.pos], axis=0)


class CrowdScene(BlitScene):
    """The crowd frames of one episode; ``drawn`` and ``total`` are the edge counts of the last ``draw``."""

    def __init__(self, rec: EpisodeRecord, title: str, style: str, *, round_: int, trail: int, receivers: int,
                 seed: int = 0, width: float = 10.0, dpi: int = 90, window: list[float] | None = None):
        from matplotlib.collections import LineCollection
        from matplotlib.colors import to_rgba
        from matplotlib.lines import Line2D

        plt = matplotlib_agg()
        self.rec, self.style, self.round, self.trail = rec, style, round_, trail
        self.recv = sample_receivers(rec.n_agents, receivers, seed, window_receivers(rec, window))  # (S,)
        self.color = np.array([to_rgba(c) for c in (group_color(rec.group) if rec.labelled
                                                    else [GROUP_COLORS[0]] * rec.n_agents)])  # (N, 4)
        self.drawn = self.total = 0
        xlim, ylim, ratio = view_limits(window, rec.pos, rec.goal, ratio=(0.75, 5.0))  # fronts are long and thin
        self.fig, ax = plt.subplots(figsize=(width, width / ratio + 1.5), dpi=dpi)
        self.ax = ax
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        goal_colors = self.color if rec.labelled else "#555555"
        ax.scatter(rec.goal[:, 0], rec.goal[:, 1], s=3, c=goal_colors, alpha=0.25, lw=0, zorder=1)
        self.trails = LineCollection([], lw=0.7, zorder=2, animated=True)
        ax.add_collection(self.trails)
        self.agents = ax.scatter(rec.pos[0, :, 0], rec.pos[0, :, 1], s=5, c=self.color, lw=0, zorder=3,
                                 animated=True)
        self.links = Links(ax, lw=0.6, zorder=4, head=head_size(xlim, ylim, share=0.008))
        self.marked = ax.scatter([], [], s=22, facecolors="none", edgecolors="black", linewidths=0.8, zorder=5,
                                 animated=True)
        self.rings = ax.scatter([], [], s=16, facecolors="none", edgecolors=COLLISION_COLOR, linewidths=0.7,
                                zorder=5, animated=True)
        self.text = ax.text(0.5, 1.015, "", transform=ax.transAxes, ha="center", va="bottom", fontsize=8,
                            family="monospace", animated=True)
        self.moving = (self.trails, self.agents, *self.links.artists, self.marked, self.rings, self.text)
        groups = sorted(set(rec.group.tolist())) if rec.labelled else [0]
        self.fig.suptitle(wrap_title(title) + f"\npoints: agents by group, trails: last {trail} steps (fading); "
                          f"edges of {len(self.recv)} of {rec.n_agents} receivers sampled at random (ringed), "
                          f"{DIRECTION}{window_note(window)}",
                          fontsize=8)
        handles = [Line2D([], [], marker="o", ls="", color=GROUP_COLORS[g % len(GROUP_COLORS)], ms=4,
                          label=f"group {g}" if rec.labelled else "agent") for g in groups]
        handles += [Line2D([], [], marker="o", ls="", color="#888888", alpha=0.4, ms=3, label="goals"),
                    Line2D([], [], marker="o", ls="", mfc="none", mec="black", ms=6, label="sampled receiver"),
                    Line2D([], [], marker="o", ls="", mfc="none", mec=COLLISION_COLOR, ms=5, label="collision")]
        handles += edge_handles(style, rec.picks)
        ncol = min(len(handles), 5)
        rows = -(-len(handles) // ncol)
        self.fig.legend(handles=handles, fontsize=6.5, loc="lower center", ncol=ncol, frameon=False)
        height = self.fig.get_size_inches()[1]
        self.fig.tight_layout(rect=(0, (0.08 + 0.16 * rows) / height, 1, 0.96))
        self.keep_background()

    def _trails(self, t: int) -> tuple[np.ndarray, np.ndarray]:
        """Segments (L N, 2, 2) of the last L <= trail steps before t and their colours, older ones fainter."""
        lo = max(0, t - self.trail)
        p = self.rec.pos[lo:t + 1]  # (L + 1, N, 2)
        if len(p) < 2:
            return np.zeros((0, 2, 2)), np.zeros((0, 4))
        seg = np.stack([p[:-1], p[1:]], 2).reshape(-1, 2, 2)  # (L N, 2, 2), step-major
        age = np.linspace(0.08, 0.6, len(p) - 1)  # alpha from the oldest step to the newest
        colors = np.repeat(self.color[None], len(p) - 1, 0)  # (L, N, 4)
        colors[..., 3] = age[:, None]
        return seg, colors.reshape(-1, 4)

    def _edges(self, s: int, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Segments (E, 2, 2) from the heard agent to each sampled receiver at step s, and colours (E, 4)."""
        from matplotlib.colors import to_rgba

        e = self.rec.edges
        rows = e.of(s, self.round, self.recv)  # (E_s,) the sampled receivers' edges
        seg = edge_segments(pos, e.recv[rows], e.sent[rows])
        if self.style == "rules":
            assert e.rule is not None
            colors = np.array([to_rgba(RULE_COLORS[int(x) % len(RULE_COLORS)], 0.65)
                               for x in e.rule[rows]]).reshape(-1, 4)
        else:
            colors = np.tile(to_rgba(EDGE_COLOR, 0.7), (len(seg), 1))
            if self.style == "weights":
                colors[:, 3] = np.clip(e.weight[rows], 0.05, 1.0)
        return seg, colors

    def draw(self, t: int) -> None:
        """Show the state after ``t`` steps with the sampled receivers' edges of step t (the last step's at the
        end)."""
        rec = self.rec
        s = min(t, rec.steps - 1)
        pos = rec.pos[t]
        seg, colors = self._trails(t)
        self.trails.set_segments(seg)
        self.trails.set_color(colors)
        self.agents.set_offsets(pos)
        seg, colors = self._edges(s, pos)
        self.links.set(seg, colors)
        self.drawn, self.total = len(seg), rec.edges.count(s, self.round)
        self.marked.set_offsets(pos[self.recv] if len(self.recv) else np.zeros((0, 2)))
        hit = rec.collide[t - 1] if t > 0 else np.zeros(rec.n_agents, bool)
        self.rings.set_offsets(pos[hit] if hit.any() else np.zeros((0, 2)))
        loss = f"{rec.cost[:t].mean():8.2f}" if t > 0 else "       -"
        self.text.set_text(f"step {t:>3}/{rec.steps}  loss so far {loss}  edges drawn {self.drawn} of "
                           f"{self.total}  colliding {int(hit.sum())}")
