"""The `neurosym` console script: picks the subcommand from argv[1] and hands the rest to its Hydra app.

Imports nothing heavy, so `neurosym --help` answers in milliseconds (torch is imported by the commands).
"""

from __future__ import annotations

import os
import sys


def drop_working_directory() -> None:
    """Take the working directory off sys.path (`python -m` and `python -c` put it first), in this process and in
    its workers (PYTHONSAFEPATH, Python 3.11+: joblib's workers start with `python -m`): a user's own datetime.py or
    queue.py there would replace the standard library's in everything the command imports. Their task modules come
    back at the end of sys.path (tasks/registry.add_import_paths); a source checkout run from its own root keeps its
    place. Only for the console entry: a notebook importing this module keeps its path."""
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != os.getcwd()
                   or os.path.isfile(os.path.join(p or ".", "neurosym_cli", "cli.py"))]
    os.environ.setdefault("PYTHONSAFEPATH", "1")


if __name__ == "__main__":
    drop_working_directory()

import logging  # noqa: E402  (after the working directory left sys.path)
import re  # noqa: E402

from neurosym_cli.choices import check_choices, check_launcher, choices  # noqa: E402
from neurosym_cli.commands import COMMANDS  # noqa: E402

EXAMPLES = """examples:
  neurosym pipeline task=random-grid                 # the whole method and its baselines, quick budget
  neurosym pipeline -m seed=0,1,2 budget=paper       # per-seed pipelines at the paper's budget
  neurosym report budget=paper                       # mean ± std over those seeds, with a plot
  neurosym train task=random-cross budget=quick
  neurosym train task=random-grid baseline=dist
  neurosym eval task=random-cross baseline=hard-attn
  neurosym synth task=random-grid rules=2 lam=0.5 features=v1
  neurosym synth -m rules=2,3,4,5 lam=0.3,0.5,0.7,1.0 hydra/launcher=joblib
  neurosym show-program task=random-grid rules=2
  neurosym select task=random-grid budget=paper      # the paper's grid, chosen by validation (appendix B)
  neurosym pipeline task=random-grid selected=true   # every baseline with the selected K, lambda, features
  neurosym eval task=random-grid baseline=prog rules=2
  neurosym retrain task=random-grid rules=2 lam=0.5
  neurosym eval task=random-grid baseline=prog-retrained rules=2
  neurosym train -m seed=0,1,2 hydra/launcher=joblib
  neurosym pipeline -m seed=0,1,2 budget=paper hydra/launcher=slurm hydra.launcher.partition=cpu
  neurosym render task=two-groups-cross episode=2   # an episode as a GIF and a PNG (render.format=mp4)
  neurosym figures task=two-groups-cross            # attention maps, group paths, rule regions
  neurosym export task=two-groups-cross             # program (JSON/Python/C), policy (TorchScript, .pt2, ONNX), golden vectors
  neurosym export task=two-groups-cross --check     # replay them in a process without neurosym
  neurosym <command> --help        groups and options of one command
  neurosym <command> --cfg job     the composed config, without running
"""


def usage() -> str:
    """`neurosym --help`: the commands, examples, and the choices of each config group, from their one source."""
    from neurosym_cli.schemes import SCHEMES

    lines = ["usage: neurosym <command> [hydra overrides] [hydra flags]", "",
             "Neurosymbolic transformers for multi-agent communication (NeurIPS 2020).", "", "commands:"]
    lines += [f"  {name:<14} {text}" for name, (_, text) in COMMANDS.items()]
    lines += ["", EXAMPLES.rstrip(), ""]
    lines += [f"{group}s: {', '.join(choices(group))}" for group in ("task", "budget")]
    lines += ["baselines:"] + [f"  {b.name:<19} {b.description}" for b in SCHEMES.values()]
    from neurosym_cli.schemes.registry import PROBLEMS

    lines += [f"  {name:<19} not usable: {why}" for name, why in PROBLEMS.items()]  # installed plugins that fail
    return "\n".join(lines) + "\n"


# flags whose next argument is their value (Hydra's argparse rejects overrides that follow a flag)
_VALUED = {"--cfg", "-c", "--package", "-p", "--config-path", "-cp", "--config-name", "-cn", "--config-dir", "-cd",
           "--experimental-rerun"}
_INFO = {"all", "config", "defaults", "defaults-tree", "plugins", "searchpath"}


