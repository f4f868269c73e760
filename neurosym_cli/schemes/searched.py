"""Baselines that run under a synthesized artifact: a program in the paper's notation (prog, det-prog; sections
3.2-3.4, appendix B) or a decision tree (dt, appendix B), on the oracle's weights or retrained under it
(prog-retrained, det-prog-retrained, dt-retrained; section 3.5). `neurosym synth` writes the artifact."""

from __future__ import annotations

import hashlib
import re
import shlex
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

from ..baselines import ORACLE, Artifact, Stage, runs_root_arg
from ..errors import ConfigError
from ..run.layout import PROGRAM, TREE
from .families import OnOracle, Retrained

if TYPE_CHECKING:
    from ..config import RunConfig

VERB_DEFAULTS = {"synth": "prog", "retrain": "prog-retrained"}
"""the baseline conf/synth.yaml and conf/retrain.yaml compose: their command lines need no baseline= for it"""


def user_program_tag(cfg: "RunConfig") -> str | None:
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


@dataclass(frozen=True)
class SearchVariant:
    """One synth setting that names a program when it differs from ``default``: its suffix on the program's tag and
    its override on the command line that searches it again."""

    key: str
    """the field of SynthConfig (``synth.<key>``)"""
    default: Any
    """the value that adds no suffix; also what a record written before the setting existed searched with"""
    suffix: Callable[[Any], str]
    """the value -> its part of the tag ("-hinge", "-coarse4")"""
    named: Callable[[Any], bool] | None = None
    """whether a value names the program (default: it differs from ``default``)"""

    def names(self, value: Any) -> bool:
        return self.named(value) if self.named else value != self.default


SEARCH_VARIANTS = (
    SearchVariant("objective", "paper", lambda v: f"-{v}"),
    SearchVariant("own_scores", True, lambda v: "-otherscores"),
    SearchVariant("simplify", True, lambda v: "-unsimplified"),
    SearchVariant("coarse", 1, lambda v: f"-coarse{v}", lambda v: v > 1),
    SearchVariant("patience", 0, lambda v: f"-patience{v}", bool),
    SearchVariant("search", "mcmc", lambda v: f"-{v}"),
)
"""every search setting that names a program, in the order of its tag's suffixes (one place: the tag, the
selection's record, the reuse of a sweep's programs and the result collectors all read it)"""

SEARCH_KEYS = tuple(v.key for v in SEARCH_VARIANTS)
"""the synth settings that name a program and that select/selected.json records"""


def override(key: str, value: Any) -> str:
    """A search setting on the command line: 'synth.own_scores=false'."""
    return f"synth.{key}={str(value).lower() if isinstance(value, bool) else value}"


def recorded_search(synth: Mapping[str, Any]) -> dict[str, Any]:
    """The search settings of a record's synth dict, by SEARCH_KEYS; a key the record lacks (written before the
    setting existed) reads as its default, the search the code made then."""
    return {v.key: synth.get(v.key, v.default) for v in SEARCH_VARIANTS}


def variants_of(synth: Mapping[str, Any]) -> list[tuple[str, str]]:
    """(name suffix, override) for each setting of ``synth`` (a SynthConfig's fields by name, or a record's synth
    dict, see ``recorded_search``) that names the program."""
    found = recorded_search(synth)
    return [(v.suffix(found[v.key]), " " + override(v.key, found[v.key]))
            for v in SEARCH_VARIANTS if v.names(found[v.key])]


def search_variants(cfg: "RunConfig") -> list[tuple[str, str]]:
    """(name suffix, override) for each way a program's search differs from the default: the reference's hinge
    objective, scores kept to the other agent's features, ..."""
    return variants_of({v.key: getattr(cfg.synth, v.key) for v in SEARCH_VARIANTS})


