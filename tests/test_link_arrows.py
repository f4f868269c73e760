"""Links in renders and figures are arrows from the agent heard to the agent hearing it, and the pictures say so
(issue 40)."""

import numpy as np
import torch

from neurosym_cli.viz.draw import DIRECTION, arrow_heads, edge_handles, trim


def test_an_arrowhead_points_at_the_listener():
    seg = np.array([[[0.0, 0.0], [10.0, 0.0]], [[3.0, 4.0], [0.0, 0.0]]])  # speaker -> listener
    heads = arrow_heads(seg, 1.0)
    assert heads.shape == (2, 3, 2)
    assert np.allclose(heads[:, 0], seg[:, 1])  # the tip is at the listener's end
    assert np.allclose(heads[0, 1:], [[9.0, 0.5], [9.0, -0.5]])  # the base 1 behind it, 1 wide
    assert np.allclose(heads[1, 1:].mean(0), [0.6, 0.8])  # behind the tip, towards the speaker
    assert np.allclose(arrow_heads(seg, 20.0)[0, 1:].mean(0), [5.0, 0.0])  # at most half the link
    assert np.allclose(trim(seg, 1.0)[0], [[1.0, 0.0], [9.0, 0.0]])


def test_a_rendered_frame_draws_an_arrow_into_each_listener(tmp_path):
    from test_render import _program, _setup

    from neurosym_cli.episode import protocol_episode, record_episode
    from neurosym_cli.viz.animate import _Scene

    env, policy = _setup(horizon=4)
    state, gen, _ = protocol_episode(env, 1)
    rec = record_episode(env, policy, _program(), state, gen, torch.device("cpu"))
    scene = _Scene(rec, "test: prog", "rules", round_=0, trail=3)
    try:
        scene.draw(1)
        i, j, _ = rec.edges.at(1, 0)
        tips = np.array([p.vertices[0] for p in scene.links.heads.get_paths()])
        assert len(i) > 0 and len(tips) == len(scene.links.lines.get_segments()) == len(i)
        pos = rec.pos[1]
        to_listener = np.linalg.norm(tips - pos[i], axis=1)
        assert (to_listener < np.linalg.norm(tips - pos[j], axis=1)).all()
        assert (to_listener <= scene.links.gap + 1e-6).all()  # the tip touches the listener's marker
        assert DIRECTION in scene.fig._suptitle.get_text()
        assert all(h.get_marker() == ">" for h in edge_handles("rules", rec.picks))
    finally:
        scene.close()
