"""Where every artifact of an experiment lives (stdlib only, so light commands need no torch).

    <exp_dir>/train/<model>/            model.pt, history.csv, manifest.json
    <exp_dir>/synth/dataset-r<R>-s<S>.pt  the oracle dataset D, shared by every synthesis run of this oracle
    <exp_dir>/synth/<program tag>/      program.txt, summary.json, trace.csv
    <exp_dir>/eval/<baseline label>/    metrics.json, metrics.csv
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from .config import RunConfig


def user_program_tag(cfg: RunConfig) -> str | None:
    """'file-<stem>-<8 hex of its SHA-1>-<features>' for a program given as program=PATH, else None: results of a
    hand-written program never take the name (and overwrite the results) of a synthesized one, and two different
    files never share one."""
    if not cfg.program:
        return None
    path = Path(cfg.program)
    try:
        digest = hashlib.sha1(path.read_bytes()).hexdigest()[:8]
    except OSError:  # missing or unreadable: loading it reports that in one line
        digest = "unreadable"
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", path.stem)[:40] or "program"
    return f"file-{stem}-{digest}-{cfg.features}"


def model_name(cfg: RunConfig) -> str:
    """Directory name of the weights a baseline uses: the shared oracle, or its own trained model."""
    if cfg.baseline.model == "oracle":
        return "oracle"
    if cfg.baseline.model == "retrained":
        return f"retrained-{program_tag(cfg)}"
    if cfg.baseline.comm == "gated":
        return f"{cfg.baseline.name}-{rl_tag(cfg)}"
    return cfg.baseline.name if cfg.baseline.comm == "none" else f"{cfg.baseline.name}-k{cfg.rules}"


def rl_tag(cfg: RunConfig) -> str:
    """The settings of an rl model (appendix D): cost weight, reward form, starting point, e.g. c0.1-togo-oracle."""
    return f"c{cfg.rl.cost:g}-{'togo' if cfg.rl.shaped else 'episode'}-{cfg.rl.init}"


def _search_variants(cfg: RunConfig) -> list[tuple[str, str]]:
    """(name suffix, override) for each way a program's search differs from the default: the reference's hinge
    objective, scores kept to the other agent's features. Trees have neither."""
    if cfg.baseline.comm == "tree":
        return []
    out = []
    if cfg.synth.objective != "paper":
        out.append((f"-{cfg.synth.objective}", f" synth.objective={cfg.synth.objective}"))
    if not cfg.synth.own_scores:
        out.append(("-otherscores", " synth.own_scores=false"))
    if not cfg.synth.simplify:
        out.append(("-unsimplified", " synth.simplify=false"))
    if cfg.synth.coarse > 1:
        out.append((f"-coarse{cfg.synth.coarse}", f" synth.coarse={cfg.synth.coarse}"))
    if cfg.synth.patience:
        out.append((f"-patience{cfg.synth.patience}", f" synth.patience={cfg.synth.patience}"))
    return out


def _search_tag(cfg: RunConfig) -> str:
    """K, lambda, feature map and search variant of a synthesized program (or a hand-written program's tag)."""
    if cfg.program:
        return user_program_tag(cfg)  # type: ignore[return-value]
    return f"k{cfg.rules}-lam{cfg.lam:g}-{cfg.features}" + "".join(suffix for suffix, _ in _search_variants(cfg))


def program_tag(cfg: RunConfig) -> str:
    """Name of one synthesis result: det- for argmax-only programs, K, lambda, feature map, and how the search
    differs from the default (dt: K, features); a hand-written program is named by file and content."""
    if cfg.baseline.comm == "tree":
        return f"dt-k{cfg.rules}-{cfg.features}"
    return ("det-" if cfg.baseline.det and not cfg.program else "") + _search_tag(cfg)


def baseline_label(cfg: RunConfig) -> str:
    """Name of a baseline's evaluation directory (k, and the program's tag, where they matter)."""
    if cfg.baseline.comm in ("full", "none"):
        return cfg.baseline.name
    if cfg.baseline.comm == "program":
        return f"{cfg.baseline.name}-{_search_tag(cfg)}"
    if cfg.baseline.comm == "tree":
        return f"{cfg.baseline.name}-k{cfg.rules}-{cfg.features}"
    if cfg.baseline.comm == "gated":
        return model_name(cfg)
    return f"{cfg.baseline.name}-k{cfg.rules}"


def train_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "train" / model_name(cfg)


def oracle_checkpoint(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "train" / "oracle" / "model.pt"


def synth_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "synth" / program_tag(cfg)


def program_file(cfg: RunConfig) -> Path:
    return Path(cfg.program) if cfg.program else synth_dir(cfg) / "program.txt"


def tree_file(cfg: RunConfig) -> Path:
    return synth_dir(cfg) / "tree.json"


def dataset_file(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "synth" / f"dataset-r{cfg.budget.synth_rollouts}-s{cfg.synth.stride}.pt"


def render_dir(cfg: RunConfig) -> Path:
    """Animations and episode pictures of one baseline (`neurosym render`)."""
    return Path(cfg.exp_dir) / "render" / baseline_label(cfg)


def figures_dir(cfg: RunConfig) -> Path:
    """The paper's figures drawn from this run directory (`neurosym figures`)."""
    return Path(cfg.exp_dir) / "figures"


def tensorboard_dir(cfg: RunConfig, run: str) -> Path:
    """TensorBoard event files of one run of this experiment (logger=tensorboard), e.g. run = "train-oracle"."""
    return Path(cfg.exp_dir) / "tensorboard" / run


def eval_dir(cfg: RunConfig) -> Path:
    return Path(cfg.exp_dir) / "eval" / baseline_label(cfg)


def train_command(cfg: RunConfig, oracle: bool = False) -> str:
    """The command line that makes the weights ``cfg``'s baseline needs (or the oracle's)."""
    if cfg.baseline.model == "retrained" and not oracle:
        return retrain_command(cfg)
    own = cfg.baseline.model == "own" and not oracle
    base = cfg.baseline.name if own else "tf-full"
    k = ""
    if own and cfg.baseline.comm == "gated":
        k = f" rl.cost={cfg.rl.cost:g} rl.shaped={str(cfg.rl.shaped).lower()} rl.init={cfg.rl.init}"
    elif own and cfg.baseline.comm != "none":
        k = f" rules={cfg.rules}"
    return f"neurosym train task={cfg.task.name} baseline={base} budget={cfg.budget.name} seed={cfg.seed}{k}"


def retrain_command(cfg: RunConfig) -> str:
    det = " baseline=det-prog-retrained" if cfg.baseline.det else ""
    det = " baseline=dt-retrained" if cfg.baseline.comm == "tree" else det
    obj = "".join(override for _, override in _search_variants(cfg))
    prog = f" program={cfg.program}" if cfg.program and cfg.baseline.comm == "program" else ""
    return (f"neurosym retrain task={cfg.task.name} rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}"
            f" budget={cfg.budget.name} seed={cfg.seed}{det}{obj}{prog}")


def synth_command(cfg: RunConfig) -> str:
    det = " baseline=det-prog" if cfg.baseline.det else ""
    det = " baseline=dt" if cfg.baseline.comm == "tree" else det
    obj = "".join(override for _, override in _search_variants(cfg))
    return (f"neurosym synth task={cfg.task.name} rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}"
            f" budget={cfg.budget.name} seed={cfg.seed}{det}{obj}")
