/* MKL's code path on every x86 CPU vendor (docs/reliability.md, "The same numbers on every x86 machine").
 *
 * MKL asks mkl_serv_intel_cpu_true whether the CPU is an Intel one and, on other vendors (AMD), runs other code in
 * its vector math (exp, log, sqrt: torch's float32 unary kernels and Adam's square root), even with MKL_CBWR=AVX2;
 * that code uses approximate instructions (rsqrtps) whose results differ between vendors, so AMD and Intel
 * machines disagree in the last bits, and training amplifies them. utils/cpu.py loads this library with
 * RTLD_GLOBAL before torch, so the libtorch_cpu.so that loads afterwards binds MKL's call to this definition and
 * takes MKL's Intel path, which is exact in those functions, on AMD as on Intel. Loaded only on x86-64 CPUs with
 * AVX2 and FMA, which that path needs. The module init only makes the file an importable (empty) module. */
#include <Python.h>

int mkl_serv_intel_cpu_true(void) { return 1; }

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_mkl_intel_path",
                                    "MKL's Intel code path on every x86 vendor (neurosym_cli/utils/cpu.py)", -1, NULL};

PyMODINIT_FUNC PyInit__mkl_intel_path(void) { return PyModule_Create(&module); }
