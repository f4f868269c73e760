"""Draw a program's rules at the first step of evaluation episodes, without its trained models (paper Figure 4).

    python benchmarks/draw_program_rules.py --task random-grid --result docs/results/random-grid.json \
        --tag k2-lam0.5-v1 --episodes 0 1 --agent 0 --out docs/figures

At step 0 the agents' positions and inputs come from the task's episode generator alone, and a program's picks
depend only on them (and on the episode's random source), so no policy is needed: the weights used for the
roll-out of that one step are untrained and play no part in what is drawn. The program comes from a result file
of docs/results/ (the paper runs) or from a program file (--program).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from neurosym_cli.commands.apps import compose_config  # noqa: E402
from neurosym_cli.dsl.parser import parse  # noqa: E402
from neurosym_cli.tasks import make_task  # noqa: E402
from neurosym_cli.episode import protocol_episode, record_episode  # noqa: E402
from neurosym_cli.policy import CommTransformer  # noqa: E402
from neurosym_cli.policy.comm import ProgramComm  # noqa: E402
from neurosym_cli.viz.figures import rule_regions  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--task", required=True)
    ap.add_argument("--result", help="a docs/results/<variant>.json file")
    ap.add_argument("--tag", help="the program's name in that file (k2-lam0.5-v1)")
    ap.add_argument("--program", help="or a program file")
    ap.add_argument("--episodes", type=int, nargs="+", default=[0])
    ap.add_argument("--agent", type=int, default=0)
    ap.add_argument("--out", default="docs/figures")
    a = ap.parse_args()
    text = Path(a.program).read_text() if a.program else json.loads(Path(a.result).read_text())["programs"][a.tag]
    program = parse(text)
    tag = a.tag or Path(a.program).stem
    cfg = compose_config("figures", [f"task={a.task}", "budget=paper"])
    env = make_task(cfg.task, cfg.horizon)
    torch.manual_seed(0)
    policy = CommTransformer.for_task(env, cfg.model)  # untrained: see above
    comm = ProgramComm(program, env.features(cfg.features))
    names = list(cfg.task.test_settings)
    for k in a.episodes:
        state, gen, seed = protocol_episode(env, k)
        rec = record_episode(env, policy, comm, state, gen, torch.device("cpu"), horizon=1)
        setting = f", test setting {names[k % len(names)]}" if names else ""
        for r in range(program.n_rounds):
            out = f"{a.out}/{a.task}-rules-{tag}-episode{k}" + (f"-round{r + 1}" if program.n_rounds > 1 else "")
            path = rule_regions(program, comm.fmap, env.pair_dim, rec, agent=a.agent, step=0, round_=r,
                                path=Path(f"{out}.png"),
                                title=f"{a.task} (paper budget, train seed 0): rules of {tag}, episode {k}{setting}")
            print(f"drew {path}")


if __name__ == "__main__":
    main()
