"""Schemes as plugins: every scheme, the built-in ones included, is registered by ``register`` (stdlib at import).

A scheme of one's own is a ``BaselineConfig`` subclass (usually ``families.OwnRule``) outside the package, found
one of two ways, as tasks are (tasks/registry.py):

    entry point     an installed package's ``[project.entry-points."neurosym.schemes"]`` ``knn = "pkg.mod:KNearest"``
                    (a class, made with ``name=knn``, or an instance): then ``baseline=knn``
    _target_        ``baseline._target_=pkg.mod.KNearest`` on the command line (or in ``ns.compose``'s overrides):
                    the class, made with its own default ``name``, imported from the working directory, a
                    ``--config-dir``'s folder or an installed package; the line then runs ``baseline=<its name>``

A class is made with its defaults; its description defaults to its docstring's first line; it is left out of the
pipeline's default list unless the class sets ``pipeline``. Every process resolves the same schemes: entry points
are read at import, and a ``_target_`` travels to workers (joblib, process pools, submitit) in NEUROSYM_SCHEMES.
A plugin that cannot be used (it does not import, breaks the contract, takes a built-in's name) is left out, and
naming it is one line saying why (``PROBLEMS``).
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import os
from typing import Any

from ..baselines import VERBS, BaselineConfig, Stage
from ..errors import ConfigError, cut, name_problem

ENTRY_POINTS = "neurosym.schemes"
"""entry-point group of installed scheme packages: name -> 'package.module:Class' (or an instance)"""

TARGETS_ENV = "NEUROSYM_SCHEMES"
"""the ``baseline._target_`` import paths of this command line, os.pathsep-separated, for every process it starts"""

TARGET_KEY = "baseline._target_"

SCHEMES: dict[str, BaselineConfig] = {}
"""name -> scheme, in registration order: the built-in ones in the paper's order (the order of every table), then
installed plugins, then those named by ``_target_``"""

BUILTIN_NAMES: set[str] = set()
"""the names of the package's own schemes (a plugin cannot take one)"""

PROBLEMS: dict[str, str] = {}
"""name -> why a plugin of that name is not registered (one line, said when the name is used)"""


def contract_problem(scheme: Any) -> str | None:
    """Why ``scheme`` cannot be registered (not a BaselineConfig dataclass, a bad name, no description, a question
    of the interface left unanswered, an upstream that is not stages ending in its weights), or None."""
    if not (isinstance(scheme, BaselineConfig) and dataclasses.is_dataclass(scheme)):
        return (f"is a {type(scheme).__name__}, not an instance of a dataclass extending "
                "neurosym_cli.baselines.BaselineConfig (schemes/families.py: OwnRule, OwnModel, OnOracle)")
    name = scheme.name
    why = name_problem(name) if isinstance(name, str) and name != "???" else "is missing"
    if why:
        return f"has a name that {why}; give the class a default name (name: str = 'my-scheme')"
    if not isinstance(scheme.description, str) or not scheme.description.strip():
        return "has no description; give the class a docstring or a default description"
    missing = [m for m in ("model_dir", "weights", "upstream", "command", "provider")
               if getattr(type(scheme), m) is getattr(BaselineConfig, m)]
    if missing:
        return (f"answers none of {', '.join(f'{m}()' for m in missing)}; extend OwnRule, OwnModel or OnOracle "
                "(docs/extending.md, section 6)")
    try:
        ups, weights = scheme.upstream(), scheme.weights()
    except Exception as e:  # the user's code: whatever it raises is its problem, said in one line
        return f"fails to name its stages ({type(e).__name__}: {cut(str(e).splitlines()[0] if str(e) else '')})"
    if not (isinstance(ups, list) and ups and all(isinstance(s, Stage) and s.verb in VERBS[:-1] for s in ups)
            and weights in ups):
        return f"has upstream() {cut(repr(ups))}: a list of train/synth/retrain Stages holding weights() {weights!r}"
    return None


def register(scheme: BaselineConfig, source: str) -> None:
    """Add ``scheme`` to ``SCHEMES`` (``source``: where it comes from, for messages: 'neurosym_cli' for the built-in
    ones, the entry point or import path for a plugin). One line when it breaks the contract or takes a name that
    another source registered."""
    why = contract_problem(scheme)
    if why:
        raise ConfigError(f"scheme {source} {why}")
    old = SCHEMES.get(scheme.name)
    if old is not None and old != scheme:
        whose = "a built-in scheme" if scheme.name in BUILTIN_NAMES else "another registered scheme"
        raise ConfigError(f"scheme {source} takes the name {scheme.name!r} of {whose}; give it another name")
    if source != "neurosym_cli":
        _check_fields(scheme, source)
    else:
        BUILTIN_NAMES.add(scheme.name)
    SCHEMES.setdefault(scheme.name, scheme)
    PROBLEMS.pop(scheme.name, None)


def _check_fields(scheme: BaselineConfig, source: str) -> None:
    """A plugin's fields are what a config holds (numbers, texts, booleans, lists of them): one line otherwise, not
    a traceback where Hydra stores it."""
    from omegaconf import OmegaConf

    try:
        OmegaConf.structured(scheme)
    except Exception as e:
        first = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise ConfigError(f"scheme {source} has a field a config cannot hold ({cut(first)}); use int, float, bool, "
                          "str or lists of them") from None


