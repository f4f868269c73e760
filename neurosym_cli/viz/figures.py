"""The paper's pictures of whom agents talk to, from recorded episodes (``episode.py``):

    attention_maps   Figures 1b, 3b, 5c: the N x N attention actually used at one step, baselines side by side,
                     one map per round, in- and out-degrees annotated
    trajectories     Figure 3a: group-averaged paths of two baselines (solid vs dashed) in one or more episodes
    figure1          Figure 1: two groups, their starts, goals and paths, and the attention at the first step
    rule_regions     Figure 4: each rule of a program over the plane, for one asking agent: where a hypothetical
                     other agent passes the rule's filter (random rules) and its score (argmax rules), computed
                     by the DSL's own evaluator, so the picture cannot drift from the semantics
    unlabeled_scene  Figure 5: starts, ends and goals of an unlabeled-goals episode, with both rounds' attention
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Sequence

import numpy as np
import torch

from ..dsl.ast import ArgMaxRule, Program
from ..dsl.interpret import cond, linear
from ..dsl.printer import describe, rule_text
from ..tasks.features import FeatureMap
from ..episode import EpisodeRecord
from .draw import (DIRECTION, GROUP_COLORS, RULE_COLORS, Links, edge_segments, frame_limits, group_color, head_size,
                   matplotlib_agg, save_figure, wrap_title)


def _order(rec: EpisodeRecord) -> np.ndarray:
    """Agents sorted by group (stable), so a map shows each group as a block."""
    return np.argsort(rec.group, kind="stable")


def attention_panel(ax, rec: EpisodeRecord, step: int, round_: int, label: str):
    """One N x N map: row i = listener, column j = heard agent, colour = attention weight a_ij actually used."""
    order = _order(rec)
    a = rec.edges.weights(step, round_)[np.ix_(order, order)]
    m = rec.edges.mask(step, round_)  # in- and out-degrees do not depend on the order
    im = ax.imshow(a, cmap="magma_r", vmin=0.0, vmax=1.0, interpolation="nearest")  # weights lie in [0, 1]
    if not m.any():
        ax.text(0.5, 0.5, "nobody hears anybody\nat this step", ha="center", va="center", transform=ax.transAxes,
                fontsize=8, color="#555555")
    groups = rec.group[order]
    for k in np.nonzero(np.diff(groups))[0]:  # group boundaries
        ax.axhline(k + 0.5, color="#4e79a7", lw=0.8)
        ax.axvline(k + 0.5, color="#4e79a7", lw=0.8)
    din, dout = int(m.sum(1).max()), int(m.sum(0).max())
    ax.set_title(f"{label}\nmax in-degree {din}, max out-degree {dout}", fontsize=8)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("heard agent j (sorted by group)", fontsize=7)
    ax.set_ylabel("listening agent i", fontsize=7)
    ax.tick_params(labelsize=6)
    return im


def attention_maps(recs: Sequence[tuple[str, EpisodeRecord]], step: int, path: Path, title: str) -> Path:
    """Attention maps of several baselines at one step (one map per round), with a shared colour bar each."""
    plt = matplotlib_agg()
    rounds = recs[0][1].rounds
    cols = len(recs) * rounds
    fig, axes = plt.subplots(1, cols, figsize=(3.6 * cols + 0.6, 4.0), dpi=110, squeeze=False)
    for k, (label, rec) in enumerate(recs):
        for r in range(rounds):
            ax = axes[0, k * rounds + r]
            name = label + (f", round {r + 1}" if rounds > 1 else "")
            im = attention_panel(ax, rec, min(step, rec.steps - 1), r, name)
            fig.colorbar(im, ax=ax, fraction=0.046, pad=0.03).ax.tick_params(labelsize=6)
    fig.suptitle(wrap_title(title) + f" (step {step}; colour: attention weight a_ij, rows sum to 1 or 0)",
                 fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def _group_paths(rec: EpisodeRecord) -> dict[int, np.ndarray]:
    """group -> (T + 1, 2) mean position of its agents over time."""
    return {int(g): rec.pos[:, rec.group == g].mean(1) for g in np.unique(rec.group)}


def trajectories(panels: Sequence[tuple[str, Sequence[tuple[str, EpisodeRecord]]]], path: Path, title: str) -> Path:
    """Figure 3a: per panel (its name, [(baseline label, record of the same episode)]), each group's mean path, the
    first baseline solid and the second dashed; start boxes as dots, goals as crosses."""
    from matplotlib.lines import Line2D

    plt = matplotlib_agg()
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 5.2), dpi=110, squeeze=False)
    styles = ("-", "--", ":")
    for ax, (name, recs) in zip(axes[0], panels):
        first = recs[0][1]
        xlim, ylim, _ = frame_limits(*[r.pos for _, r in recs], first.goal, ratio=(0.9, 1.1))
        colors = group_color(first.group)
        ax.scatter(first.pos[0, :, 0], first.pos[0, :, 1], s=8, c=colors, alpha=0.5)
        ax.scatter(first.goal[:, 0], first.goal[:, 1], marker="x", s=14, c=colors, alpha=0.6, lw=0.8)
        for k, (label, rec) in enumerate(recs):
            for g, p in _group_paths(rec).items():
                ax.plot(p[:, 0], p[:, 1], ls=styles[k % 3], color=GROUP_COLORS[g % len(GROUP_COLORS)], lw=1.8)
                ax.plot(*p[-1], marker="o", ms=4, color=GROUP_COLORS[g % len(GROUP_COLORS)])
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=8)
        ax.tick_params(labelsize=7)
        handles = [Line2D([], [], color="#333333", ls=styles[k % 3], label=f"{label}: loss {rec.cost.mean():.1f}")
                   for k, (label, rec) in enumerate(recs)]
        handles += [Line2D([], [], marker="o", ls="", color="#777777", ms=3, label="starts"),
                    Line2D([], [], marker="x", ls="", color="#777777", ms=4, label="goals")]
        ax.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=2,
                  frameon=False)
    fig.suptitle(wrap_title(title) + " (lines: mean position of each group, colour: group)", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def _scene(ax, rec: EpisodeRecord, step: int | None = None, round_: int = 0, group_mean: bool = True) -> None:
    """Starts (open), ends (filled), goals (x) and paths of one episode; with ``step``, that step's edges."""
    colors = group_color(rec.group) if rec.labelled else ["#4e79a7"] * rec.n_agents
    xlim, ylim, _ = frame_limits(rec.pos, rec.goal)
    if group_mean and rec.labelled:
        for g, p in _group_paths(rec).items():
            ax.plot(p[:, 0], p[:, 1], color=GROUP_COLORS[g % len(GROUP_COLORS)], lw=2.0, alpha=0.9)
    else:
        for i in range(rec.n_agents):
            ax.plot(rec.pos[:, i, 0], rec.pos[:, i, 1], color=colors[i], lw=0.7, alpha=0.6)
    if step is not None:
        i, j, _ = rec.edges.at(step, round_)
        seg = edge_segments(rec.pos[step], i, j)
        from matplotlib.colors import to_rgba

        Links(ax, lw=0.7, zorder=2, head=head_size(xlim, ylim), animated=False).set(seg, [to_rgba("#333333", 0.6)])
    ax.scatter(rec.pos[0, :, 0], rec.pos[0, :, 1], s=18, facecolors="none", edgecolors=colors, lw=0.9)
    ax.scatter(rec.pos[-1, :, 0], rec.pos[-1, :, 1], s=14, c=colors)
    goal_colors = colors if rec.labelled else ["#555555"] * len(rec.goal)
    ax.scatter(rec.goal[:, 0], rec.goal[:, 1], marker="x", s=20, c=goal_colors, lw=0.9)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)


