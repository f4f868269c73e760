"""Which CPU kernels torch and MKL use: pinned to the AVX2 code paths and to MKL's Intel path by default, so one
seed and thread count give the same numbers on every x86-64 machine with AVX2, AMD or Intel, with or without
AVX-512 (docs/reliability.md, 'The same numbers on every x86 machine'). Stdlib only: it must run before torch is
imported, which reads these variables (and binds MKL's vendor check) when it loads.

The console script (cli.py) and ``import neurosym_cli`` call :func:`apply`; the mode travels to every child process
(joblib and process-pool workers, submitit jobs) in ``NEUROSYM_CPU_KERNELS``, which their own ``import
neurosym_cli`` reads before they import torch. :func:`runtime` is what each artifact records.
"""

from __future__ import annotations

import functools
import os
import platform
import sys

ENV = "NEUROSYM_CPU_KERNELS"
"""environment variable holding the mode: set by the console script for its children, or by a user"""
DEFAULT = "avx2"
CHOICES = {
    "avx2": "torch's and MKL's AVX2 code paths and MKL's Intel path on every vendor: the same numbers on every "
            "x86-64 machine with AVX2, AMD or Intel, with or without AVX-512",
    "avx2-vendor": "the AVX2 code paths, MKL's own path per CPU vendor: AMD and Intel machines differ in the last "
                   "bits (the default before 2026-12-03; docs/results.md's paper runs, made on AMD)",
    "native": "the widest kernels this CPU has, AVX-512 where present, MKL's own path per vendor",
}
"""cpu_kernels values -> what they do"""
PINNED_MODES = ("avx2", "avx2-vendor")
"""the modes that set PIN before torch loads"""
PIN = {"ATEN_CPU_CAPABILITY": "avx2", "MKL_CBWR": "AVX2", "ONEDNN_MAX_CPU_ISA": "AVX2"}
"""what the pinned modes set before torch loads: ATen's vectorized kernels (softmax, layer norm, elementwise), MKL's
BLAS (the matmuls: conditional numerical reproducibility, AVX2 branch) and oneDNN's ISA ceiling (no fp32 op of
this project reaches oneDNN on x86 today; the ceiling keeps it so if a torch release routes one there)"""
SHIM = "_mkl_intel_path"
"""the compiled library (utils/mkl_intel_path.c, built by setup.py) that gives every vendor MKL's Intel path: MKL's
vector math (exp, log, sqrt) runs other code on AMD than on Intel even with MKL_CBWR=AVX2"""

WAIT_POLICY = "PASSIVE"
"""OMP_WAIT_POLICY set before torch loads unless the user set one (GNU OpenMP reads it when it starts)"""

MARK = "NEUROSYM_PINNED"
"""the variables of PIN that neurosym set (comma-separated), so that native in a child of a pinned process undoes
them while a user's own settings stay"""

_state: dict[str, object] = {"mode": None, "warned": False, "shim": None, "why": None}
"""this process: the mode applied (None: not yet), whether its warning was printed, the shim's handle while it is
loaded (MKL then takes its Intel path), and why it was not loaded"""


def check(value: str) -> str | None:
    """A one-line error for an unknown cpu_kernels value, else None."""
    if value in CHOICES:
        return None
    return f"unknown cpu_kernels {value!r}; choose one of: " + ", ".join(f"{k} ({v})" for k, v in CHOICES.items())


def from_args(args: list[str]) -> str | None:
    """The value of ``cpu_kernels=`` on a command line (the last one wins, as in Hydra), else None."""
    value = None
    for a in args:
        key, sep, v = a.partition("=")
        if sep and key.lstrip("+") == "cpu_kernels":
            value = v.strip("'\"")
    return value


def requested() -> str:
    """The mode asked for through the environment (NEUROSYM_CPU_KERNELS), else the default."""
    return os.environ.get(ENV) or DEFAULT


@functools.lru_cache(maxsize=1)
def cpu_flags() -> frozenset[str]:
    """The CPU's feature flags from /proc/cpuinfo (Linux); empty where they cannot be read."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith(("flags", "Features")):
                    return frozenset(line.partition(":")[2].split())
    except OSError:
        pass
    return frozenset()


@functools.lru_cache(maxsize=None)
def _cpuinfo(key: str) -> str:
    """The first value of ``key`` in /proc/cpuinfo (Linux); "" where it cannot be read."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith(key):
                    return line.partition(":")[2].strip()
    except OSError:
        pass
    return ""


