"""Per-agent decision time of the exported programs (`neurosym export`): program.py under plain Python and program.h
compiled with cc -O2, for one asking agent among N = 10, 100, 1,000 candidates.

    python benchmarks/bench_export.py [--program FILE] [--task random-cross] [--json out.json]

The program defaults to a five-rule one of the shape `neurosym synth` finds on random-cross (argmax and random
rules, guards on the agent's own state, tests on the candidate's offset and bearing). Observations are random
(positions in a 40 x 40 box); every agent in turn asks, and the time is per decision (all rules of the round).
Prints a table; the figures in docs/performance.md come from it.
"""

from __future__ import annotations

import argparse
import json
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

PROGRAM = """random(filter(dx <= -8.47 or gtheta <= -1.67, l))
argmax(map(d, filter(gtheta >= 1.58, l)))
random(filter(gy >= 15.24 and dy >= -8.91, l))
argmax(map(-1.0*theta, filter(dy <= 0.46, l)))
argmax(map(-1.0*d, filter(true, l)))
"""

HARNESS = r"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "program.h"
static unsigned long long s = 88172645463325252ULL;
static double xorshift(void *state) { (void)state; s ^= s << 13; s ^= s >> 7; s ^= s << 17; return (s >> 11) * (1.0 / 9007199254740992.0); }
int main(int argc, char **argv) {
    int n = atoi(argv[1]), reps = atoi(argv[2]), i, j, r, picks[NS_MAX_RULES];
    double *pos = malloc(sizeof(double) * 2 * n), *others = malloc(sizeof(double) * 2 * n), me[NS_AGENT_DIM] = {0};
    struct timespec a, b; long sink = 0;
    for (j = 0; j < 2 * n; j++) pos[j] = 40.0 * xorshift(0);
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (r = 0; r < reps; r++) {
        i = r % n;
        for (j = 0; j < n; j++) { others[2 * j] = pos[2 * j] - pos[2 * i]; others[2 * j + 1] = pos[2 * j + 1] - pos[2 * i + 1]; }
        me[0] = pos[2 * i] - 20.0; me[1] = pos[2 * i + 1] - 20.0;
        ns_round1(me, others, n, i, xorshift, 0, picks);
        sink += picks[0];
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    printf("%.9f %ld\n", ((b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec)) / reps, sink);
    return 0;
}
"""


def build(program_text: str, task: str, folder: Path) -> None:
    """program.py and program.h of ``program_text`` for ``task``'s v1 features, as `neurosym export` writes them."""
    import neurosym as ns
    from neurosym_cli.export.codegen import c_header, python_module

    cfg = ns.compose("export", task=task, budget="tiny")
    t = ns.task(cfg)
    p = ns.parse(program_text)
    args = (p, t.features("v1").vocab, task, "v1", t.obs_dim, t.pair_dim)
    (folder / "program.py").write_text(python_module(*args))
    (folder / "program.h").write_text(c_header(*args))


def time_python(folder: Path, n: int, budget_s: float = 1.0) -> float:
    """Seconds per decision of program.py's round1 (the module imported from its file, stdlib only)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("exported", folder / "program.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rng = random.Random(0)
    pos = [(40 * rng.random(), 40 * rng.random()) for _ in range(n)]
    views = [[(x - xi, y - yi) for x, y in pos] for xi, yi in pos]
    mes = [(xi - 20.0, yi - 20.0) for xi, yi in pos]
    reps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < budget_s or reps < 3:
        i = reps % n
        mod.round1(mes[i], views[i], i, rng.random)
        reps += 1
    return (time.perf_counter() - t0) / reps


def time_c(folder: Path, n: int) -> float | None:
    cc = shutil.which("cc")
    if cc is None:
        return None
    src, exe = folder / "bench.c", folder / "bench"
    src.write_text(HARNESS)
    subprocess.run([cc, "-std=c99", "-O2", f"-DNS_MAX_AGENTS={max(n, 1)}", f"-I{folder}", str(src), "-o", str(exe),
                    "-lm"], check=True)
    reps = max(10, int(2e7 // n))
    out = subprocess.run([str(exe), str(n), str(reps)], capture_output=True, text=True, check=True).stdout
    return float(out.split()[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--program", default="", help="a program file (default: a five-rule random-cross program)")
    ap.add_argument("--task", default="random-cross")
    ap.add_argument("--json", default="")
    args = ap.parse_args()
    text = Path(args.program).read_text() if args.program else PROGRAM
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        build(text, args.task, folder)
        for n in (10, 100, 1000):
            py, c = time_python(folder, n), time_c(folder, n)
            rows.append({"n": n, "python_us": py * 1e6, "c_us": None if c is None else c * 1e6})
    print(f"{'N':>6} {'program.py (us/decision)':>26} {'program.h, cc -O2 (us/decision)':>34}")
    for r in rows:
        c = "n/a (no cc)" if r["c_us"] is None else f"{r['c_us']:.3f}"
        print(f"{r['n']:>6} {r['python_us']:>26.1f} {c:>34}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
