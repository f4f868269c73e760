"""cpu_kernels: the AVX2 pin is in effect in every process that computes (the console script, joblib workers,
select's process pool, submitit jobs, Python code importing neurosym_cli), every artifact records it, native opts
out, and a bad value is one line. Each process starts from an environment without the pin's variables, so what
the test sees was set by neurosym itself."""

import json
import os
import shutil
import subprocess
import sys
import textwrap
from importlib.util import find_spec

import pytest
import torch

from conftest import ROOT, neurosym_cmd
from neurosym_cli.utils import cpu

PINNED = {"capability": "AVX2", "aten_cpu_capability": "avx2", "mkl_cbwr": "AVX2", "onednn_max_cpu_isa": "AVX2",
          "mkl_path": "intel", "mkl_shim": cpu.shim_path() is not None}
NATIVE = {"aten_cpu_capability": None, "mkl_cbwr": None, "onednn_max_cpu_isa": None, "mkl_shim": False}

needs_x86 = pytest.mark.skipif(not cpu.pinnable(), reason="the AVX2 pin applies to x86-64 CPUs with AVX2 only")


def clean_env(tmp_path, **extra) -> dict:
    """The environment of a fresh shell: none of the pin's variables, no mode, runs under tmp_path."""
    env = {k: v for k, v in os.environ.items() if k not in (*cpu.PIN, cpu.ENV, cpu.MARK, "NEUROSYM_MKL_WARNED")}
    return {**env, "NEUROSYM_RUNS": str(tmp_path), **extra}


def cli(args, tmp_path, env=None, timeout=300, check=True):
    p = subprocess.run([*neurosym_cmd(), *args], cwd=tmp_path, env=env or clean_env(tmp_path), capture_output=True,
                       text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"exit {p.returncode}\nstdout:\n{p.stdout}\nstderr:\n{p.stderr}")
    return p


def python(code, tmp_path, env=None):
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=tmp_path, env=env or clean_env(tmp_path),
                          capture_output=True, text=True, timeout=120)


def subset(record: dict, expected: dict) -> dict:
    return {k: record.get(k) for k in expected}


TINY = ["task=two-groups-cross", "budget=tiny", "threads=1", "plots=false"]


@needs_x86
def test_the_console_script_pins_and_every_artifact_records_it(tmp_path):
    cli(["train", *TINY], tmp_path)
    cli(["synth", *TINY, "budget.mcmc_steps=20"], tmp_path)
    cli(["eval", *TINY, "baseline=prog"], tmp_path)
    exp = tmp_path / "two-groups-cross/tiny/seed0"
    records = {"manifest.json": json.loads((exp / "train/oracle/manifest.json").read_text())["runtime"],
               "model.pt": torch.load(exp / "train/oracle/model.pt", weights_only=True)["runtime"],
               "summary.json": json.loads(next((exp / "synth").glob("*/summary.json")).read_text())["runtime"],
               "metrics.json": json.loads(next((exp / "eval").glob("prog*/metrics.json")).read_text())["runtime"]}
    for name, r in records.items():
        assert subset(r, PINNED) == PINNED and r["pinned"] is True and r["cpu_kernels"] == "avx2", (name, r)
        assert r["torch"] == torch.__version__ and r["cpu"] and r["avx512f"] in (True, False), (name, r)
    manifest = json.loads((exp / "train/oracle/manifest.json").read_text())
    assert manifest["config"]["cpu_kernels"] == "avx2"  # the request, beside what was in effect


@needs_x86
def test_native_leaves_the_environment_alone(tmp_path):
    cli(["train", *TINY, "cpu_kernels=native"], tmp_path)
    m = json.loads((tmp_path / "two-groups-cross/tiny/seed0/train/oracle/manifest.json").read_text())
    assert subset(m["runtime"], NATIVE) == NATIVE, m["runtime"]
    assert m["runtime"]["cpu_kernels"] == "native" and m["runtime"]["pinned"] is False
    assert m["config"]["cpu_kernels"] == "native"


