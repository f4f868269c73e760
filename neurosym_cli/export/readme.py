"""The README.md of an export folder: how to call each piece, the units, and what each agent must broadcast and
receive. Written from the manifest and the task's feature declarations."""

from __future__ import annotations

from ..dsl.ast import Program
from ..dsl.printer import describe, rule_text
from ..dsl.vocabulary import FeatureSet
from .bandwidth import readme_lines
from .spec import SEMANTICS_TEXT, used_features


def _features(program: Program, vocab: FeatureSet, task: str) -> list[str]:
    rows = ["| feature | of | meaning | unit | computed as |", "|---|---|---|---|---|"]
    for f in used_features(program, vocab, task):
        s = f.source
        assert s is not None
        if s.product:
            how = " * ".join(s.product)
        else:
            arr = "me" if s.field == "agent" else "others[j]"
            v = f"{'-' if s.sign < 0 else ''}{arr}[{s.start}:{s.start + 2}]"
            how = {"x": f"x of {v}", "y": f"y of {v}", "d": f"hypot of {v}", "theta": f"atan2(y, x) of {v}"}[s.part]
        rows.append(f"| `{f.name}` | {'my own state' if f.of == 'self' else 'the candidate j'} | {f.words} | "
                    f"{f.unit or '-'} | {how} |")
    return rows


_LOAD = {  # format -> (file, what it is, loading it from Python, from C++)
    "torchscript": ("policy.pt", "TorchScript",
                    '`m = torch.jit.load("policy.pt"); action, raw = m(agent, rel, picks)`',
                    'libtorch: `auto m = torch::jit::load("policy.pt"); auto out = m.forward({agent, rel, '
                    'picks}).toTuple();`'),
    "pt2": ("policy.pt2", "a torch.export program (`torch.export.save`)",
            '`m = torch.export.load("policy.pt2").module(); action, raw = m(agent, rel, picks)`',
            "compile it once with AOTInductor (`torch._inductor.aoti_compile_and_package(torch.export.load("
            '"policy.pt2"), package_path="policy_aoti.pt2")`) and run that with libtorch\'s '
            "`torch::inductor::AOTIModelPackageLoader` (not covered by check.py)"),
    "onnx": ("policy.onnx", "ONNX, and the per-agent pieces `agent/*.onnx` below",
             '`s = onnxruntime.InferenceSession("policy.onnx"); action, raw = s.run(None, {"agent": agent, "rel": '
             'rel, "picks": picks})`',
             'ONNX Runtime\'s C++ API: `Ort::Session s(env, "policy.onnx", opts); s.Run(...)` with the inputs named '
             "as here"),
}


def _formats(formats: dict | None) -> list[str]:
    """One item per policy format of the manifest: its file, its exporter and free sizes, how to load it."""
    if formats is None:  # an export written before formats were recorded: TorchScript and legacy ONNX
        formats = {"torchscript": {"files": ["policy.pt"]}, "onnx": {"files": ["policy.onnx"]}}
    rows = []
    for fmt, made in formats.items():
        file, what, py, cpp = _LOAD[fmt]
        if "skipped" in made:
            rows.append(f"- `{file}` ({fmt}): not written ({made['skipped']})")
            continue
        opset = f", opset {made['opset']}" if made.get("opset") else ""
        made_by = f" Made by {made['exporter']}{opset}; free sizes {made['free']}." if "exporter" in made else ""
        rows.append(f"- `{file}`, {what}.{made_by} Python: {py}. C++: {cpp}.")
    return rows


