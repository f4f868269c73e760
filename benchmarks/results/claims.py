"""The paper's claims as data (claims.toml: one record each, with the paper's words and where they stand) and the
one function that checks a record on one training seed's numbers."""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from .files import FORMATION
from .tables import gap, mean, minus, ms, paired

CLAIMS = Path(__file__).with_name("claims.toml")

TESTS = {  # (quantity, its 95 % half-width or 0, threshold) -> whether the claim holds
    "abs_at_most": lambda q, h, t: abs(q) <= t,
    "below": lambda q, h, t: q < t,
    "above": lambda q, h, t: q > t,
    "ci_below": lambda q, h, t: q + h < t,
    "ci_above": lambda q, h, t: q - h > t,
}
QUANTITIES = ("gap", "paired", "diff", "mean")


@dataclass(frozen=True)
class ClaimSpec:
    """One claim of the paper (claims.toml's header says what each field means)."""

    family: str
    name: str
    quantity: str
    a: str
    test: str
    threshold: float
    paper: str
    source: str
    unit: str
    long: str
    cell: str
    b: str = ""
    metrics: tuple[str, ...] = ("cost",)
    short: str = ""
    weak: str = ""
    digits: int = 2

    def __post_init__(self):
        if self.test not in TESTS or self.quantity not in QUANTITIES:
            raise ValueError(f"claim {self.name!r}: test {self.test!r} (one of {', '.join(TESTS)}) or quantity "
                             f"{self.quantity!r} (one of {', '.join(QUANTITIES)}) unknown")
        if self.quantity != "mean" and not self.b:
            raise ValueError(f"claim {self.name!r}: a {self.quantity} compares a with b; b is missing")


class Claim(NamedTuple):
    """One claim of the paper checked on one set of numbers: its short and long lines, its glance cell, whether it
    holds, its name (the short line without numbers: the same on every seed), the quantity the verdict reads
    (``value``, described by ``unit``) and how it was read (``quantity``: gap, paired, diff or mean)."""

    short: str
    long: str
    cell: str
    holds: bool
    name: str
    value: float
    unit: str
    quantity: str


@functools.lru_cache(maxsize=None)
def load(path: Path = CLAIMS) -> tuple[ClaimSpec, ...]:
    """The claim records of a TOML file, in its order."""
    with open(path, "rb") as f:
        records = tomllib.load(f)["claim"]
    return tuple(ClaimSpec(**{**r, "metrics": tuple(r.get("metrics", ("cost",)))}) for r in records)


def evaluate(spec: ClaimSpec, v: dict) -> Claim:
    """Claim ``spec`` checked on the numbers of ``v`` (one training seed's variant: baselines with summaries and
    per-evaluation-seed losses); a KeyError names a baseline ``v`` lacks."""
    f: dict = {}
    for side, b in (("a", spec.a), ("b", spec.b)):
        if not b:
            continue
        for k in spec.metrics:
            f[f"{side}_{k}"], f[f"{side}_{k}_ms"] = mean(v, b, k), ms(v, b, k, spec.digits)
        f[side], f[f"{side}_ms"] = f[f"{side}_{spec.metrics[0]}"], f[f"{side}_{spec.metrics[0]}_ms"]
    half = 0.0
    if spec.quantity in ("gap", "paired"):
        f["d0"], f["d1"] = paired(v, spec.a, spec.b)
    if spec.quantity == "gap":
        q = gap(v, spec.a, spec.b)
    elif spec.quantity == "paired":
        q, half = f["d0"], f["d1"]
    elif spec.quantity == "diff":
        q = max(f[f"a_{k}"] - f[f"b_{k}"] for k in spec.metrics)
    else:
        q = f["a"]
    test = TESTS[spec.test]
    holds = test(q, half, spec.threshold)
    weak = not holds and test(q, 0.0, spec.threshold)  # the mean alone points the claimed way
    f.update(q=q, weak=f" ({spec.weak}, not significant)" if weak and spec.weak else "",
             ns=", not significant" if weak else "")
    return Claim(short=(spec.short or spec.name).format(**f), long=spec.long.format(**f),
                 cell=minus(spec.cell.format(**f)), holds=holds, name=spec.name, value=q, unit=spec.unit,
                 quantity=spec.quantity)


def family(task: str) -> str:
    """The claims a task is checked on: the formation-flying ones (paper section 4) or unlabeled-goals'."""
    return "formation" if task in FORMATION else "unlabeled-goals"


def claims(task: str, v: dict) -> list[Claim]:
    """Each claim of the paper on this task, checked on the numbers of ``v`` (one training seed)."""
    return [evaluate(spec, v) for spec in load() if spec.family == family(task)]
