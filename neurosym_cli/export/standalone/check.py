"""Replays an export folder's golden vectors through every artifact in it, without neurosym.

    python check.py [FOLDER] [--tolerance 1e-5] [--report report.json] [--require pt2,onnx]

program.py (plain Python), program.json (read by this file as its semantics say), program.h (compiled with the
system's cc, where there is one), policy.pt (TorchScript: torch), policy.pt2 (torch.export: torch), policy.onnx
and agent/*.onnx (onnxruntime), each on the recorded inputs: picks must agree exactly (random rules fed the
recorded uniforms), actions within the tolerance (max absolute difference, finite). Every file must also be the
one exported (the manifest's sha256). Prints one line per artifact; the first mismatch is named by file, episode,
step, round and agent. Exit 0: all agree; 1: a mismatch, a required format (--require) missing or not run, or
nothing replayed; 2: the folder cannot be read (no golden episode included). An artifact whose runtime is missing,
or a policy format the export could not write, is skipped, with the reason.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


class Mismatch(Exception):
    """The first disagreement of one artifact with the golden vectors."""


def where(e, t, i, r=None):
    return f"episode {e}, step {t}" + (f", round {r + 1}" if r is not None else "") + f", agent {i}"


class Golden:
    """golden.json and golden.npz; ValueError when they hold no step to replay or disagree on the episodes (a
    check of nothing must not pass)."""

    def __init__(self, folder: Path):
        self.meta = json.loads((folder / "golden.json").read_text())
        with np.load(folder / "golden.npz", allow_pickle=False) as z:  # arrays only, never pickles
            self.arrays = {k: z[k] for k in z.files}
        self.episodes = [m["episode"] for m in self.meta["episodes"]]
        held = sorted(int(k[1:-len("_agent")]) for k in self.arrays if k.startswith("e") and k.endswith("_agent"))
        if not self.episodes:
            raise ValueError("golden.json lists no episode, so there is nothing to replay")
        if sorted(self.episodes) != held:
            raise ValueError(f"golden.json lists episodes {sorted(self.episodes)}, golden.npz holds {held}")
        empty = [e for e in self.episodes if 0 in self.arrays[f"e{e}_agent"].shape[:2]]
        if empty:
            raise ValueError(f"golden.npz holds no step or no agent in episode {empty[0]}")

    def __getitem__(self, key):
        return self.arrays[key]


# ------------------------------------------------------------------------------------------- program
def rule_counts(mod):
    return list(mod.RULES), list(mod.RANDOM_RULES)


def check_program_py(folder: Path, g: Golden) -> str:
    sys.path.insert(0, str(folder))
    from agent_runtime import load_program

    mod = load_program(folder / "program.py")
    return f"{replay_picks('program.py', mod.ROUNDS, *rule_counts(mod), g)} decisions, picks identical"


def replay_picks(name: str, rounds, rules: list, randoms: list, g: Golden) -> int:
    """Every recorded decision through ``rounds`` (round<r>(me, others, i, uniform) each, fed the recorded
    uniforms): the number replayed, or a Mismatch naming the first that differs."""
    if len(rounds) != g[f"e{g.episodes[0]}_picks"].shape[1]:
        raise Mismatch(f"{name}: {len(rounds)} round(s), golden {g[f'e{g.episodes[0]}_picks'].shape[1]}")
    n_checked = 0
    for e in g.episodes:
        agent, rel, picks, uni = g[f"e{e}_agent"], g[f"e{e}_rel"], g[f"e{e}_picks"], g[f"e{e}_uniform"]
        for t in range(agent.shape[0]):
            n = agent.shape[1]
            for r, fn in enumerate(rounds):
                for i in range(n):
                    stream = [float(x) for q in range(randoms[r]) for x in uni[t, r, q, i]]
                    used = [0]

                    def uniform():
                        used[0] += 1
                        return stream[used[0] - 1] if used[0] <= len(stream) else 0.5

                    got = fn(agent[t, i].tolist(), rel[t, i].tolist(), i, uniform if randoms[r] else None)
                    want = picks[t, r, i, :rules[r]].tolist()
                    if got != want or list(picks[t, r, i, rules[r]:]) != [-1] * (picks.shape[-1] - rules[r]):
                        raise Mismatch(f"{name}: {where(e, t, i, r)}: picks {got}, golden {want}")
                    if used[0] != len(stream):
                        raise Mismatch(f"{name}: {where(e, t, i, r)}: drew {used[0]} uniforms, golden "
                                       f"{len(stream)}")
                    n_checked += 1
    if n_checked == 0:
        raise Mismatch(f"{name}: no decision to replay")
    return n_checked


# ------------------------------------------------------------------------------------------- program.json
def json_rounds(spec: dict) -> tuple[list, list, list]:
    """program.json read as its semantics_text says, by itself (features from their sources, filters, scores):
    (round functions like program.py's, rules per round, random rules per round). The check replays the file a
    robot in another language implements, not only the code generated beside it."""
    sources = {f["name"]: f["source"] for f in spec["features"]}

    def feature(name, me, o):
        src = sources[name]
        if "product" in src:  # left to right, as program.py multiplies
            vals = [feature(p, me, o) for p in src["product"]]
            out = vals[0]
            for v in vals[1:]:
                out = out * v
            return out
        arr = me if src["field"] == "agent" else o
        x, y = arr[src["start"]], arr[src["start"] + 1]
        x, y = (-x, -y) if src["sign"] < 0 else (x, y)
        parts = {"x": lambda: x, "y": lambda: y, "d": lambda: math.hypot(x, y), "theta": lambda: math.atan2(y, x)}
        return parts[src["part"]]()

    def linear(terms, me, o):  # sum_k w_k phi_k in the written order
        out = None
        for name, w in terms:
            v = feature(name, me, o) if w == 1.0 else w * feature(name, me, o)
            out = v if out is None else out + v
        return 0.0 if out is None else out

    def holds(c, me, o):
        op = c["op"]
        if op == "true":
            return True
        if op == "test":
            return linear(c["lhs"], me, o) >= c["threshold"]
        if op in ("and", "or"):
            a, b = holds(c["left"], me, o), holds(c["right"], me, o)
            return (a and b) if op == "and" else (a or b)
        raise ValueError(f"unknown filter op {op!r}")

    def rule_fn(rule):
        rnd = {"random": True, "argmax": False}[rule["kind"]]

        def pick(me, others, i, uniform):
            best_j, best = -1, 0.0
            for j, o in enumerate(others):
                u = uniform() if rnd else None  # one draw per index j, before any test
                if j == i:
                    continue
                if holds(rule["filter"], me, o):
                    score = u if rnd else linear(rule["score"], me, o)
                    if best_j < 0 or score > best:  # ties keep the lowest index
                        best_j, best = j, score
            return best_j
        return pick

    rounds = []
    for rules in spec["rounds"]:
        fns = [rule_fn(r) for r in rules]
        rounds.append(lambda me, others, i, uniform, fns=fns: [f(me, others, i, uniform) for f in fns])
    return (rounds, [len(rs) for rs in spec["rounds"]],
            [sum(r["kind"] == "random" for r in rs) for rs in spec["rounds"]])


def check_program_json(folder: Path, g: Golden) -> str:
    spec = json.loads((folder / "program.json").read_text())
    if spec.get("semantics") != SEMANTICS:
        raise Mismatch(f"program.json: semantics {spec.get('semantics')!r}, this checker implements {SEMANTICS}")
    return f"{replay_picks('program.json', *json_rounds(spec), g)} decisions, picks identical"


SEMANTICS = "neurosym-rules/1"


# ------------------------------------------------------------------------------------------- integrity
def check_checksums(folder: Path, manifest: dict) -> str:
    """Every file the export wrote is the one the manifest recorded (sha256): an artifact edited after the
    export, even where no golden decision would notice, is not passed."""
    sums = manifest.get("sha256")
    if not isinstance(sums, dict) or not sums:
        raise SkipCheck("the manifest records no checksums (an export written before they were)")
    for name, want in sorted(sums.items()):
        got = hashlib.sha256((folder / name).read_bytes()).hexdigest()
        if got != want:
            raise Mismatch(f"{name}: changed after the export (its sha256 is not the manifest's)")
    return f"{len(sums)} files as exported (sha256)"


HARNESS = r"""
#include <stdio.h>
#include "program.h"
static double me[64], others[NS_MAX_AGENTS * NS_PAIR_DIM], uni[NS_MAX_AGENTS * (NS_MAX_RULES + 1)];
struct stream { int pos, len; };
static double next_uniform(void *state) {
    struct stream *s = (struct stream *)state;
    return s->pos < s->len ? uni[s->pos++] : (s->pos++, 0.5);
}
int main(void) {
    int q, r, n, i, nu, k, m, picks[NS_MAX_RULES + 1];
    if (scanf("%d", &q) != 1) return 2;
    while (q-- > 0) {
        struct stream s = {0, 0};
        if (scanf("%d %d %d %d", &r, &n, &i, &nu) != 4 || n > NS_MAX_AGENTS) return 2;
        for (k = 0; k < NS_AGENT_DIM; k++) if (scanf("%lf", &me[k]) != 1) return 2;
        for (k = 0; k < n * NS_PAIR_DIM; k++) if (scanf("%lf", &others[k]) != 1) return 2;
        for (k = 0; k < nu; k++) if (scanf("%lf", &uni[k]) != 1) return 2;
        s.len = nu;
        m = ns_round(r, me, others, n, i, next_uniform, &s, picks);
        printf("%d %d", m, s.pos);
        for (k = 0; k < m; k++) printf(" %d", picks[k]);
        printf("\n");
    }
    return 0;
}
"""


def check_program_h(folder: Path, g: Golden) -> str:
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        raise SkipCheck("no C compiler (cc) on the PATH")
    sys.path.insert(0, str(folder))
    from agent_runtime import load_program

    rules, randoms = rule_counts(load_program(folder / "program.py"))
    lines, keys = [], []
    for e in g.episodes:
        agent, rel, uni = g[f"e{e}_agent"], g[f"e{e}_rel"], g[f"e{e}_uniform"]
        for t in range(agent.shape[0]):
            n = agent.shape[1]
            for r in range(len(rules)):
                for i in range(n):
                    u = [x for q in range(randoms[r]) for x in uni[t, r, q, i]]
                    lines.append(f"{r + 1} {n} {i} {len(u)}")
                    lines.append(" ".join(repr(float(x)) for x in agent[t, i]))
                    lines.append(" ".join(repr(float(x)) for x in rel[t, i].reshape(-1)))
                    lines.append(" ".join(repr(float(x)) for x in u))
                    keys.append((e, t, r, i, len(u)))
    n_max = max(g[f"e{e}_agent"].shape[1] for e in g.episodes)
    with tempfile.TemporaryDirectory() as tmp:
        src, exe = Path(tmp) / "harness.c", Path(tmp) / "harness"
        src.write_text(HARNESS)
        cmd = [cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", f"-DNS_MAX_AGENTS={max(n_max, 1)}",
               f"-I{folder}", str(src), "-o", str(exe), "-lm"]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            errors = [ln.strip() for ln in p.stderr.splitlines() if "error" in ln] or [p.stderr.strip()]
            raise Mismatch(f"program.h: does not compile with {' '.join(cmd[:7])}: {errors[0][:300]}")
        p = subprocess.run([str(exe)], input=f"{len(keys)}\n" + "\n".join(lines) + "\n", capture_output=True,
                           text=True)
        if p.returncode != 0:
            raise Mismatch(f"program.h: the harness failed (exit {p.returncode})")
    out = p.stdout.splitlines()
    for (e, t, r, i, nu), line in zip(keys, out):
        vals = [int(v) for v in line.split()]
        got, drew = vals[2:], vals[1]
        want = g[f"e{e}_picks"][t, r, i, :rules[r]].tolist()
        if vals[0] != rules[r] or got != want:
            raise Mismatch(f"program.h: {where(e, t, i, r)}: picks {got}, golden {want}")
        if drew != nu:
            raise Mismatch(f"program.h: {where(e, t, i, r)}: drew {drew} uniforms, golden {nu}")
    if len(out) != len(keys):
        raise Mismatch(f"program.h: the harness answered {len(out)} of {len(keys)} decisions")
    return f"{len(keys)} decisions, picks identical ({Path(cc).name})"


# ------------------------------------------------------------------------------------------- policy
def compare_actions(name: str, e: int, got: np.ndarray, want: np.ndarray, tol: float) -> float:
    """(T, N, A) each; the largest difference, or a Mismatch naming the first step and agent beyond ``tol``."""
    diff = np.abs(got.astype(np.float64) - want.astype(np.float64)).max(-1)  # (T, N)
    bad = np.argwhere(~(diff <= tol))
    if len(bad):
        t, i = bad[0]
        raise Mismatch(f"{name}: {where(e, t, i)}: action {got[t, i].tolist()}, golden {want[t, i].tolist()} "
                       f"(|diff| {diff[t, i]:.3g} > {tol:g})")
    return float(diff.max()) if diff.size else 0.0


def check_onnx(folder: Path, g: Golden, tol: float) -> str:
    try:
        import onnxruntime as ort
    except ImportError:
        raise SkipCheck("onnxruntime is not installed (pip install onnxruntime)") from None
    opts = ort.SessionOptions()
    opts.log_severity_level = 3
    s = ort.InferenceSession(str(folder / "policy.onnx"), opts, providers=["CPUExecutionProvider"])
    worst = 0.0
    for e in g.episodes:  # the steps of an episode as the batch: one call
        out = s.run(None, {"agent": g[f"e{e}_agent"], "rel": g[f"e{e}_rel"], "picks": g[f"e{e}_picks"]})[0]
        worst = max(worst, compare_actions("policy.onnx", e, out, g[f"e{e}_action"], tol))
    return f"actions agree, max |diff| {worst:.2g} <= {tol:g}"


def check_torchscript(folder: Path, g: Golden, tol: float) -> str:
    try:
        import torch
    except ImportError:
        raise SkipCheck("torch is not installed") from None
    m = torch.jit.load(str(folder / "policy.pt"), map_location="cpu")
    worst = 0.0
    with torch.no_grad():
        for e in g.episodes:
            out = m(*(torch.from_numpy(g[f"e{e}_{k}"]) for k in ("agent", "rel", "picks")))[0].numpy()
            worst = max(worst, compare_actions("policy.pt", e, out, g[f"e{e}_action"], tol))
    return f"actions agree, max |diff| {worst:.2g} <= {tol:g}"


def check_pt2(folder: Path, g: Golden, tol: float) -> str:
    try:
        import torch
    except ImportError:
        raise SkipCheck("torch is not installed") from None
    m = torch.export.load(str(folder / "policy.pt2")).module()
    worst = 0.0
    with torch.no_grad():
        for e in g.episodes:
            out = m(*(torch.from_numpy(g[f"e{e}_{k}"]) for k in ("agent", "rel", "picks")))[0].numpy()
            worst = max(worst, compare_actions("policy.pt2", e, out, g[f"e{e}_action"], tol))
    return f"actions agree, max |diff| {worst:.2g} <= {tol:g}"


def check_agents(folder: Path, g: Golden, tol: float) -> str:
    """agent/*.onnx, one agent at a time, messages passed as on a robot, fed the golden picks."""
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        raise SkipCheck("onnxruntime is not installed (pip install onnxruntime)") from None
    sys.path.insert(0, str(folder))
    from agent_runtime import Agent, Export, team_step

    team = Export(folder)
    worst = 0.0
    for e in g.episodes:
        agent, rel, picks = g[f"e{e}_agent"], g[f"e{e}_rel"], g[f"e{e}_picks"]
        agents = [Agent(team, i) for i in range(agent.shape[1])]
        acts = np.stack([team_step(team, agents, agent[t], rel[t], picks=picks[t])[0] for t in range(agent.shape[0])])
        worst = max(worst, compare_actions("agent/*.onnx", e, acts, g[f"e{e}_action"], tol))
    return f"actions agree agent by agent, max |diff| {worst:.2g} <= {tol:g}"


class SkipCheck(Exception):
    """An artifact this machine cannot run (its runtime is missing)."""


POLICY = {  # format (the manifest's "formats", export.formats) -> its main file, its checks
    "torchscript": ("policy.pt", [("policy.pt", check_torchscript)]),
    "pt2": ("policy.pt2", [("policy.pt2", check_pt2)]),
    "onnx": ("policy.onnx", [("policy.onnx", check_onnx), ("agent/*.onnx", check_agents)]),
}


def policy_checks(folder: Path, manifest: dict, present: set, g: Golden, tol: float) -> list:
    """(format, file, check) for every policy format the export wrote or the folder holds; the check of one the
    export could not write raises SkipCheck with its reason. An export written before formats were recorded
    held TorchScript and ONNX."""
    made = manifest.get("formats")
    out = []
    for fmt, (main, checks) in POLICY.items():
        entry = (made or {}).get(fmt)
        written = main in present or (entry is not None and entry.get("files")) or (
            made is None and manifest["policy"] and fmt != "pt2")
        if written:
            out += [(fmt, name, lambda fn=fn: fn(folder, g, tol)) for name, fn in checks]
        elif entry is not None:
            out.append((fmt, main, lambda why=entry.get("skipped", "?"): skip(f"not written by the export: {why}")))
    return out


def skip(why: str):
    raise SkipCheck(why)


def neurosym_importable() -> bool:
    import importlib.util

    try:
        return importlib.util.find_spec("neurosym_cli") is not None or importlib.util.find_spec("neurosym") is not None
    except (ImportError, ValueError):
        return False


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(Path(__file__).resolve().parent))
    ap.add_argument("--tolerance", type=float, default=None, help="max |action difference| (default: manifest's)")
    ap.add_argument("--report", default="", help="also write the results as JSON here")
    ap.add_argument("--require", default="", help="policy formats that must be here and pass (comma-separated: "
                                                  f"{', '.join(POLICY)}); others may be skipped")
    args = ap.parse_args(argv)
    required = [f for f in args.require.split(",") if f]
    if any(f not in POLICY for f in required):
        print(f"check: --require takes {', '.join(POLICY)}, got {args.require!r}", file=sys.stderr)
        return 2
    folder = Path(args.folder).resolve()
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        g = Golden(folder)
        tol = args.tolerance if args.tolerance is not None else float(manifest["tolerance"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"check: cannot read the export folder {folder}: {e}", file=sys.stderr)
        return 2
    if not (math.isfinite(tol) and tol >= 0):  # an infinite tolerance passes any action: a check of nothing
        print(f"check: the tolerance must be a finite number >= 0, got {tol}", file=sys.stderr)
        return 2
    present = {p.name for p in folder.iterdir()}
    checks = []  # an artifact in the folder is checked whatever the manifest says
    if manifest["program"] or present & {"program.json", "program.py", "program.h"}:
        checks += [("program.py", lambda: check_program_py(folder, g)),
                   ("program.json", lambda: check_program_json(folder, g)),
                   ("program.h", lambda: check_program_h(folder, g))]
    checks = [(None, name, fn) for name, fn in checks]
    checks += policy_checks(folder, manifest, present, g, tol)
    for fmt in required:  # asked for, and neither written nor in the folder
        if fmt not in {c[0] for c in checks}:
            checks.append((fmt, POLICY[fmt][0], lambda: skip("not in the folder")))
    checks.append((None, "checksums", lambda: check_checksums(folder, manifest)))
    results, first = [], None
    for fmt, name, fn in checks:
        try:
            results.append({"file": name, "status": "ok", "detail": fn()})
        except SkipCheck as e:
            if fmt in required:  # a format asked for by name may not be skipped
                msg = f"{name}: required ({fmt}) but {e}"
                results.append({"file": name, "status": "missing", "detail": msg})
                first = first or msg
            else:
                results.append({"file": name, "status": "skipped", "detail": str(e)})
        except Mismatch as e:
            results.append({"file": name, "status": "mismatch", "detail": str(e)})
            first = first or str(e)
        except Exception as e:  # an artifact that crashes is a failed check, reported like a mismatch
            msg = f"{name}: cannot be replayed: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
            results.append({"file": name, "status": "mismatch", "detail": msg})
            first = first or msg
    if not any(r["status"] == "ok" for r in results if r["file"] != "checksums"):
        first = first or ("nothing was replayed: " + ("; ".join(f"{r['file']} {r['detail']}" for r in results
                                                               if r["status"] == "skipped") or "no artifact"))
    for r in results:
        print(f"{r['file']:<14} {r['status']:<9} {r['detail']}")
    report = {"folder": str(folder), "tolerance": tol, "neurosym_importable": neurosym_importable(),
              "episodes": g.episodes, "results": results, "first_mismatch": first}
    if args.report:
        Path(args.report).write_text(json.dumps(report, indent=1) + "\n")
    return 1 if first else 0


if __name__ == "__main__":
    raise SystemExit(main())