def readme(manifest: dict, golden: dict, program: Program | None, vocab: FeatureSet | None, cfg, task) -> str:
    m = manifest
    ds, dp, a, rounds = m["agent_dim"], m["pair_dim"], m["action_dim"], m["rounds"]
    # the first docstring up the task's classes that says what s_i is (formation.py, unlabeled_goals.py do)
    docs = [c.__doc__ or "" for c in type(task).__mro__]
    doc = next((d for d in docs if "s_i" in d), docs[0]).strip().split("\n\n")[0]
    doc = " ".join(doc.split())
    out = [f"# Export of `{m['baseline']}` on `{m['task']}`", "",
           f"Made by `neurosym export` from the run of task {m['task']}, budget {m['budget']}, training seed "
           f"{m['seed']}, features {m['features']}. Nothing here imports neurosym. Check the folder on any machine "
           "with `python check.py` (numpy; onnxruntime, torch and a C compiler where present), or from the "
           "neurosym checkout with `neurosym export ... --check`.", "",
           "## Inputs and units", "",
           f"The task: {doc}" if doc else "", "",
           f"- `me` = s_i: agent i's own input, {ds} floats, as the task observes it (world units).",
           f"- `others[j]` = o_ij: agent i's view of agent j, {dp} floats (by convention the first two are the "
           "offset x_j - x_i, world units). Row i is ignored.",
           f"- the action: {a} floats, as the task applies it (`Task.target`, of the action and the agent's own "
           "`me`, is inside the model: for the formation tasks the velocity clipped to the speed limit, for "
           "unlabeled goals the goal weights).", "",
           "## What each agent broadcasts and receives, per step", "",
           "1. Every agent broadcasts a cheap position beacon; from everyone's beacons each agent forms its own "
           "`others` (o_ij). Nothing else goes to everybody.",
           f"2. For each of the {rounds} communication round(s): agent i runs the program on its own `me` and "
           "`others` and gets one agent per rule (-1: nobody). It sends a request to those agents only; each asked "
           "agent j answers with one message (`agent/message<r>.onnx` on its round input and its own view of i, "
           "o_ji). Agent i combines the answers (`agent/receive<r>.onnx`). Messages go only to the chosen few: "
           "that is the bandwidth saving.",
           "3. `agent/act.onnx` gives the action.", "",
           "`agent_runtime.py` does all of this for one agent (`Agent.observe`, `whom`, `message`, `receive`, "
           "`act`; `team_step` for a whole team in one process).", ""]
    if program is not None and vocab is not None:
        out += ["## The program", "", "```", *[rule_text(r) if rounds == 1 else f"round {k + 1}: {rule_text(r)}"
                                              for k, rs in enumerate(program.rounds) for r in rs], "```", ""]
        for k, rs in enumerate(program.rounds):
            for q, r in enumerate(rs, start=1):
                out.append(f"- round {k + 1}, rule {q}: {describe(r, vocab)}")
        out += ["", f"Semantics ({m['semantics']}): {SEMANTICS_TEXT}", "", "Features it reads:", "",
                *_features(program, vocab, m["task"]), "",
                "- `program.json`: the AST (`rounds`: per rule `kind`, `score` as [feature, weight] terms, `filter` "
                "with `test` meaning sum of terms >= threshold), the features above with their sources, and the "
                "semantics.",
                "- `program.py` (standard library only): `round1(me, others, i, uniform=None)` ... -> one agent "
                "index per rule. `uniform` is a zero-argument callable returning a float in [0, 1) "
                "(`random.random` works); each random rule calls it exactly n times, once per j = 0..n-1 in "
                "index order, i and rejected agents included, also when nobody passes; the random rules of a round "
                "in rule order. `heard(picks)` gives the agents heard, each once.",
                "- `program.h` (C99, one header, no allocation): `int ns_round1(const double *me, const double "
                "*others, int n, int i, ns_uniform_fn uniform, void *state, int *picks)`, `others` row-major n x "
                f"{dp}; `uniform(state)` is called as above; returns the number of rules, or -1 for n outside "
                "1..NS_MAX_AGENTS (define it before the include; default 4096).", ""]
    else:
        out += ["## No program", "",
                f"`{m['baseline']}` has no program: whom each agent hears is an input of the model (golden picks are "
                "the agents it heard, in index order, padded with -1).", ""]
    if m["policy"]:
        out += ["## The policy", "",
                f"The team in one call: `agent` float32 (B, N, {ds}), `rel` float32 (B, N, N, {dp}) with rel[b, i, j] "
                f"= o_ij, `picks` int64 (B, {rounds}, N, K): whom agent i hears in each round, one slot per rule (-1: "
                f"nobody; an agent in two slots is heard once) -> `action` float32 (B, N, {a}), `raw` (B, N, {a}) "
                "before the task's target. Formats (manifest.json's `formats` says which exporter made each file):",
                "", *_formats(m.get("formats")),
                "", "- `agent/encode.onnx` s (M, Ds) -> h (M, D); `agent/message<r>.onnx` x (M, D), o_ji (M, Dp) -> "
                "m (M, D); `agent/receive<r>.onnx` x, h (M, D), o_ij (M, K, Dp), m (M, K, D), valid (M, K) bool -> "
                "y (M, D), the next round's x; `agent/act.onnx` y (M, D), and s (M, Ds) where the task's "
                "target reads the agent's own input -> action (M, A). Round 1's x is h.", ""]
    eps = ", ".join(f"{e['episode']} (eval seed {e['eval_seed']}, {e['steps']} steps, {e['agents']} agents"
                    + (f", loss {e['loss']:.6g}" if "loss" in e else "") + ")" for e in golden["episodes"])
    out += readme_lines(m["bandwidth"]) if m.get("bandwidth") else []  # what the messages cost
    out += ["## Golden vectors", "",
            f"`golden.npz` (numpy arrays, no pickles; `golden.json` says what they are): evaluation episodes {eps}, "
            "recorded by the rollout `neurosym eval` runs: per step the inputs, the uniforms each random rule drew "
            "((T, R, U, N, N): row i for agent i), the picks, the applied action and the loss. `check.py` replays "
            f"them: picks must agree exactly, actions within {m['tolerance']:g} (absolute).", "",
            "## Limits", "",
            "- Features are computed in double precision here and in float32 by neurosym: a pick can differ where a "
            "feature is within float32 rounding of a threshold, or two candidates' scores tie within it.",
            "- Link failure, the noise model and the world's dynamics are not exported; the golden vectors are "
            "without link failure.", ""]
    return "\n".join(out)
