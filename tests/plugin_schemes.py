"""The example scheme plugin (examples/schemes/random_k.py), registered for one test as its entry point registers it,
so the contract tests run over every registered scheme and a scheme from outside the package."""

from conftest import ROOT
from neurosym_cli.schemes import SCHEMES, registry

EXAMPLE_DIR = ROOT / "examples" / "schemes"
EXAMPLE = "random-k"
"""the example's name (its entry point's, examples/schemes/pyproject.toml)"""

ALL_SCHEMES = [*SCHEMES, *([EXAMPLE] if EXAMPLE not in SCHEMES else [])]
"""every registered scheme (the built-in ones, installed plugins) and the example"""


def use(name: str, monkeypatch) -> None:
    """Make ``name`` a registered scheme for this test: the example is imported from examples/schemes and registered
    through the registry's own checks, then taken out again when the test ends."""
    if name in SCHEMES:
        return
    assert name == EXAMPLE
    monkeypatch.syspath_prepend(str(EXAMPLE_DIR))
    from neurosym_cli.tasks.registry import import_target

    scheme = registry.made(import_target("random_k:RandomK"), EXAMPLE, "examples/schemes")
    assert registry.contract_problem(scheme) is None
    monkeypatch.setitem(SCHEMES, EXAMPLE, scheme)