def hoist_flags(args: list[str]) -> list[str]:
    """Move flags (and their values) before the overrides, so `neurosym train seed=1 -m ...` works."""
    flags, rest, i = [], [], 0
    while i < len(args):
        a = args[i]
        if a.startswith("-"):
            flags.append(a)
            if (a in _VALUED or (a == "--info" and i + 1 < len(args) and args[i + 1] in _INFO)) and i + 1 < len(args):
                flags.append(args[i + 1])
                i += 1
        else:
            rest.append(a)
        i += 1
    return flags + rest


def pin_kernels(args: list[str]) -> str | None:
    """Put the ``cpu_kernels`` of the command line (else NEUROSYM_CPU_KERNELS, else avx2) in effect before torch is
    imported, in this process and through the environment in every job it starts; a one-line error for an unknown
    value or a sweep over it (each value needs its own processes), else None."""
    from neurosym_cli.utils import cpu

    value = cpu.from_args(args)
    if value is not None and "," in value:
        return (f"cpu_kernels={value}: one value per command (it is fixed before torch loads); run one sweep per "
                "value")
    mode = value if value is not None else cpu.requested()
    bad = cpu.check(mode)
    if bad:
        return bad if value is not None else f"{cpu.ENV}={mode}: {bad}"
    cpu.warn_once(mode)
    if mode == "native" and cpu.kept():
        print(f"neurosym: warning: cpu_kernels=native leaves {' '.join(cpu.kept())} of the environment in place",
              file=sys.stderr)
    return None


def swept_keys(args: list[str]) -> list[str]:
    """The keys a sweep varies (`seed=0,1`, `lam=range(...)`): a comma outside brackets and quotes, or a sweep
    function. Multirun jobs prefix their lines with these keys' values (passed in NEUROSYM_SWEPT)."""
    keys = []
    for a in args:
        key, sep, value = a.partition("=")
        if not sep or a.startswith("-"):
            continue
        depth, quote, comma = 0, "", False
        for ch in value:
            if quote:
                quote = "" if ch == quote else quote
            elif ch in "'\"":
                quote = ch
            elif ch in "[{(":
                depth += 1
            elif ch in "]})":
                depth -= 1
            elif ch == "," and depth == 0:
                comma = True
        if comma or value.startswith(("range(", "choice(", "glob(", "interval(")):
            keys.append(key.lstrip("+~"))
    return keys


READ_ONLY = ("show-program", "report")
"""commands that only read a runs directory: their logs go to the temp directory, never into a run directory (so
they also run on an archived, read-only one)"""


def _runs_root(args: list[str]) -> str:
    for a in args:
        if a.startswith(("runs_root=", "+runs_root=", "++runs_root=")):
            return a.split("=", 1)[1].strip("'\"")
    return os.environ.get("NEUROSYM_RUNS", "outputs")


def _writable(directory) -> bool:
    """Whether a directory can be written, by trying (os.access says yes to root even on a read-only mount)."""
    import tempfile

    try:
        os.rmdir(tempfile.mkdtemp(dir=directory, prefix=".neurosym-probe-"))
        return True
    except OSError:
        return False


def _log_dir(cmd: str, args: list[str]) -> tuple[list[str], str | None]:
    """Where the runs root cannot hold Hydra's log directory: one line for a command that writes there, and for a
    read-only command its logs moved to the temp directory. Returns (args, error)."""
    from pathlib import Path

    if any(a in ("--help", "-h", "--hydra-help", "--cfg", "-c", "--info", "-i", "--version") or a.startswith("-sc")
           for a in args):
        return args, None  # Hydra answers these without a run directory
    if not _runs_root(args).strip():  # Path("") is the working directory, and Hydra's ${runs_root}/... is "/..."
        return args, "runs_root is empty; name the directory that holds the runs (runs_root=outputs, or NEUROSYM_RUNS)"
    if any(a.partition("=")[0].lstrip("+") == "exp_dir" and not a.partition("=")[2].strip("'\" ") for a in args):
        return args, "exp_dir is empty; leave it out (it is <runs_root>/<task>/<budget>/seed<S>)"
    from neurosym_cli.errors import lies_under

    for a in args:  # Hydra makes its log directory under exp_dir before the schema can refuse it
        key, _, value = a.partition("=")
        if key.lstrip("+") == "exp_dir" and "${" not in value and not lies_under(value.strip("'\""), _runs_root(args)):
            return args, (f"exp_dir={value} lies outside runs_root={_runs_root(args)}; every artifact is written "
                          "under runs_root: set runs_root=... instead")
    root = Path(_runs_root(args)).expanduser().absolute()
    probe = root
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        return args, f"runs_root {root} lies under {probe}, which is a file, not a directory"
    if cmd not in READ_ONLY:
        if _writable(probe):
            return args, None
        return args, (f"cannot write to the runs directory {probe} (read-only); point runs_root=... (or "
                      f"NEUROSYM_RUNS) at a writable directory")
    if any(a.startswith(("hydra.run.dir=", "hydra.sweep.dir=")) for a in args):
        return args, None  # the user's own choice
    import tempfile
    import time

    logs = Path(tempfile.gettempdir()) / "neurosym-logs" / f"{cmd}-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    return [*args, f"hydra.run.dir={logs}", f"hydra.sweep.dir={logs}"], None