@needs_x86
def test_native_under_a_pinned_parent_opts_out_and_a_users_own_setting_stays(tmp_path):
    """A neurosym process started by a pinned one (a script that imported neurosym_cli) inherits the pin's
    variables: native undoes what neurosym set, not what the user exported (and says so)."""
    inherited = python("import os, neurosym_cli; print(os.environ['NEUROSYM_PINNED'])", tmp_path).stdout.strip()
    env = clean_env(tmp_path, NEUROSYM_PINNED=inherited, **cpu.PIN, NEUROSYM_CPU_KERNELS="avx2")
    code = "import os, neurosym_cli.cli as c; c.pin_kernels(['cpu_kernels=native']); print(os.environ.get('MKL_CBWR'))"
    p = python(code, tmp_path, env)
    assert p.returncode == 0 and p.stdout.strip() == "None" and p.stderr == "", p.stderr
    env = clean_env(tmp_path, MKL_CBWR="AVX2")  # the user's own
    p = python(code, tmp_path, env)
    assert p.stdout.strip() == "AVX2", p.stderr
    assert p.stderr.strip() == "neurosym: warning: cpu_kernels=native leaves MKL_CBWR=AVX2 of the environment in place"


@needs_x86
def test_joblib_workers_are_pinned(tmp_path):
    p = cli(["train", "-m", "seed=0,1", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2", *TINY], tmp_path)
    for s in (0, 1):
        m = json.loads((tmp_path / f"two-groups-cross/tiny/seed{s}/train/oracle/manifest.json").read_text())
        assert subset(m["runtime"], PINNED) == PINNED, (s, m["runtime"], p.stdout)


@needs_x86
@pytest.mark.skipif(find_spec("hydra_plugins.hydra_submitit_launcher") is None,
                    reason="hydra-submitit-launcher is not installed (the dev or cluster extra)")
def test_a_submitit_job_is_pinned(tmp_path):
    cli(["train", "-m", "seed=0", "hydra/launcher=submitit_local", *TINY], tmp_path, timeout=600)
    m = json.loads((tmp_path / "two-groups-cross/tiny/seed0/train/oracle/manifest.json").read_text())
    assert subset(m["runtime"], PINNED) == PINNED, m["runtime"]


PROBE = """
import os


def job(cfg, info):
    from neurosym_cli.utils.cpu import runtime

    return {"name": f"seed{cfg.seed}", "pid": os.getpid(), **runtime()}
"""

POOL = """
import json, os
from neurosym_cli.stages import RunInfo
from neurosym_cli.stages.jobs import run_jobs
import probe

from neurosym_cli.api import compose

cfgs = [compose("train", ["task=random-grid", "budget=tiny", f"seed={s}"]) for s in (0, 1)]
print(json.dumps({"pid": os.getpid(), "rows": run_jobs(probe.job, cfgs, RunInfo(), 2, "probe", name=str)}))
"""


@needs_x86
@pytest.mark.parametrize("mode", ["avx2", "native"])
def test_select_and_rl_pool_workers_follow_the_mode(tmp_path, mode):
    """select and rl run their grid points through run_jobs: a spawned process pool."""
    (tmp_path / "probe.py").write_text(PROBE)
    env = clean_env(tmp_path, PYTHONPATH=str(tmp_path), NEUROSYM_CPU_KERNELS=mode)
    p = python(POOL, tmp_path, env)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert all(r["pid"] != out["pid"] for r in out["rows"]), "the jobs ran in the parent"
    want = PINNED if mode == "avx2" else NATIVE
    for r in out["rows"]:
        assert subset(r, want) == want and r["cpu_kernels"] == mode, r


@needs_x86
def test_importing_neurosym_first_pins_without_importing_torch(tmp_path):
    p = python("""
        import os, sys
        import neurosym_cli
        assert "torch" not in sys.modules
        import torch
        print(torch.backends.cpu.get_cpu_capability(), os.environ["MKL_CBWR"], os.environ["NEUROSYM_CPU_KERNELS"])
        """, tmp_path)
    assert p.returncode == 0 and p.stdout.split() == ["AVX2", "AVX2", "avx2"], p.stderr
    assert p.stderr == ""


def test_torch_imported_first_is_one_warning_line(tmp_path):
    p = python("""
        import os, torch
        import neurosym_cli
        from neurosym_cli.utils.cpu import runtime
        print(runtime()["pinned"], os.environ.get("MKL_CBWR"))
        """, tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["False", "None"]  # not pinned, and the record does not pretend it is
    lines = p.stderr.strip().splitlines()
    if cpu.pinnable():
        assert len(lines) == 1 and lines[0].startswith("neurosym: warning: cpu_kernels=avx2, but torch was imported "
                                                       "before the kernels could be pinned"), p.stderr
    # the pin set by hand before torch: nothing to say
    p = python("import torch, neurosym_cli", tmp_path, clean_env(tmp_path, ATEN_CPU_CAPABILITY="avx2", MKL_CBWR="AVX2"))
    assert p.returncode == 0 and p.stderr == "", p.stderr


@needs_x86
def test_a_config_that_comes_too_late_is_one_warning_line(tmp_path):
    """A Hydra app called without the console script: the import pinned (the default), the config says native."""
    p = python(f"""
        import sys
        from neurosym_cli.commands.apps import APPS
        sys.argv = ["neurosym train", *{TINY!r}, "cpu_kernels=native"]
        APPS["train"]()
        """, tmp_path)
    assert p.returncode == 0, p.stderr
    warnings = [line for line in p.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "cpu_kernels=native, but torch was loaded with the AVX2 pin" in warnings[0], p.stderr
    m = json.loads((tmp_path / "two-groups-cross/tiny/seed0/train/oracle/manifest.json").read_text())
    assert m["runtime"]["cpu_kernels"] == "native" and m["runtime"]["pinned"] is True  # the truth, not the request


@pytest.mark.parametrize("args,env,needle", [
    (["cpu_kernels=avx512"], {}, "unknown cpu_kernels 'avx512'; choose one of: avx2 ("),
    (["-m", "cpu_kernels=avx2,native"], {}, "cpu_kernels=avx2,native: one value per command"),
    ([], {"NEUROSYM_CPU_KERNELS": "fast"}, "NEUROSYM_CPU_KERNELS=fast: unknown cpu_kernels 'fast'"),
])
def test_a_bad_value_is_one_line(tmp_path, args, env, needle):
    p = cli(["train", *TINY, *args], tmp_path, env=clean_env(tmp_path, **env), check=False)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert needle in p.stderr and "Traceback" not in p.stderr, p.stderr
    assert not (tmp_path / "two-groups-cross").exists()


def test_the_schema_rejects_an_unknown_value_in_one_line():
    from neurosym_cli.config import ConfigError, RunConfig

    with pytest.raises(ConfigError, match=r"^unknown cpu_kernels 'x'; choose one of: avx2 .*, native "):
        RunConfig(cpu_kernels="x")
    assert RunConfig().cpu_kernels == cpu.DEFAULT == "avx2"


def test_the_mode_is_read_from_the_command_line_then_the_environment(monkeypatch):
    assert cpu.from_args(["seed=1", "cpu_kernels=native", "+cpu_kernels='avx2'"]) == "avx2"  # the last one wins
    assert cpu.from_args(["seed=1"]) is None
    monkeypatch.delenv(cpu.ENV, raising=False)
    assert cpu.requested() == "avx2"
    monkeypatch.setenv(cpu.ENV, "native")
    assert cpu.requested() == "native"


def test_the_test_process_itself_is_pinned():
    """conftest imports neurosym_cli before torch, so the in-process tests compute with the pin too."""
    if cpu.pinnable() and cpu.requested() == "avx2" and not any(os.environ.get(k) not in (None, v) for k, v in cpu.PIN.items()):
        r = cpu.runtime()
        assert r["pinned"] is True and r["capability"] == "AVX2", r


def test_help_stays_free_of_torch():
    code = ("import sys; sys.argv=['neurosym','--help']; from neurosym_cli.cli import main; main(); "
            "assert 'torch' not in sys.modules, 'torch imported'")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr


# ------------------------------------------------------------------------------------------ MKL's path per vendor
x86_linux = pytest.mark.skipif(not (cpu.pinnable() and sys.platform.startswith("linux")),
                               reason="MKL's vendor path concerns x86-64 Linux with AVX2")


@x86_linux
def test_the_install_built_the_mkl_path_library():
    """setup.py builds it with the package (optional: without a compiler the install goes on, and then this says
    so); it defines the one function MKL asks."""
    import ctypes

    path = cpu.shim_path()
    assert path is not None, "neurosym_cli/utils/_mkl_intel_path*.so is missing: reinstall with a C compiler present"
    assert ctypes.CDLL(path).mkl_serv_intel_cpu_true() == 1


@x86_linux
def test_avx2_loads_mkls_intel_path_before_torch_and_avx2_vendor_does_not(tmp_path):
    code = """
        import json, neurosym_cli, torch
        from neurosym_cli.utils.cpu import runtime, SHIM
        maps = open("/proc/self/maps").read()
        print(json.dumps({**runtime(), "mapped": SHIM in maps}))
        """
    for mode, shim in (("avx2", cpu.shim_path() is not None), ("avx2-vendor", False), ("native", False)):
        p = python(code, tmp_path, clean_env(tmp_path, NEUROSYM_CPU_KERNELS=mode))
        assert p.returncode == 0 and p.stderr == "", p.stderr
        r = json.loads(p.stdout)
        assert r["mkl_shim"] is shim and r["mapped"] is shim, (mode, r)
        assert r["cpu_kernels"] == mode and r["pinned"] is (mode != "native"), (mode, r)


def test_another_vendor_without_the_library_is_warned_once_and_only_for_the_final_mode(monkeypatch, capsys):
    monkeypatch.setattr(cpu, "cpu_vendor", lambda: "AuthenticAMD")
    monkeypatch.setattr(cpu, "pinnable", lambda: True)
    monkeypatch.setitem(cpu._state, "shim", None)
    monkeypatch.setitem(cpu._state, "why", "neurosym_cli/utils/_mkl_intel_path*.so was not built: reinstall")
    monkeypatch.setitem(cpu._state, "warned", False)
    monkeypatch.setenv("NEUROSYM_MKL_WARNED", "")  # restored (removed) at the end
    monkeypatch.setitem(cpu._state, "mode", "avx2-vendor")
    assert cpu._no_shim() is None  # the command line asked for another mode: nothing to say about avx2
    monkeypatch.setitem(cpu._state, "mode", "avx2")
    msg = cpu._no_shim()
    assert msg and msg.startswith("cpu_kernels=avx2: MKL's Intel path is not in effect on this AuthenticAMD CPU ("), msg
    assert "was not built: reinstall" in msg and "\n" not in msg
    assert cpu._no_shim() is None  # once per process tree (children inherit NEUROSYM_MKL_WARNED)
    monkeypatch.setenv("NEUROSYM_MKL_WARNED", "")
    monkeypatch.setitem(cpu._state, "shim", object())
    assert cpu._no_shim() is None  # loaded: nothing to say
    monkeypatch.setitem(cpu._state, "shim", None)
    cpu.warn_once("avx2", final=False)  # the import's guess: silent
    assert capsys.readouterr().err == ""


def test_avx2_vendor_after_torch_loaded_mkls_intel_path_is_one_warning_line(monkeypatch):
    """An AMD user who imported neurosym_cli (avx2: the library loaded) and torch, then asks for avx2-vendor to
    reproduce the old runs, is told that this process cannot give it."""
    monkeypatch.setattr(cpu, "cpu_vendor", lambda: "AuthenticAMD")
    monkeypatch.setattr(cpu, "in_effect", lambda: True)
    monkeypatch.setitem(cpu._state, "shim", object())
    msg = cpu._mismatch("avx2-vendor")
    assert msg and msg.startswith("cpu_kernels=avx2-vendor, but torch was loaded with MKL's Intel path on this "
                                  "AuthenticAMD CPU") and "NEUROSYM_CPU_KERNELS=avx2-vendor" in msg
    monkeypatch.setattr(cpu, "cpu_vendor", lambda: "GenuineIntel")
    assert cpu._mismatch("avx2-vendor") is None  # on Intel the two modes compute the same


@x86_linux
@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler to build a test library")
def test_the_installed_torch_lets_a_library_loaded_before_it_answer_mkls_vendor_check(tmp_path):
    """What avx2 rests on: libtorch_cpu.so's MKL asks mkl_serv_intel_cpu_true through a binding that a library
    loaded with RTLD_GLOBAL before torch takes over. Checked by effect on this machine: a library answering "not
    Intel" changes MKL's float32 exp (its other vendor's path) against the same process without it. A torch build
    that bound the call inside its own library would fail here."""
    src = tmp_path / "not_intel.c"
    src.write_text("int mkl_serv_intel_cpu_true(void) { return 0; }\n")
    lib = tmp_path / "not_intel.so"
    subprocess.run(["cc", "-shared", "-fPIC", str(src), "-o", str(lib)], check=True)
    code = """
        import ctypes, hashlib, os, sys
        if sys.argv[1:] == ["preload"]:
            ctypes.CDLL(os.environ["LIB"], mode=os.RTLD_GLOBAL)
        import torch
        x = torch.linspace(-5, 5, 100_000)
        print(hashlib.sha1((x.exp().numpy().tobytes() + x.abs().add(1e-3).log().numpy().tobytes())).hexdigest())
        """
    env = clean_env(tmp_path, LIB=str(lib), ATEN_CPU_CAPABILITY="avx2", MKL_CBWR="AVX2")
    runs = {}
    for arg in ("plain", "preload"):
        p = subprocess.run([sys.executable, "-c", textwrap.dedent(code), arg], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stderr
        runs[arg] = p.stdout.strip()
    if cpu.cpu_vendor() == "GenuineIntel":
        assert runs["plain"] != runs["preload"], "MKL did not ask the library loaded before torch"
    else:  # on another vendor MKL already takes its other path: the library agrees with it
        assert runs["plain"] == runs["preload"]


QEMU = shutil.which("qemu-x86_64")


@x86_linux
@pytest.mark.slow
@pytest.mark.skipif(QEMU is None, reason="needs qemu-x86_64 (Debian's qemu-user) to emulate an AMD CPU")
def test_an_emulated_amd_cpu_trains_the_weights_of_this_one(tmp_path):
    """The claim of avx2: the same numbers on AMD as on Intel. QEMU emulates an AMD EPYC (Zen 2: AVX2, no AVX-512)
    whose CPUID MKL reads, with IEEE-exact arithmetic (its approximate rsqrtps/rcpps are not the hardware's, which
    is why MKL's AMD path, using them, gives a third result there); the weights a short training run gives there
    under avx2 are this machine's, bit for bit, and under avx2-vendor they are not (the test can fail)."""
    args = ["train", *TINY, "budget.horizon=20"]

    def weights(root, mode, emulate):
        env = clean_env(root, NEUROSYM_CPU_KERNELS=mode)
        pre = [QEMU, "-cpu", "EPYC-Rome"] if emulate else []
        p = subprocess.run([*pre, sys.executable, "-m", "neurosym_cli.cli", *args], cwd=ROOT, env=env,
                           capture_output=True, text=True, timeout=900)
        assert p.returncode == 0, p.stderr[-2000:]
        ck = torch.load(root / "two-groups-cross/tiny/seed0/train/oracle/model.pt", weights_only=True)
        return ck["state_dict"], ck["runtime"]

    here, rt = weights(tmp_path / "here", "avx2", False)
    amd, rt_amd = weights(tmp_path / "amd", "avx2", True)
    assert rt_amd["mkl_shim"] is True and rt_amd["mkl_path"] == "intel"
    assert all(torch.equal(here[k], amd[k]) for k in here), "avx2 on an emulated AMD CPU trained other weights"
    vendor, _ = weights(tmp_path / "amd-vendor", "avx2-vendor", True)
    assert not all(torch.equal(here[k], vendor[k]) for k in here), "MKL's AMD path gave Intel's weights"


@pytest.mark.parametrize("users, want", [(None, "PASSIVE"), ("ACTIVE", "ACTIVE")])
def test_idle_openmp_threads_sleep_unless_the_user_says_otherwise(tmp_path, users, want):
    """Issue 39: spinning OpenMP threads collapse training beside other busy processes, so importing neurosym sets
    OMP_WAIT_POLICY=PASSIVE before torch loads; a user's own value stays, and children inherit it."""
    env = {k: v for k, v in clean_env(tmp_path).items() if k != "OMP_WAIT_POLICY"}
    if users:
        env["OMP_WAIT_POLICY"] = users
    p = python("""
        import os, subprocess, sys
        import neurosym_cli
        child = subprocess.run([sys.executable, "-c", "import os; print(os.environ['OMP_WAIT_POLICY'])"],
                               capture_output=True, text=True).stdout.strip()
        print(os.environ["OMP_WAIT_POLICY"], child)
        """, tmp_path, env=env)
    assert p.returncode == 0 and p.stdout.split() == [want, want], p.stderr


def test_one_thread_is_the_default():
    """Issue 39: threads=1 by default (the same numbers on every core count; no collapse under contention)."""
    from neurosym_cli.config import RunConfig

    assert RunConfig().threads == 1