def search_overrides(cfg: "RunConfig") -> str:
    """The command-line overrides that search ``cfg``'s program again: each setting that names the program, and each
    that differs from what a command line composes without it (synth.search=mcmc names nothing, mcmc being the
    tag's old default, yet hybrid is composed now; synth.objective's default is the task's own)."""
    from ..config import SynthConfig

    composed = {f.name: f.default for f in dataclasses.fields(SynthConfig)}
    composed["objective"] = cfg.task.objective
    out = []
    for v in SEARCH_VARIANTS:
        value = getattr(cfg.synth, v.key)
        if v.names(value) or value != composed[v.key]:
            out.append(" " + override(v.key, value))
    return "".join(out)


def point_tag(*, rules: int, lam: float, features: str) -> str:
    """The grid point's part of a program's tag (K, lambda, feature map): 'k2-lam0.5-v1'."""
    return f"k{rules}-lam{lam:g}-{features}"


def program_tag(*, rules: int, lam: float, features: str, synth: Mapping[str, Any]) -> str:
    """The tag of the program searched at a grid point with the settings ``synth`` (a record's synth dict; keys it
    lacks read as their defaults): 'k2-lam0.5-v1-hinge-hybrid'."""
    return point_tag(rules=rules, lam=lam, features=features) + "".join(s for s, _ in variants_of(synth))


def search_tag(cfg: "RunConfig") -> str:
    """K, lambda, feature map and search variant of a synthesized program (or a hand-written program's tag)."""
    if cfg.program:
        return user_program_tag(cfg)  # type: ignore[return-value]
    return point_tag(rules=cfg.rules, lam=cfg.lam, features=cfg.features) \
        + "".join(suffix for suffix, _ in search_variants(cfg))


def tag_prefixes() -> set[str]:
    """What the artifact tags of the program-running schemes start with ('' for prog, 'det-' for det-prog)."""
    from . import SCHEMES

    return {s.tag_prefix() for s in SCHEMES.values() if isinstance(s, Program)}


def _given(artifact: Path | None, scheme: "Searched") -> Path:
    """The file of a scheme's program or tree, as its caller passes it (run/ composes where it lives)."""
    if artifact is None:
        raise TypeError(f"{scheme.name} runs under a program or tree: pass its file as artifact=")
    return Path(artifact)


@dataclass
class Searched(OnOracle):
    """Runs under an artifact that `neurosym synth baseline=<search()>` makes from the oracle."""

    def search(self) -> str:
        """The baseline whose `synth` stage makes its artifact."""
        return self.name

    def tag_prefix(self) -> str:
        """What its artifact tags start with (the report tells retrainings apart by it)."""
        return ""

    def overrides(self, cfg: "RunConfig") -> str:
        """The search settings that make its artifact again, as command-line overrides."""
        return ""

    def upstream(self) -> list[Stage]:
        return [Stage("train", ORACLE), Stage("synth", self.search())]

    def requires(self, verb: str) -> tuple[Stage, ...]:
        return (Stage("train", ORACLE),)  # synth collects its dataset from the oracle

    def _line(self, verb: str, cfg: "RunConfig", baseline: str, extra: str = "") -> str:
        named = "" if VERB_DEFAULTS.get(verb) == baseline else f" baseline={baseline}"
        obj = self.overrides(cfg)
        return (f"neurosym {verb} task={cfg.task.name} rules={cfg.rules} lam={cfg.lam:g} features={cfg.features}"
                f" budget={cfg.budget.name} seed={cfg.seed}{runs_root_arg(cfg)}{named}{obj}{extra}")

    def command(self, verb: str, cfg: "RunConfig") -> str:
        if verb == "synth":
            return self._line("synth", cfg, self.search())
        if verb == "retrain":
            return self._line("retrain", cfg, self.name)
        return super().command(verb, cfg)

    def artifact_identity(self, cfg: "RunConfig", comm: Any, *, artifact: Path | None = None) -> str:
        """SHA-1 of what a model retrained under it is retrained under; ``artifact``: the file of its program or
        tree (run/layout.py)."""
        raise NotImplementedError


