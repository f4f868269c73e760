"""The Python API is a library: importing it, and composing a config through its choice checks, never imports the
console script (neurosym_cli/cli.py)."""

import json
import subprocess
import sys

CODE = """
import json, sys
import neurosym_cli.api as api
from neurosym_cli.errors import UserError
loaded = ["neurosym_cli.cli" in sys.modules]
try:
    api.compose(task="random-grdi")
except UserError as e:
    message = str(e)
loaded.append("neurosym_cli.cli" in sys.modules)
print(json.dumps({"cli_loaded": loaded, "message": message}))
"""


def test_the_api_does_not_import_the_console_script():
    p = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["cli_loaded"] == [False, False]
    assert "did you mean task=random-grid" in out["message"]  # the check ran, from the library module
