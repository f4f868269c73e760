"""Drawing helpers shared by every episode picture: colours, world limits, the agents-and-goals scene, saving."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..utils.io import atomic_file

GROUP_COLORS = ("#4e79a7", "#f28e2b", "#59a14f", "#b07aa1", "#76b7b2", "#edc948", "#9c755f", "#ff9da7")
"""agents and goals by group (formation tasks); unlabeled agents all take the first"""
RULE_COLORS = ("#d62728", "#111111", "#17becf", "#bcbd22", "#8c564b", "#e377c2", "#7f7f7f", "#9467bd")
"""communication edges of a program, by the rule that chose them"""
EDGE_COLOR = "#333333"
"""edges of providers without rules (hard-attn, dist, dt) and soft attention (opacity = weight)"""
COLLISION_COLOR = "#d62728"


DIRECTION = "arrow j → i: agent i hears agent j"
"""what a link's arrowhead means, said under every picture that draws links"""


def edge_handles(style: str, picks) -> list:
    """Legend entries of the links a frame draws, each an arrow: one per rule ('rules'; ``picks`` (..., K) or
    None), else one for every link ('weights': opacity is the attention weight)."""
    from matplotlib.lines import Line2D

    def arrow(color: str, label: str) -> Line2D:
        return Line2D([], [], color=color, marker=">", ms=4, label=label)

    if style == "rules":
        k = picks.shape[-1] if picks is not None else 0
        return [arrow(RULE_COLORS[i % len(RULE_COLORS)], f"hears, by rule {i + 1}") for i in range(k)]
    return [arrow(EDGE_COLOR, "hears (opacity: attention weight)" if style == "weights" else "hears")]


def matplotlib_agg():
    """pyplot on the non-interactive Agg back-end (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def group_color(group: np.ndarray) -> list[str]:
    return [GROUP_COLORS[int(g) % len(GROUP_COLORS)] for g in group]


def frame_limits(*points: np.ndarray, margin: float = 0.06, ratio: tuple[float, float] = (0.75, 2.0)):
    """Limits around every point with a margin whose width/height stays within ``ratio`` (so a scene that is
    wide gets a wide frame, not a square one mostly empty): ((x0, x1), (y0, y1)), width / height."""
    xy = np.concatenate([p.reshape(-1, 2) for p in points])
    lo, hi = xy.min(0), xy.max(0)
    c, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-6) * (1 + 2 * margin)
    r = float(np.clip(half[0] / half[1], *ratio))
    half = np.maximum(half, [half[1] * r, half[0] / r])
    return (c[0] - half[0], c[0] + half[0]), (c[1] - half[1], c[1] + half[1]), float(half[0] / half[1])


def view_limits(window: list[float] | None, *points: np.ndarray, ratio: tuple[float, float] = (0.75, 2.0)):
    """``frame_limits`` of the points, or the ``window`` [x0, x1, y0, y1] (render.window) when given:
    ((x0, x1), (y0, y1)), and the figure's width / height within ``ratio`` (a window of any shape: equal axes
    leave the rest blank)."""
    if window is None:
        return frame_limits(*points, ratio=ratio)
    x0, x1, y0, y1 = window
    return (x0, x1), (y0, y1), float(np.clip((x1 - x0) / (y1 - y0), *ratio))


def in_window(window: list[float] | None, pos: np.ndarray) -> np.ndarray:
    """pos (N, 2) -> (N,) bool, whether each point lies in ``window`` (every point when it is None)."""
    if window is None:
        return np.ones(len(pos), bool)
    x0, x1, y0, y1 = window
    return (pos[:, 0] >= x0) & (pos[:, 0] <= x1) & (pos[:, 1] >= y0) & (pos[:, 1] <= y1)


def window_note(window: list[float] | None) -> str:
    """A title's last line about the window (with its leading newline): "" for the whole episode."""
    if window is None:
        return ""
    x0, x1, y0, y1 = window
    return f"\nzoomed to x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}] (render.window); agents outside are not shown"


def wrap_title(title: str) -> str:
    """A long title broken after its first colon, the way the figures' titles are built (what: which)."""
    head, sep, tail = title.partition(": ")
    return f"{head}:\n{tail}" if sep else title