def cpu_vendor() -> str:
    """The CPU's vendor id (GenuineIntel, AuthenticAMD, ...): /proc/cpuinfo on Linux, else what platform reports
    (Windows names it there); "" where neither says."""
    found = _cpuinfo("vendor_id")
    if found:
        return found
    return next((v for v in ("GenuineIntel", "AuthenticAMD") if v in platform.processor()), "")


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo on Linux, else what platform reports)."""
    return _cpuinfo("model name") or platform.processor() or platform.machine()


def pinnable() -> bool:
    """Whether the AVX2 pin means anything here: an x86-64 CPU with AVX2 (elsewhere torch would reject or ignore
    it: ARM has other kernels and no MKL; an x86 CPU without AVX2 would fault on AVX2 code)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return False
    flags = cpu_flags()
    return not flags or "avx2" in flags  # unreadable flags (not Linux): every x86-64 CPU since 2013 has AVX2


def shim_path() -> str | None:
    """The compiled MKL-path library beside this file (built at install; None where it was not: no C compiler, not
    x86-64 Linux)."""
    here = os.path.dirname(os.path.abspath(__file__))
    for name in sorted(os.listdir(here)):
        if name.startswith(SHIM) and name.endswith(".so"):
            return os.path.join(here, name)
    return None


def _load_shim() -> None:
    """Before torch loads: make MKL take its Intel path (x86-64 with AVX2 and FMA, which that path needs). Loaded
    with RTLD_GLOBAL, its mkl_serv_intel_cpu_true comes before libtorch_cpu.so's own in the lookup of every library
    loaded later. Nothing happens where the library was not built (runtime() then records MKL's own path)."""
    flags = cpu_flags()
    if _state["shim"] is not None or not pinnable():
        return
    if flags and "fma" not in flags:
        _state["why"] = "this CPU has no FMA, which MKL's Intel AVX2 path needs"
        return
    path = shim_path()
    if path is None:
        _state["why"] = (f"neurosym_cli/utils/{SHIM}*.so was not built: reinstall neurosym where a C compiler is "
                         "present, with pip's --no-cache-dir --force-reinstall --no-deps")
        return
    import ctypes

    try:
        _state["shim"] = ctypes.CDLL(path, mode=os.RTLD_GLOBAL)
    except OSError as e:
        _state["why"] = f"{path} did not load ({e})"


def _unload_shim() -> None:
    """Before torch loads: undo :func:`_load_shim` (``import neurosym_cli`` applied the environment's mode, then the
    command line asked for another)."""
    if _state.get("shim") is None or _torch_mapped():
        return  # once libtorch_cpu.so bound MKL's call to it, unloading would leave that binding dangling
    from _ctypes import dlclose

    dlclose(_state["shim"]._handle)
    _state["shim"] = None


def _torch_mapped() -> bool:
    """Whether torch's CPU library is in this process already (even if ``torch`` is not in sys.modules)."""
    try:
        with open("/proc/self/maps") as f:
            return any("libtorch_cpu" in line for line in f)
    except OSError:
        return "torch" in sys.modules


def apply(mode: str | None = None) -> str | None:
    """Put ``mode`` (default: :func:`requested`) in effect for this process and its children. Before torch is
    imported it sets (avx2, avx2-vendor) or clears (native) the variables of ``PIN`` and loads (avx2) or unloads
    the shim; once torch is loaded nothing can change,
    so it returns a one-line warning when what torch loaded with differs from ``mode`` (else None). An unknown mode
    is left to the caller's check (the console script and RunConfig reject it in one line)."""
    mode = mode or requested()
    if mode not in CHOICES:
        return None
    os.environ[ENV] = mode  # children (joblib, process pools, submitit) read it in their own import neurosym_cli
    # OpenMP threads that wait for each other sleep instead of spinning: on a shared machine a spinning team takes
    # the cores the other processes need (issue 39: training 2.4x slower beside 3 busy processes at threads=2;
    # benchmarks/bench_contention.py). It moves no number (the work is split the same way); a user's setting stays.
    os.environ.setdefault("OMP_WAIT_POLICY", WAIT_POLICY)
    if "torch" in sys.modules:
        if _state["mode"] == mode:
            return None
        _state["mode"] = mode
        return _mismatch(mode)
    ours = {k for k in os.environ.get(MARK, "").split(",") if k in PIN}
    if mode == "avx2":
        _load_shim()
    else:
        _unload_shim()
    if mode in PINNED_MODES and pinnable():
        for key, value in PIN.items():
            if os.environ.get(key) != value:
                os.environ[key] = value
                ours.add(key)
        if ours:
            os.environ[MARK] = ",".join(sorted(ours))
    else:  # native, or a CPU the pin does not apply to: undo what neurosym set (a user's own settings stay)
        for key in ours:
            if os.environ.get(key) == PIN[key]:
                del os.environ[key]
        os.environ.pop(MARK, None)
    _state["mode"] = mode
    return None


def _intel_vendor() -> bool | None:
    """Whether the CPU is an Intel one (None: the vendor cannot be read)."""
    return cpu_vendor() == "GenuineIntel" if cpu_vendor() else None


def _intel() -> bool | None:
    """Whether MKL takes its Intel path in this process: the shim is loaded or the CPU is an Intel one (True), the
    CPU is another vendor's (False), unknown (None)."""
    return True if _state["shim"] is not None else _intel_vendor()