def figure1(full: tuple[str, EpisodeRecord], prog: tuple[str, EpisodeRecord], path: Path, title: str) -> Path:
    """Figure 1: (a) the two groups' starts (open), goals (x) and mean paths under the program, with whom each agent
    hears at the first step; (b), (c) the attention at the first step of the full transformer and of the program."""
    plt = matplotlib_agg()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), dpi=110, gridspec_kw={"width_ratios": [1.5, 1, 1]})
    _scene(axes[0], prog[1], step=0)
    axes[0].set_title(f"(a) {prog[0]}: starts (open), goals (x), group paths;\nwhom each agent hears at step 0, "
                      f"{DIRECTION}", fontsize=8)
    for ax, (label, rec), tag in ((axes[1], full, "(b)"), (axes[2], prog, "(c)")):
        im = attention_panel(ax, rec, 0, 0, f"{tag} {label}, step 0")
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.03).ax.tick_params(labelsize=6)
    fig.suptitle(wrap_title(title), fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def unlabeled_scene(label: str, rec: EpisodeRecord, step: int, path: Path, title: str) -> Path:
    """Figure 5: starts (open), ends (filled) and goals (x) of every agent, and the attention of each round."""
    plt = matplotlib_agg()
    rounds = rec.rounds
    fig, axes = plt.subplots(1, 1 + rounds, figsize=(4.6 * (1 + rounds), 4.4), dpi=110)
    _scene(axes[0], rec, group_mean=False)
    axes[0].set_title(f"(a) {label}: starts (open), ends (filled), goals (x)\nloss {rec.cost.mean():.3f} "
                      f"(time-averaged), {rec.cost[-1]:.3f} at the last step", fontsize=8)
    for r in range(rounds):
        im = attention_panel(axes[1 + r], rec, min(step, rec.steps - 1), r, f"({chr(98 + r)}) round {r + 1}, "
                             f"step {step}")
        fig.colorbar(im, ax=axes[1 + r], fraction=0.046, pad=0.03).ax.tick_params(labelsize=6)
    fig.suptitle(wrap_title(title), fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def rule_grid(program: Program, round_: int, fmap: FeatureMap, *, pair_dim: int, agent_input: np.ndarray,
              origin: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> list[tuple[np.ndarray, np.ndarray | None]]:
    """For each rule of the round: where a hypothetical other agent at each grid point passes the rule's filter,
    (len(ys), len(xs)) bool, and for an argmax rule the score it would get there (else None).

    agent_input: (Ds,) the asking agent's input s_i; origin: (2,) its position. Each grid point is a bucket of two
    agents (the asking agent and the hypothetical one), observed without noise, evaluated by ``dsl.interpret``."""
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx.ravel(), gy.ravel()], -1) - origin  # (G, 2): o_ij of the hypothetical agent
    g = len(pts)
    agent = torch.as_tensor(agent_input, dtype=torch.float32).expand(g, 2, -1)
    rel = torch.zeros(g, 2, 2, pair_dim)  # columns beyond the offset (velocities, ...) are 0: an agent at rest
    rel[:, 0, 1, :2] = torch.as_tensor(pts, dtype=torch.float32)
    rel[:, 1, 0, :2] = -rel[:, 0, 1, :2]
    feats = fmap.view(agent, rel)
    out = []
    for rule in program.rounds[round_]:
        keep = cond(rule.cond, feats)[:, 0, 1].reshape(gy.shape).numpy()
        score = linear(rule.score, feats)[:, 0, 1].reshape(gy.shape).numpy() if isinstance(rule, ArgMaxRule) \
            else None
        out.append((keep, score))
    return out


def rule_regions(program: Program, fmap: FeatureMap, pair_dim: int, rec: EpisodeRecord, *, agent: int, step: int,
                 round_: int, path: Path, title: str, grid: int = 160) -> Path:
    """Figure 4: one panel per rule, for agent ``agent`` at ``step``: shaded where another agent would pass the
    rule's filter; for an argmax rule, the score there as a heat map; the other agents as dots and the agent the
    rule picked at that step ringed."""
    plt = matplotlib_agg()
    rules = program.rounds[round_]
    xlim, ylim, _ = frame_limits(rec.pos[step], rec.goal, ratio=(0.8, 1.25))
    xs, ys = np.linspace(*xlim, grid), np.linspace(*ylim, grid)
    regions = rule_grid(program, round_, fmap, pair_dim=pair_dim, agent_input=rec.inputs[step, agent],
                        origin=rec.pos[step, agent], xs=xs, ys=ys)
    cols = min(len(rules), 3)
    rows = (len(rules) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 5.4 * rows), dpi=110, squeeze=False)
    others = np.arange(rec.n_agents) != agent
    for k, (rule, (keep, score)) in enumerate(zip(rules, regions)):
        ax = axes[k // cols, k % cols]
        color = RULE_COLORS[k % len(RULE_COLORS)]
        extent = (*xlim, *ylim)
        if score is not None:
            im = ax.imshow(np.where(keep, score, np.nan), origin="lower", extent=extent, cmap="viridis",
                           aspect="equal", interpolation="nearest")
            bar = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.03)
            bar.set_label("score (argmax picks the highest)", fontsize=7)
            bar.ax.tick_params(labelsize=6)
        else:
            from matplotlib.colors import ListedColormap

            ax.imshow(np.where(keep, 1.0, np.nan), origin="lower", extent=extent, aspect="equal",
                      cmap=ListedColormap([color]), alpha=0.25, interpolation="nearest")
        ax.scatter(rec.goal[:, 0], rec.goal[:, 1], marker="x", s=12, c="#999999", lw=0.7, zorder=2, label="goals")
        ax.scatter(rec.pos[step, others, 0], rec.pos[step, others, 1], s=10, c="#555555", zorder=3,
                   label="other agents")
        if not keep.any():  # a guard on the agent's own state that fails, or a filter nobody here could pass
            ax.text(0.5, 0.5, "no agent anywhere passes the filter:\nthis rule asks nobody now", ha="center",
                    va="center", transform=ax.transAxes, fontsize=8, color=color)
        ax.scatter(*rec.pos[step, agent], marker="*", s=140, c=color, edgecolors="black", lw=0.6, zorder=4,
                   label=f"asking agent {agent}")
        if rec.picks is not None:
            j = int(rec.picks[step, round_, agent, k])
            if j >= 0:
                ax.scatter(*rec.pos[step, j], s=120, facecolors="none", edgecolors="red", lw=1.5, zorder=5,
                           label=f"picked: agent {j}")
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        kind_text = "shaded: passes the filter" if score is None else "coloured: passes the filter"
        reading = textwrap.fill(describe(rule, fmap.vocab), 70)
        ax.set_title(f"rule {k + 1}: {rule_text(rule)}\n{reading}\n({kind_text})", fontsize=7)
        ax.legend(fontsize=6, loc="lower right", framealpha=0.8)
        ax.tick_params(labelsize=7)
    for k in range(len(rules), rows * cols):
        axes[k // cols, k % cols].axis("off")
    fig.suptitle(wrap_title(title) + f" (agent {agent}, step {step})", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)
