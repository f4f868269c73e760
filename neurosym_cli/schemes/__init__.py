"""The communication schemes: every baseline, registered once (stdlib at import, so `neurosym --help` stays fast;
what a scheme builds imports torch when it is built).

Everything else is derived from ``SCHEMES``: the config group ``baseline=`` (commands/apps.py stores each entry as
an option, its class as the schema), the pipeline's stage graph (stages/graph.py), the order and colours of every
results table and figure, the default of ``baselines=`` and the lists in ``neurosym --help``. A new baseline is one
class (families.py: ``OwnRule`` for a fixed rule with its own model) and one entry here; a scheme outside the package
is the same class, registered by the same ``registry.register`` through an entry point or ``baseline._target_``
(registry.py; docs/extending.md, section 6).
"""

from __future__ import annotations

from ..baselines import ORACLE, BaselineConfig
from ..errors import ConfigError
from . import registry
from .comm_range import CommRange
from .expo import Expo
from .gated import Gated
from .paper import Full, Nearest, Silent, TopK
from .searched import Program, RetrainedProgram, RetrainedTree, Tree

__all__ = ["BUILTIN", "ORACLE", "SCHEMES", "default_baselines", "get", "model_baseline", "rank", "register",
           "with_run"]

BUILTIN: tuple[BaselineConfig, ...] = (
    Full("tf-full", "the oracle: soft attention over every other agent (paper section 3.1)"),
    TopK("hard-attn", "the oracle, each agent hears only its k = rules largest attention logits"),
    Nearest("dist", "a transformer trained and run hearing its k = rules nearest agents"),
    Program("prog", "the oracle under the synthesized program's hard attention (section 3.3)"),
    RetrainedProgram("prog-retrained", "the full method: the oracle retrained under the program (section 3.5)"),
    Program("det-prog", "like prog, with argmax rules only (appendix C)", det=True),
    RetrainedProgram("det-prog-retrained", "det-prog with the oracle retrained under it (appendix C)", det=True),
    Tree("dt", "the oracle under a decision tree imitating a degree-capped hard attention (appendix C)"),
    RetrainedTree("dt-retrained", "dt with the oracle retrained under the tree (appendix C)"),
    Silent("no-comm", "a transformer trained and run with no communication (reference point)"),
    Gated("rl", "appendix D: whom to hear as actions, by policy gradient (`neurosym rl`: rl1, rl2)", pipeline=False),
    Expo("expo", "ExpoComm (ICLR 2025): its own transformer, agent i hears (i + 2^(t mod ceil(log2 N))) mod N",
         pipeline=False),
    CommRange("comm-range", "its own transformer, each agent hears every agent within baseline.radius (BenchMARL "
              "from_pos)", pipeline=False),
)
"""the package's own schemes, in the paper's order (the order of every table), the follow-ups after it"""

SCHEMES: dict[str, BaselineConfig] = registry.SCHEMES
"""name -> baseline: the built-in ones in the paper's order, then the plugins (registry.py)."""

register = registry.register
for _b in BUILTIN:
    register(_b, "neurosym_cli")


def get(name: str) -> BaselineConfig:
    """The baseline of that name; an unknown name is a one-line error listing the choices."""
    if name not in SCHEMES:
        raise ConfigError(registry.unknown(name))
    return SCHEMES[name]


def with_run(cfg, name: str) -> BaselineConfig:
    """Baseline ``name`` for a stage of the run ``cfg``: the run's own ``cfg.baseline`` when it is that one (so
    `neurosym pipeline baseline=comm-range baseline.radius=2` keeps its radius), else the registered one."""
    return cfg.baseline if cfg.baseline.name == name else get(name)


def rank(name: str) -> int:
    """Position of a baseline in the paper's order (unknown names last)."""
    return list(SCHEMES).index(name) if name in SCHEMES else len(SCHEMES)


def default_baselines() -> list[str]:
    """What `neurosym pipeline` makes and evaluates unless baselines= says otherwise, in the paper's order."""
    return [name for name, b in SCHEMES.items() if b.pipeline]


def model_baseline(model_dir: str) -> tuple[str, bool]:
    """A train/ directory name -> (the baseline that claims it longest, whether it is a retraining); an unclaimed
    name comes back as itself."""
    claims = [(b.claims(model_dir), -rank(name), name) for name, b in SCHEMES.items()]
    best, _, name = max(claims)
    if not best:
        return model_dir, False
    return name, SCHEMES[name].weights().verb == "retrain"


registry.load_plugins()  # installed packages' schemes and this command line's baseline._target_, once all of the
# above is defined: a plugin module may import this package while it loads