def _no_shim() -> str | None:
    """The warning of an avx2 process on another vendor's x86 CPU that could not load the shim: said once per
    process tree (children inherit the note that it was said), and only where the final mode is known (the command
    line's, a command's config), never by the import that applied the environment's."""
    if _state["mode"] != "avx2" or not pinnable() or _intel() is not False or os.environ.get("NEUROSYM_MKL_WARNED"):
        return None
    os.environ["NEUROSYM_MKL_WARNED"] = "1"
    why = _state.get("why") or "torch was loaded before cpu_kernels=avx2 took effect"
    return (f"cpu_kernels=avx2: MKL's Intel path is not in effect on this {cpu_vendor()} CPU ({why}), so numbers "
            "differ in the last digits from Intel machines")


def kept() -> list[str]:
    """The variables of PIN set in the environment by the user, not by neurosym (native leaves them in place)."""
    ours = set(os.environ.get(MARK, "").split(","))
    return [f"{k}={os.environ[k]}" for k in PIN if k in os.environ and k not in ours]


def in_effect() -> bool:
    """Whether the AVX2 pin held when torch loaded (judged from the variables torch and MKL read)."""
    return all(os.environ.get(k) == v for k, v in PIN.items() if k != "ONEDNN_MAX_CPU_ISA")


def _mismatch(mode: str) -> str | None:
    import torch

    cap = torch.backends.cpu.get_cpu_capability()
    pinned = cap == "AVX2" and in_effect()
    have = f"torch uses {cap} kernels, MKL_CBWR={os.environ.get('MKL_CBWR', 'unset')}"
    if mode in PINNED_MODES:
        if pinnable() and not pinned:
            return (f"cpu_kernels={mode}, but torch was imported before the kernels could be pinned ({have}); numbers "
                    "may differ in the last digits from other machines: import neurosym_cli before torch, or set "
                    "ATEN_CPU_CAPABILITY=avx2 MKL_CBWR=AVX2 first")
        if mode == "avx2-vendor" and _state["shim"] is not None and _intel_vendor() is False:
            return (f"cpu_kernels=avx2-vendor, but torch was loaded with MKL's Intel path on this {cpu_vendor()} CPU; "
                    f"this run uses it: set {ENV}=avx2-vendor before starting Python to keep MKL's own path")
        return None  # avx2 without the shim: _no_shim says so
    if not pinned:
        return None
    return (f"cpu_kernels=native, but torch was loaded with the AVX2 pin ({have}); this run uses the pinned "
            f"kernels: set {ENV}=native before starting Python to opt out")


def warn_once(mode: str | None = None, final: bool = True) -> None:
    """:func:`apply`, printing its warning (once per process) on stderr; ``final``: ``mode`` is the one the run
    computes with (the command line's or a command's config, not the import's guess), so a missing MKL Intel path
    is said too."""
    msg = apply(mode) or (_no_shim() if final else None)
    if msg and not _state["warned"]:
        _state["warned"] = True
        print(f"neurosym: warning: {msg}", file=sys.stderr)


def runtime() -> dict[str, object]:
    """What was in effect in this process, recorded beside every artifact: the cpu_kernels mode, torch's CPU
    capability, the variables of the pin, which of MKL's code paths ran ("intel": the shim was loaded or the CPU is
    an Intel one; "vendor": MKL's own path for another vendor; "unknown": the vendor cannot be read; None: not x86)
    and whether this process loaded the shim, the torch version, and the CPU (vendor, model, machine, AVX2 and
    AVX-512F), and the compile mode of the step."""
    import torch

    from . import compiling

    flags = cpu_flags()
    return {
        "cpu_kernels": _state["mode"] or requested(),
        "pinned": in_effect() and torch.backends.cpu.get_cpu_capability() == "AVX2",
        "capability": torch.backends.cpu.get_cpu_capability(),
        **{key.lower(): os.environ.get(key) for key in PIN},
        "mkl_path": None if not pinnable() else {True: "intel", False: "vendor", None: "unknown"}[_intel()],
        "mkl_shim": _state["shim"] is not None,
        "cpu_vendor": cpu_vendor(),
        "torch": str(torch.__version__),  # a plain str: a checkpoint loads with weights_only=True
        "cpu": cpu_model(),
        "machine": platform.machine(),
        "avx2": "avx2" in flags if flags else None,
        "avx512f": "avx512f" in flags if flags else None,
        "compile": compiling.record(),  # compile=: asked, in effect, why not, compile seconds (utils/compiling.py)
    }


def set_threads(n: int) -> None:
    """torch's intra-op threads: set now when torch is loaded, else through the environment it reads when it loads
    (OMP_NUM_THREADS, MKL_NUM_THREADS), so a command that never imports torch does not pay for importing it."""
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(n)
    else:
        os.environ["OMP_NUM_THREADS"] = os.environ["MKL_NUM_THREADS"] = str(n)
