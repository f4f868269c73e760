"""The import layers written in neurosym_cli/__init__.py hold: no module imports from a layer above its own."""

import ast
import re
from pathlib import Path

import neurosym_cli

PKG = Path(neurosym_cli.__file__).resolve().parent


def layers() -> dict[str, int]:
    """Top-level module or package name -> layer, from the package docstring's table."""
    table = re.findall(r"^\s*layer (\d+): ([a-z_ ]+?)\s{2,}", neurosym_cli.__doc__, flags=re.M)
    return {name: int(k) for k, names in table for name in names.split()}


def imports(path: Path) -> list[tuple[int, str]]:
    """(line, top-level neurosym_cli name) of every import in a file, lazy ones inside functions included."""
    tree = ast.parse(path.read_text())
    here = path.relative_to(PKG).with_suffix("").parts  # e.g. ("stages", "train")
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against this module's package
                base = list(here[:-1])[: len(here) - node.level] if node.level > 1 else list(here[:-1])
                parts = base + (node.module.split(".") if node.module else [])
                if not parts:  # `from . import x` at the top of the package, or `from .. import paths`
                    parts = [a.name for a in node.names]
                    out += [(node.lineno, p) for p in parts]
                    continue
                out.append((node.lineno, parts[0]))
            elif node.module and node.module.startswith("neurosym_cli."):
                out.append((node.lineno, node.module.split(".")[1]))
            elif node.module == "neurosym_cli":
                out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            out += [(node.lineno, a.name.split(".")[1]) for a in node.names if a.name.startswith("neurosym_cli.")]
    return out


def test_the_table_names_every_module():
    known = layers()
    assert known["config"] == 0 and known["cli"] == max(known.values())
    mods = {p.relative_to(PKG).parts[0].removesuffix(".py") for p in PKG.glob("*") if p.name != "__init__.py"
            and (p.suffix == ".py" or (p / "__init__.py").exists())}
    assert mods - {"__pycache__"} <= set(known), sorted(mods - set(known))


def test_no_module_imports_from_a_layer_above_its_own():
    known = layers()
    bad = []
    for path in sorted(PKG.rglob("*.py")):
        top = path.relative_to(PKG).parts[0].removesuffix(".py")
        if top == "__init__":
            continue
        for line, name in imports(path):
            if name in known and known[name] > known[top]:
                bad.append(f"{path.relative_to(PKG)}:{line} ({top}, layer {known[top]}) imports {name} "
                           f"(layer {known[name]})")
    assert not bad, "\n".join(bad)


def test_the_checker_sees_an_upward_import(tmp_path):
    """The check itself works: a layer-1 module importing the layer-5 stages is caught, absolute or relative."""
    for text in ("from ..stages import RunInfo\n", "import neurosym_cli.stages.train\n",
                 "def f():\n    from neurosym_cli.stages import graph\n"):
        fake = PKG / "dsl" / "_layer_probe.py"
        try:
            fake.write_text(text)
            assert imports(fake) and imports(fake)[0][1] == "stages"
        finally:
            fake.unlink()


def test_pyproject_lists_every_package():
    """A wheel carries only the packages pyproject.toml names: a new sub-package left out installs broken."""
    import tomllib

    listed = set(tomllib.loads((PKG.parent / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(("neurosym_cli",) + p.parent.relative_to(PKG).parts) for p in PKG.rglob("__init__.py")}
    assert found - listed == set(), "add these to [tool.setuptools] packages"
