"""The longer fuzz run of the program parser (docs/reliability.md): mutations of a valid program, hostile lines,
and the parser's time against the length of a line.

    python benchmarks/fuzz_parser.py                  # 200,000 mutations, then the timing table
    python benchmarks/fuzz_parser.py --cases 20000

Every mutation must parse to a program that prints and parses back the same, or raise ProgramSyntaxError; any
other exception is a failure and is printed with its input.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from test_faults_programs import fuzz_parser  # noqa: E402  (the same mutations as the CI test)

from neurosym_cli.dsl import ProgramSyntaxError, parse  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, default=200_000)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    t0 = time.perf_counter()
    parsed, rejected = fuzz_parser(a.cases, a.seed)
    took = time.perf_counter() - t0
    print(f"mutations: {a.cases:,} tried, {parsed:,} parsed and round-tripped, {rejected:,} rejected with line and "
          f"column, 0 other exceptions ({took:.1f} s, {a.cases / took:,.0f} per s)")
    print("| line | characters | seconds | outcome |")
    print("|---|---:|---:|---|")
    rule = "random(filter(d >= 1.0 and gd <= 2.0, l))"
    for name, text in [
        ("one rule", rule),
        ("1,200-term score", "argmax(map(" + " + ".join(f"w{k}" for k in range(1200)) + ", filter(true, l)))"),
        ("10,000 rules, one per line", "\n".join([rule] * 10_000)),
        ("1 MB line", "random(filter(" + "d >= 1 and " * 95_000),
        ("10 MB line", "random(filter(" + "d >= 1 and " * 950_000),
        ("10 MB token", "x" * 10_000_000),
    ]:
        t0 = time.perf_counter()
        try:
            parse(text)
            outcome = "parsed"
        except ProgramSyntaxError as e:
            outcome = f"refused: {e.msg[:60]}"
        print(f"| {name} | {len(text):,} | {time.perf_counter() - t0:.3f} | {outcome} |")


if __name__ == "__main__":
    main()