def edge_segments(pos: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """pos (N, 2), edges i hears j (E,) each -> segments (E, 2, 2) from j to i."""
    return np.stack([pos[j], pos[i]], 1).reshape(-1, 2, 2)  # from the speaker j to the listener i


def _directions(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """segments (E, 2, 2) -> (unit directions (E, 2) from their first point to their second, lengths (E, 1))."""
    d = seg[:, 1] - seg[:, 0]
    length = np.linalg.norm(d, axis=1, keepdims=True)
    return d / np.maximum(length, 1e-12), length


def trim(seg: np.ndarray, gap: float) -> np.ndarray:
    """segments (E, 2, 2) with ``gap`` world units (at most a quarter of each) cut off both ends: a link stops at
    the edge of an agent's marker instead of under it."""
    if not len(seg):
        return seg
    u, length = _directions(seg)
    cut = u * np.minimum(gap, 0.25 * length)
    return np.stack([seg[:, 0] + cut, seg[:, 1] - cut], 1)


def arrow_heads(seg: np.ndarray, size: float) -> np.ndarray:
    """segments (E, 2, 2) from speaker to listener -> triangles (E, 3, 2) with their tip at each segment's listener
    end, pointing along it: ``size`` world units long (at most half the segment), half as wide."""
    if not len(seg):
        return np.zeros((0, 3, 2))
    u, length = _directions(seg)
    h = np.minimum(size, 0.5 * length)  # (E, 1)
    base = seg[:, 1] - u * h
    side = np.stack([-u[:, 1], u[:, 0]], 1) * h * 0.5
    return np.stack([seg[:, 1], base + side, base - side], 1)


class Links:
    """Directed links on an axes: a line from the agent heard to the agent hearing it, an arrowhead at the hearer
    (``head``: its length in world units; equal axes keep its shape), both ends trimmed by ``gap`` (default 0.4
    head: about an agent marker's radius). ``animated``: for blitted frames."""

    def __init__(self, ax, *, lw: float, zorder: float, head: float, gap: float | None = None,
                 animated: bool = True):
        from matplotlib.collections import LineCollection, PolyCollection

        self.head, self.gap = head, 0.4 * head if gap is None else gap
        self.lines = LineCollection([], lw=lw, zorder=zorder, animated=animated)
        self.heads = PolyCollection([], lw=0, zorder=zorder, animated=animated)
        ax.add_collection(self.lines)
        ax.add_collection(self.heads)

    @property
    def artists(self) -> tuple:
        return (self.lines, self.heads)

    def set(self, seg: np.ndarray, colors) -> None:
        """Show the links ``seg`` (E, 2, 2), speaker to listener, in ``colors`` (E, 4) RGBA, or one colour."""
        seg = trim(seg, self.gap)
        self.lines.set_segments(seg)
        self.lines.set_color(colors)
        self.heads.set_verts(arrow_heads(seg, self.head))
        self.heads.set_facecolor(colors)


def head_size(xlim, ylim, share: float = 0.018) -> float:
    """An arrowhead's length in world units: ``share`` of the larger side of the view."""
    return share * max(xlim[1] - xlim[0], ylim[1] - ylim[0])


def save_figure(fig, path: Path) -> Path:
    """Write a figure atomically (temp file, then rename) and close it."""
    plt = matplotlib_agg()
    try:
        with atomic_file(path) as tmp:
            fig.savefig(tmp, bbox_inches="tight", pad_inches=0.12)  # legends below the axes are kept, never clipped
    finally:
        plt.close(fig)
    return path


class BlitScene:
    """A figure whose moving artists (``self.moving``, drawn over ``self.ax``) are redrawn frame by frame over a
    background drawn once (blitting: fast). Subclasses build the figure, then call ``keep_background``."""

    fig: object
    ax: object
    moving: tuple

    def keep_background(self) -> None:
        self.fig.canvas.draw()
        self.background = self.fig.canvas.copy_from_bbox(self.fig.bbox)  # everything that never moves

    def frame(self) -> np.ndarray:
        """(H, W, 3) uint8 pixels of the current drawing: the background, then the moving parts over it."""
        self.fig.canvas.restore_region(self.background)
        for artist in self.moving:
            self.ax.draw_artist(artist)
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def close(self) -> None:
        matplotlib_agg().close(self.fig)