def _typed(cmd: str, args: list[str]):
    """The typed config ``neurosym <cmd> <args>`` would run with (flags and Hydra's own keys left out); bad input
    is one line and exit 2."""
    from neurosym_cli.commands.apps import compose_config
    from neurosym_cli.errors import UserError
    from neurosym_cli.tasks.registry import search_dirs

    hoisted = hoist_flags(args)
    n_flags = len(hoisted) - len([a for a in args if not a.startswith("-") and a not in _flag_values(args)])
    overrides = [a for a in hoisted[n_flags:] if not a.startswith(("hydra.", "hydra/", "+hydra", "~hydra"))]
    dirs = search_dirs(args)
    try:
        return compose_config(COMMANDS[cmd][0], overrides, str(dirs[0]) if dirs else None)
    except UserError as e:
        print(f"neurosym {cmd}: error: {e}", file=sys.stderr)
        raise SystemExit(2) from None


def print_typed_config(cmd: str, args: list[str]) -> None:
    """`--cfg job`: the typed config the run would use, every field of the task's own schema with its value and no
    interpolation left (``rules: 5``, not ``rules: ${task.rules}``); bad input is one line."""
    from omegaconf import OmegaConf

    sys.stdout.write(OmegaConf.to_yaml(OmegaConf.structured(_typed(cmd, args))))


def print_help(cmd: str, args: list[str]) -> None:
    """`neurosym <cmd> --help`: the groups, keys and sections the command reads, with their docstrings."""
    from neurosym_cli.helptext import command_help

    sys.stdout.write(command_help(cmd, _typed(cmd, args), lambda group: choices(group, args)))


def _flag_values(args: list[str]) -> set[str]:
    """The arguments that are values of a flag (`--config-dir DIR`, `--cfg job`), not overrides."""
    out = set()
    for i, a in enumerate(args[:-1]):
        if a in _VALUED or (a == "--info" and args[i + 1] in _INFO):
            out.add(args[i + 1])
    return out


def _complete() -> bool:
    """Bash completion through Hydra's hook: complete the subcommand, then delegate to its app."""
    line = os.environ.get("COMP_LINE", "")
    words = line.split()
    if len(words) <= 1 or (len(words) == 2 and not line.endswith(" ")):
        prefix = words[1] if len(words) > 1 else ""
        print(" ".join(c for c in COMMANDS if c.startswith(prefix)))
        return True
    if words[1] not in COMMANDS:
        return True
    os.environ["COMP_LINE"] = " ".join([words[0]] + words[2:]) + (" " if line.endswith(" ") else "")
    sys.argv = [sys.argv[0], *sys.argv[1:]]
    sys.argv.insert(1, words[1])
    return False


class QuietLauncherDump(logging.Filter):
    """Shortens the joblib launcher's first line, a dump of every joblib argument, to what a user chose."""

    def filter(self, record: logging.LogRecord) -> bool:
        msg = str(record.msg)
        if msg.startswith("Joblib.Parallel("):
            n_jobs = re.search(r"n_jobs=(-?\d+)", msg % record.args if record.args else msg)
            jobs = re.search(r"is launching (\d+) jobs", msg % record.args if record.args else msg)
            record.msg, record.args = (f"joblib: launching {jobs.group(1) if jobs else 'the'} jobs, "
                                       f"n_jobs={n_jobs.group(1) if n_jobs else '?'} at a time"), None
        return True


