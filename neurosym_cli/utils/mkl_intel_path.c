/* MKL's code path on every x86 CPU vendor (docs/reliability.md, "The same numbers on every x86 machine").
 *
 * MKL asks this function whether the CPU is an Intel one and, on other vendors (AMD), runs other code in its
 * vector math (exp, log, sqrt: torch's float32 unary kernels and Adam's square root), even with MKL_CBWR=AVX2;
 * that code uses approximate instructions (rsqrtps) whose results differ between vendors, so AMD and Intel
 * machines disagree in the last bits, and training amplifies them. utils/cpu.py loads this library with
 * RTLD_GLOBAL before torch, so the libtorch_cpu.so that loads afterwards binds MKL's call to this definition
 * and takes MKL's Intel path, which is exact in those functions, on AMD as on Intel. Loaded only on x86-64 CPUs
 * with AVX2 and FMA, which that path needs. */
int mkl_serv_intel_cpu_true(void) { return 1; }