@dataclass
class Program(Searched):
    """prog, det-prog: the oracle under the synthesized program's hard attention (section 3.3)."""

    det: bool = False
    """no random rules (det-prog, paper appendix C)"""

    has_program = True

    def search(self) -> str:
        return "det-prog" if self.det else "prog"

    def tag_prefix(self) -> str:
        return "det-" if self.det else ""

    def overrides(self, cfg: "RunConfig") -> str:
        return search_overrides(cfg)

    def artifact(self, cfg: "RunConfig") -> Artifact:
        return Artifact(("det-" if self.det and not cfg.program else "") + search_tag(cfg), PROGRAM)

    def label(self, cfg: "RunConfig") -> str:
        return f"{self.name}-{search_tag(cfg)}"

    def command(self, verb: str, cfg: "RunConfig") -> str:
        if verb == "retrain" and cfg.program:
            return self._line("retrain", cfg, self.name, " " + shlex.quote(f"program={cfg.program}"))  # spaces
        return super().command(verb, cfg)

    def provider(self, cfg: "RunConfig", env: Any = None, *, artifact: Path | None = None):
        from ..dsl.files import load_program
        from ..policy.comm import ProgramComm

        from ..tasks.programs import check_program, feature_map

        path = _given(artifact, self)
        program = load_program(path, None if cfg.program else self.command("synth", cfg))
        fmap = feature_map(cfg, env)
        check_program(program, cfg, str(path), fmap)
        return ProgramComm(program, fmap)

    def rules(self, cfg: "RunConfig", comm: Any) -> int:
        from ..policy.protocol import unwrap

        return unwrap(comm).program.max_rules  # the file's K (program= is any file; a search may drop rules)

    def artifact_identity(self, cfg: "RunConfig", comm: Any, *, artifact: Path | None = None) -> str:
        from ..dsl.printer import to_text

        from ..policy.protocol import unwrap

        return hashlib.sha1(to_text(unwrap(comm).program).encode()).hexdigest()  # the rules, comments aside


@dataclass
class Tree(Searched):
    """dt: the oracle under a decision tree per round imitating a degree-capped hard attention (appendix B)."""

    def search(self) -> str:
        return "dt"

    def tag_prefix(self) -> str:
        return "dt-"

    def artifact(self, cfg: "RunConfig") -> Artifact:
        return Artifact(f"dt-k{cfg.rules}-{cfg.features}", TREE)

    def label(self, cfg: "RunConfig") -> str:
        return f"{self.name}-k{cfg.rules}-{cfg.features}"

    def provider(self, cfg: "RunConfig", env: Any = None, *, artifact: Path | None = None):
        from ..errors import UserError
        from ..policy.comm import TreeComm
        from ..synth.tree import TreeModel
        from ..utils.io import ArtifactError, read_json

        path = _given(artifact, self)
        if not path.exists():
            raise ArtifactError(f"no tree at {path}; create it with `{self.command('synth', cfg)}`")
        try:
            rounds = [TreeModel.from_dict(t) for t in read_json(path)["rounds"]]
        except (UserError, KeyError, TypeError, ValueError, IndexError) as e:
            raise ArtifactError(f"corrupt tree {path} ({e}); `{self.command('synth', cfg)} "
                                f"overwrite=true` fits it again") from None
        if len(rounds) != cfg.task.rounds:
            raise ConfigError(f"the tree file has {len(rounds)} round(s), the task {cfg.task.rounds}")
        from ..tasks.programs import feature_map

        return TreeComm(rounds, feature_map(cfg, env))

    def artifact_identity(self, cfg: "RunConfig", comm: Any, *, artifact: Path | None = None) -> str:
        return hashlib.sha1(_given(artifact, self).read_bytes()).hexdigest()  # the file it was read from


@dataclass
class RetrainedProgram(Retrained, Program):
    """prog-retrained, det-prog-retrained: the full method, the oracle retrained under the program (section 3.5)."""


@dataclass
class RetrainedTree(Retrained, Tree):
    """dt-retrained: the oracle retrained under the tree (appendix B)."""