def _description(cls: type) -> str:
    """The first line of a class's own docstring ('' when it has none: a dataclass writes its signature there)."""
    doc = inspect.getdoc(cls) or ""
    return "" if doc.startswith(f"{cls.__name__}(") else doc.strip().splitlines()[0] if doc.strip() else ""


def made(obj: Any, name: str | None, source: str) -> BaselineConfig:
    """The scheme an import path names: an instance as it is (its name must be ``name`` when given), a class made
    with its defaults (``name=`` when given)."""
    if not inspect.isclass(obj):
        if name is not None and getattr(obj, "name", None) != name:
            raise ConfigError(f"scheme {source} is named {getattr(obj, 'name', None)!r}, not {name!r}")
        return obj
    if not (dataclasses.is_dataclass(obj) and issubclass(obj, BaselineConfig)):
        raise ConfigError(f"scheme {source} is the class {obj.__name__}, which does not extend "
                          "neurosym_cli.baselines.BaselineConfig as a dataclass (docs/extending.md, section 6)")
    kw: dict[str, Any] = {"name": name} if name is not None else {}
    if not obj.__dataclass_fields__["description"].default:
        kw["description"] = _description(obj)
    if not any("pipeline" in vars(k) for k in obj.__mro__[:obj.__mro__.index(BaselineConfig)]):
        kw["pipeline"] = False  # a plugin runs in `neurosym pipeline` when baselines= names it
    try:
        return obj(**kw)
    except ConfigError:
        raise
    except Exception as e:
        raise ConfigError(f"scheme {source}: {obj.__name__}({', '.join(f'{k}={v!r}' for k, v in kw.items())}) "
                          f"failed ({type(e).__name__}: {cut(str(e).splitlines()[0] if str(e) else '')})") from None


def load(target: str, name: str | None, key: str) -> BaselineConfig:
    """Import ``target`` ('pkg.mod:attr' or 'pkg.mod.attr'; ``key`` names where it was given) and register the
    scheme it names; returns it. One line when it cannot be."""
    from ..tasks.registry import import_target

    scheme = made(import_target(target, key=key), name, f"{key}={target}")
    register(scheme, f"{key}={target}")
    return scheme


def load_plugins() -> None:
    """Register the installed packages' schemes (entry points) and this command line's ``_target_`` ones
    (NEUROSYM_SCHEMES); one that cannot be used goes to ``PROBLEMS`` under its name."""
    from importlib.metadata import entry_points

    try:
        eps = [(ep.name, ep.value) for ep in entry_points(group=ENTRY_POINTS)]
    except Exception:  # a broken distribution's metadata must not break the CLI
        eps = []
    for name, value in dict(eps).items():  # one per name: the same distribution seen twice on the path
        try:
            load(value, name, f"entry point {ENTRY_POINTS}:{name}")
        except ConfigError as e:
            PROBLEMS[name] = str(e)
    for target in [t for t in os.environ.get(TARGETS_ENV, "").split(os.pathsep) if t]:
        try:
            load(target, None, TARGET_KEY)
        except ConfigError as e:
            PROBLEMS[target] = str(e)


def unknown(name: str) -> str:
    """The one line for a baseline name that is not registered: why, when a plugin of that name could not be,
    else the nearest name and every choice."""
    if name in PROBLEMS:
        return PROBLEMS[name]
    near = difflib.get_close_matches(name, list(SCHEMES), n=1, cutoff=0.6)
    hint = f"; did you mean baseline={near[0]}?" if near else ""
    return (f"unknown baseline {cut(repr(name))}{hint}; choose one of: {', '.join(SCHEMES)} (or your own: "
            f"{TARGET_KEY}=package.module.Class, or the entry-point group {ENTRY_POINTS})")


def targets_in(args: list[str]) -> tuple[list[str], str | None]:
    """The command line with each ``baseline._target_=X`` registered (and passed to the workers it starts) and
    replaced by ``baseline=<its name>``; returns (args, one-line error or None)."""
    out, named = [], []
    for a in args:
        key, sep, value = a.partition("=")
        if not (sep and key.lstrip("+") == TARGET_KEY):
            out.append(a)
            continue
        value = value.strip().strip("'\"")
        if "," in value:
            return args, f"{TARGET_KEY}={cut(value)}: one class per command line (run one command per scheme)"
        try:
            scheme = load(value, None, TARGET_KEY)
        except ConfigError as e:
            return args, str(e)
        old = [t for t in os.environ.get(TARGETS_ENV, "").split(os.pathsep) if t]
        os.environ[TARGETS_ENV] = os.pathsep.join(dict.fromkeys(old + [value]))
        named.append(scheme.name)
    if not named:
        return args, None
    given = {a.partition("=")[2] for a in out if a.partition("=")[0].lstrip("+") == "baseline"}
    if len(set(named)) > 1 or given - set(named):
        return args, (f"{TARGET_KEY} names {', '.join(sorted(set(named)))} while baseline= names "
                      f"{', '.join(sorted(given - set(named))) or 'another'}; name one scheme")
    out = [a for a in out if a.partition("=")[0].lstrip("+") != "baseline"]
    return out + [f"baseline={named[0]}"], None
