"""Fingerprints of the numbers in a runs directory, to show that a refactor moves none of them.

    python benchmarks/fingerprint.py outputs/ > before.json        # on the old code
    python benchmarks/fingerprint.py outputs/ --against before.json  # on the new code: exit 1 on any difference

Covers what a run computes, not how it is recorded: the tensors of every checkpoint (model weights, the rl gate)
and of every synthesis dataset, every program's text, every tree's splits, and every evaluation's per-seed rows.
Configs, paths, versions and wall times recorded beside them are left out (a refactor may rename a key there).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

from neurosym_cli.run.layout import METRICS_FILE, MODEL, PROGRAM, TREE


def tensors_digest(obj) -> str:
    """SHA-1 over every tensor in a nested dict/list, in key order (values' bytes, dtype and shape)."""
    import torch

    h = hashlib.sha1()

    def walk(x, key=""):
        if isinstance(x, torch.Tensor):
            h.update(f"{key}:{x.dtype}:{tuple(x.shape)}".encode())
            h.update(x.detach().cpu().contiguous().numpy().tobytes())
        elif isinstance(x, dict):
            for k in sorted(x, key=str):
                walk(x[k], f"{key}/{k}")
        elif isinstance(x, (list, tuple)):
            for i, v in enumerate(x):
                walk(v, f"{key}[{i}]")

    walk(obj)
    return h.hexdigest()


def fingerprint(root: Path) -> dict[str, str]:
    import torch

    out: dict[str, str] = {}
    for f in sorted(root.rglob("*")):
        rel = str(f.relative_to(root))
        if "/logs/" in f"/{rel}" or not f.is_file():
            continue
        if f.name == MODEL:
            p = torch.load(f, map_location="cpu", weights_only=True)
            out[rel] = tensors_digest({"state_dict": p["state_dict"], "comm_state": p.get("comm_state", {})})
        elif f.suffix == ".pt" and f.name.startswith("dataset-"):
            out[rel] = tensors_digest(torch.load(f, map_location="cpu", weights_only=True))
        elif f.name == PROGRAM:
            out[rel] = f.read_text()
        elif f.name == TREE:
            out[rel] = json.dumps(json.loads(f.read_text()).get("rounds"), sort_keys=True)
        elif f.name == METRICS_FILE:
            out[rel] = json.dumps(json.loads(f.read_text())["per_seed"], sort_keys=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root")
    ap.add_argument("--against", help="a fingerprint file to compare with")
    args = ap.parse_args()
    now = fingerprint(Path(args.root))
    if not args.against:
        print(json.dumps(now, indent=1, sort_keys=True))
        return
    before = json.loads(Path(args.against).read_text())
    bad = [k for k in sorted(set(before) | set(now)) if before.get(k) != now.get(k)]
    for k in bad:
        print(f"differs: {k} ({'missing now' if k not in now else 'new' if k not in before else 'changed'})")
    print(f"{len(before)} artifacts before, {len(now)} now, {len(bad)} differ")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