def main() -> None:
    drop_working_directory()
    try:
        _main()
    except KeyboardInterrupt:  # Ctrl-C before a command's own handler is in place (while torch imports)
        print("neurosym: interrupted before the command started; nothing was written", file=sys.stderr)
        raise SystemExit(130) from None


def _main() -> None:
    argv = sys.argv[1:]
    if argv[:2] == ["-sc", "query=bash"] and "COMP_LINE" in os.environ:
        if _complete():
            return
        argv = sys.argv[1:]
    if not argv or argv[0] in ("-h", "--help", "help"):
        sys.stdout.write(usage())
        return
    if argv[0] in ("--version", "-V"):
        from neurosym_cli import __version__

        print(f"neurosym {__version__}")
        return
    if argv[0].startswith("-sc"):  # `eval "$(neurosym -sc install=bash)"` installs completion
        argv = ["train", *argv]
    cmd, rest = argv[0], argv[1:]
    if cmd not in COMMANDS:
        from neurosym_cli.errors import unknown_command

        print(f"neurosym: error: {unknown_command(cmd, COMMANDS)}", file=sys.stderr)
        raise SystemExit(2)
    if cmd == "export":  # `neurosym export --check`: Hydra has no flags of its own for a verb, so it is an override
        rest = ["export.check=true" if a == "--check" else a for a in rest]
    from neurosym_cli import defaults
    from neurosym_cli.errors import UserError
    from neurosym_cli.overrides import check
    from neurosym_cli.tasks.registry import add_import_paths, force_task_keys, import_paths, task_schemas

    try:  # task= and budget= from NEUROSYM_TASK / NEUROSYM_BUDGET or ./neurosym.yaml when the line names none
        rest, sources = defaults.apply(rest)
    except defaults.DefaultsError as e:
        print(f"neurosym {cmd}: error: {e}", file=sys.stderr)
        raise SystemExit(2) from None
    os.environ[defaults.SOURCES_ENV] = defaults.describe(sources)  # the job's first log line names them
    add_import_paths(import_paths(rest))  # a user's task module, beside their config directory or in the cwd
    from neurosym_cli.schemes.registry import targets_in

    rest, bad = targets_in(rest)  # baseline._target_=pkg.Class: registered, then baseline=<its name>
    if bad:
        from neurosym_cli.errors import cut_words

        print(f"neurosym {cmd}: error: {cut_words(bad)}", file=sys.stderr)
        raise SystemExit(2)
    from neurosym_cli import argv as words
    from neurosym_cli.overrides import known_keys

    given, keys = _flag_values(rest), known_keys()
    bad = (words.check_words(rest, given, keys, lambda group: choices(group, rest))
           or words.check_grammar(rest, given, any(a in ("-m", "--multirun") for a in rest), keys))
    bad, schemas = bad or check_choices(rest, sources) or check_launcher(rest), []
    if not bad:
        try:  # the tasks' own schemas: their keys are known to the check (and a class that does not import is one line)
            schemas = task_schemas(rest, COMMANDS[cmd][0])
        except UserError as e:
            bad = str(e)
    bad = bad or check(rest, schemas) or pin_kernels(rest)
    rest = force_task_keys(rest, schemas)
    if bad:
        from neurosym_cli.errors import cut_words

        print(f"neurosym {cmd}: error: {cut_words(bad)}", file=sys.stderr)  # whoever wrote it, no 20,000-character word
        raise SystemExit(2)
    if any(a in ("--help", "-h") for a in rest):  # Hydra's own: --hydra-help
        print_help(cmd, [a for a in rest if a not in ("--help", "-h")])
        return
    rest, bad = _log_dir(cmd, rest)
    if bad:
        print(f"neurosym {cmd}: error: {bad}", file=sys.stderr)
        raise SystemExit(2)
    if any(a in ("--cfg", "-c") and rest[i + 1:i + 2] == ["job"] for i, a in enumerate(rest)):
        print_typed_config(cmd, rest)
        return
    if any(a in ("-m", "--multirun") for a in rest):
        os.environ["NEUROSYM_SWEPT"] = ",".join(swept_keys(rest))  # read by each job (commands/_run.py)
    sys.argv = [f"neurosym {cmd}", *hoist_flags(rest)]
    logging.getLogger("hydra_plugins.hydra_joblib_launcher._core").addFilter(QuietLauncherDump())
    from neurosym_cli.commands import apps

    apps.APPS[COMMANDS[cmd][0]]()


if __name__ == "__main__":
    main()
