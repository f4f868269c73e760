"""The paper's claims as data (claims.toml: one record each, with the paper's words and where they stand) and the
one function that checks a record on one training seed's numbers."""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from .files import FORMATION
from .tables import gap, mean, minus, ms, paired, pm

CLAIMS = Path(__file__).with_name("claims.toml")

TESTS = {  # (quantity, its 95 % half-width or 0, threshold) -> whether the claim holds
    "abs_at_most": lambda q, h, t: abs(q) <= t,
    "below": lambda q, h, t: q < t,
    "above": lambda q, h, t: q > t,
    "ci_below": lambda q, h, t: q + h < t,
    "ci_above": lambda q, h, t: q - h > t,
    "equals": lambda q, h, t: q == t,
}
QUANTITIES = ("gap", "paired", "diff", "mean", "dominated", "value")


@dataclass(frozen=True)
class Condition:
    """A second test a claim must also pass (claims.toml's ``also``): a quantity of the claim's baselines."""

    quantity: str
    test: str
    threshold: float
    metrics: tuple[str, ...] = ("cost",)


@dataclass(frozen=True)
class ClaimSpec:
    """One claim of the paper (claims.toml's header says what each field means)."""

    family: str
    name: str
    quantity: str
    test: str
    threshold: float
    paper: str
    source: str
    unit: str
    long: str
    cell: str = ""
    a: str = ""
    b: str = ""
    c: str = ""
    metrics: tuple[str, ...] = ("cost",)
    among: tuple[str, ...] = ()
    field: str = ""
    requires: tuple[str, ...] = ()
    also: Condition | None = None
    after: str = ""
    short: str = ""
    weak: str = ""
    digits: int = 2

    def __post_init__(self):
        for test, quantity in ((self.test, self.quantity), *(((self.also.test, self.also.quantity),) if self.also
                                                            else ())):
            if test not in TESTS or quantity not in QUANTITIES:
                raise ValueError(f"claim {self.name!r}: test {test!r} (one of {', '.join(TESTS)}) or quantity "
                                 f"{quantity!r} (one of {', '.join(QUANTITIES)}) unknown")
        if self.quantity not in ("dominated", "value") and not self.a:
            raise ValueError(f"claim {self.name!r}: a {self.quantity} reads baseline a; a is missing")
        if self.quantity not in ("mean", "value") and not self.b:
            raise ValueError(f"claim {self.name!r}: a {self.quantity} compares with b; b is missing")
        if (self.quantity == "dominated") != bool(self.among) or (self.quantity == "value") != bool(self.field):
            raise ValueError(f"claim {self.name!r}: among goes with quantity dominated, field with value")

    def applies(self, v: dict) -> bool:
        """Whether the numbers of ``v`` have every baseline ``requires`` names (a claim on an optional baseline)."""
        return all(b in v["baselines"] for b in self.requires)


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
    after: str = ""
    """what the line says after its verdict (the record's ``after``, when the claim fails)"""


@functools.lru_cache(maxsize=None)
def load(path: Path = CLAIMS) -> tuple[ClaimSpec, ...]:
    """The claim records of a TOML file, in its order."""
    with open(path, "rb") as f:
        records = tomllib.load(f)["claim"]
    return tuple(ClaimSpec(**_record(r)) for r in records)


def _record(r: dict) -> dict:
    """A TOML record as ClaimSpec's fields: lists as tuples, ``also`` as a Condition."""
    out = {**r, **{k: tuple(r[k]) for k in ("metrics", "among", "requires") if k in r}}
    if "also" in r:
        out["also"] = Condition(**{**r["also"], "metrics": tuple(r["also"].get("metrics", ("cost",)))})
    return out


def _quantity(quantity: str, metrics: tuple[str, ...], spec: ClaimSpec, v: dict, f: dict) -> tuple[float, float]:
    """(the quantity the verdict reads, its 95 % half-width or 0) of ``spec``'s baselines in ``v``."""
    if quantity == "gap":
        return gap(v, spec.a, spec.b), 0.0
    if quantity == "paired":
        return paired(v, spec.a, spec.b)
    if quantity == "diff":
        return max(mean(v, spec.a, k) - mean(v, spec.b, k) for k in metrics), 0.0
    if quantity == "dominated":
        return float(len(f["dominating"])), 0.0
    if quantity == "value":
        return f[spec.field], 0.0
    return mean(v, spec.a, metrics[0]), 0.0


def evaluate(spec: ClaimSpec, v: dict, extra: dict[str, Any] | None = None) -> Claim:
    """Claim ``spec`` checked on the numbers of ``v`` (one training seed's variant: baselines with summaries and
    per-evaluation-seed losses) and the named numbers ``extra`` (a ``value`` claim's field, and words the templates
    use); a KeyError names a baseline ``v`` lacks."""
    f: dict = dict(extra or {})
    for side, b in (("a", spec.a), ("b", spec.b), ("c", spec.c)):
        if not b:
            continue
        for k in spec.metrics:
            f[f"{side}_{k}"], f[f"{side}_{k}_ms"] = mean(v, b, k), ms(v, b, k, spec.digits)
        f[side], f[f"{side}_ms"] = f[f"{side}_{spec.metrics[0]}"], f[f"{side}_{spec.metrics[0]}_ms"]
        f[f"{side}_label"] = v["baselines"][b].get("label", b)
    if spec.a and spec.b and (spec.quantity in ("gap", "paired") or "{d" in spec.long + spec.cell + spec.after):
        f["d0"], f["d1"] = paired(v, spec.a, spec.b)
        f["d_pm"] = pm((f["d0"], f["d1"]), spec.digits)  # signed, with a true minus sign
    if spec.quantity == "dominated":  # the baselines of `among` at most b's on every metric
        f["dominating"] = [x for x in spec.among
                           if all(mean(v, x, k) <= mean(v, spec.b, k) for k in spec.metrics)]
        f["who"] = ", ".join(f["dominating"])
    q, half = _quantity(spec.quantity, spec.metrics, spec, v, f)
    test = TESTS[spec.test]
    holds = test(q, half, spec.threshold)
    weak = not holds and test(q, 0.0, spec.threshold)  # the mean alone points the claimed way
    if spec.also is not None:
        q2, half2 = _quantity(spec.also.quantity, spec.also.metrics, spec, v, f)
        holds = holds and TESTS[spec.also.test](q2, half2, spec.also.threshold)
    f.update(q=q, weak=f" ({spec.weak}, not significant)" if weak and spec.weak else "",
             ns=", not significant" if weak else "")
    return Claim(short=(spec.short or spec.name).format(**f), long=spec.long.format(**f),
                 cell=minus(spec.cell.format(**f)), holds=holds, name=spec.name, value=q, unit=spec.unit,
                 quantity=spec.quantity, after="" if holds else spec.after.format(**f))


def family(task: str) -> str:
    """The claims a task is checked on: the formation-flying ones (paper section 4) or unlabeled-goals'."""
    return "formation" if task in FORMATION else "unlabeled-goals"


def claims(task: str, v: dict) -> list[Claim]:
    """Each claim of the paper on this task, checked on the numbers of ``v`` (one training seed)."""
    return of_family(family(task), v)


def of_family(name: str, v: dict, extra: dict[str, Any] | None = None) -> list[Claim]:
    """Each claim of family ``name`` (formation, unlabeled-goals, appendix-d, appendix-e, vmas) that applies to the
    numbers of ``v``, checked on them and ``extra``."""
    return [evaluate(spec, v, extra) for spec in load() if spec.family == name and spec.applies(v)]
