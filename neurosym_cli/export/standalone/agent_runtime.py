"""One agent's decisions from a neurosym export folder: whom to ask (program.py), what to send when asked, what to
do with what it hears (agent/*.onnx). numpy and onnxruntime; nothing of neurosym. README.md has the message flow.

    team = Export("path/to/export")               # load once per process
    me = Agent(team, i)
    me.observe(s_i, o_i)                          # each step: own input (Ds,) and views of the others (N, Dp)
    for r in range(team.rounds):
        asked = me.whom(r, uniform)               # program: one agent per rule (-1: nobody)
        # send a request to each agent in set(asked) - {-1}; each answers with   m = it.message(r, i)
        me.receive(r, asked, {j: m_j})            # only the answers of the agents asked
    action = me.act()                             # the action as the task applies it (target inside, of it and s_i)
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np


def load_program(path):
    """The exported program module (program.py), from its file."""
    spec = importlib.util.spec_from_file_location("neurosym_exported_program", str(path))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def valid_slots(picks):
    """picks (K,) -> (K,) bool: a real agent, not picked by an earlier rule (an agent is heard once)."""
    seen, out = set(), []
    for p in picks:
        out.append(p >= 0 and p not in seen)
        if p >= 0:
            seen.add(p)
    return np.array(out, dtype=bool)


class Export:
    """The artifacts of one export folder, loaded once and shared by every agent of a process."""

    def __init__(self, folder):
        import onnxruntime as ort

        self.folder = Path(folder)
        self.manifest = json.loads((self.folder / "manifest.json").read_text())
        self.rounds = int(self.manifest["rounds"])
        self.program = load_program(self.folder / "program.py") if self.manifest["program"] else None
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1  # one agent's small matrices: threads cost more than they give
        opts.log_severity_level = 3

        def session(name):
            return ort.InferenceSession(str(self.folder / "agent" / name), opts, providers=["CPUExecutionProvider"])

        self.encode = session("encode.onnx")
        self.message = [session(f"message{r + 1}.onnx") for r in range(self.rounds)]
        self.receive = [session(f"receive{r + 1}.onnx") for r in range(self.rounds)]
        self.act = session("act.onnx")


class Agent:
    """Agent ``index`` of a team: keeps its own observation and its round inputs for one step."""

    def __init__(self, team: Export, index: int):
        self.team, self.index = team, index

    def observe(self, me, others):
        """me (Ds,) s_i; others (N, Dp) o_ij, row j = this agent's view of agent j."""
        self.me = np.asarray(me, dtype=np.float32)
        self.others = np.asarray(others, dtype=np.float32)
        self.h = self.team.encode.run(None, {"s": self.me[None]})[0]  # (1, D)
        self.x = [self.h]  # x[r]: the input of round r (round 1: h); kept to answer round r's requests

    def whom(self, r, uniform=None):
        """Round r (0-based): whom the program asks, one agent per rule (-1: nobody)."""
        fn = self.team.program.ROUNDS[r]
        return fn(self.me.tolist(), self.others.tolist(), self.index, uniform)

    def message(self, r, requester):
        """This agent's answer in round r to agent ``requester`` (which asked it): (D,). Uses its own view of the
        requester, o_ji = others[requester]."""
        o_ji = self.others[requester][None]
        return self.team.message[r].run(None, {"x": self.x[r], "o_ji": o_ji})[0][0]

    def receive(self, r, picks, messages):
        """Round r's update from the answers ``messages`` {j: (D,)} of the agents in ``picks`` (one slot per rule,
        -1 for nobody; an agent in two slots is heard once). An asked agent with no answer (a lost message) is
        not heard, as neurosym's link-failure model has it."""
        picks = [p if p in messages else -1 for p in picks] or [-1]  # a round asking nobody: one empty slot
        valid = valid_slots(picks)
        d = self.h.shape[-1]
        o_ij = np.zeros((1, len(picks), self.others.shape[-1]), np.float32)
        m = np.zeros((1, len(picks), d), np.float32)
        for k, p in enumerate(picks):
            if valid[k]:
                o_ij[0, k] = self.others[p]
                m[0, k] = messages[p]
        y = self.team.receive[r].run(None, {"x": self.x[r], "h": self.h, "o_ij": o_ij, "m": m,
                                            "valid": valid[None]})[0]
        self.x.append(y)

    def act(self):
        """The action (A,) as the task applies it, from the last round's output; ``self.raw`` keeps the
        transformer's output before the task's target (what a simulator's Task.step takes)."""
        feeds = {"y": self.x[-1], "s": self.me[None]}  # act.onnx has s only where the task's target reads it
        action, raw = self.team.act.run(None, {i.name: feeds[i.name] for i in self.team.act.get_inputs()})
        self.raw = raw[0]
        return action[0]


def team_step(team: Export, agents, agent_obs, rel_obs, uniforms=None, picks=None):
    """One step of every agent, message by message: agent_obs (N, Ds), rel_obs (N, N, Dp) (row i is agent i's own
    observations); ``uniforms(r, i)`` a zero-argument uniform source for agent i in round r (programs with random
    rules), or ``picks`` (R, N, K) whom each agent asks when the export has no program. Returns the actions (N, A)
    and the picks used, per round (N, K) each."""
    for i, a in enumerate(agents):
        a.observe(agent_obs[i], rel_obs[i])
    used = []
    for r in range(team.rounds):
        asked = [list(picks[r][i]) if picks is not None else a.whom(r, uniforms(r, i) if uniforms else None)
                 for i, a in enumerate(agents)]
        # every request of the round is answered from the sender's round-r input, before anybody updates
        answers = [{j: agents[j].message(r, i) for j in set(asked[i]) if j >= 0} for i in range(len(agents))]
        for i, a in enumerate(agents):
            a.receive(r, asked[i], answers[i])
        used.append(asked)
    return np.stack([a.act() for a in agents]), used
