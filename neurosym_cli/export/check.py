"""`neurosym export export.check=true`: the folder's own checker (standalone/check.py, copied there) run in a
fresh Python process that cannot import neurosym, so an artifact that leans on neurosym fails here, not on the
robot."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

from ..errors import UserError
from .folder import manifest_problem

# the child refuses any import of neurosym before it runs check.py (an editable install would otherwise be found)
_ISOLATED = """import runpy, sys
class _NoNeurosym:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in ('neurosym', 'neurosym_cli'):
            raise ImportError('neurosym cannot be imported here: an export must stand alone')
        return None
sys.meta_path.insert(0, _NoNeurosym())
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name='__main__')
"""


def run_check(folder: Path, tolerance: float | None = None, required: list[str] | tuple = (), timeout: float = 600
              ) -> dict:
    """The checker's report (results per artifact, the first mismatch or None, whether neurosym was importable).
    ``required``: policy formats (export.formats) that must be in the folder and pass, not be skipped. A folder
    that is not an export, or a checker that cannot start, is one line."""
    folder = Path(folder).resolve()  # the checker runs in a temporary directory: a relative path would not reach
    problem = manifest_problem(folder) or (None if (folder / "check.py").is_file() else "it holds no check.py")
    if problem:
        raise UserError(f"{folder} is not an export folder ({problem}); `neurosym export` writes one")
    if tolerance is not None and not (math.isfinite(tolerance) and tolerance >= 0):
        raise UserError(f"the check's tolerance must be a finite number >= 0, got {tolerance}")
    with tempfile.TemporaryDirectory(prefix="neurosym-check-") as tmp:
        report = Path(tmp) / "report.json"
        cmd = [sys.executable, "-I", "-B", "-c", _ISOLATED, str(folder / "check.py"), str(folder), "--report",
               str(report)]
        if tolerance is not None:
            cmd += ["--tolerance", repr(tolerance)]
        if required:
            cmd += ["--require", ",".join(required)]
        try:  # cwd: an empty directory, so nothing beside the caller's working directory is importable either;
            # -B: the check writes nothing (no __pycache__) into the folder it checks
            p = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise UserError(f"the export check of {folder} took more than {timeout:g} s") from None
        if not report.exists():
            last = (p.stderr.strip().splitlines() or ["no output"])[-1]
            raise UserError(f"the export check of {folder} did not run (exit {p.returncode}): {last}")
        out = json.loads(report.read_text())
    out["exit"] = p.returncode
    return out
