"""Pin this process to one core before numpy loads, so the timings mean 'one core'.

The core is the lowest this process may use, or $PSORR_BENCH_CORE: two benchmarks run side by
side must be given different cores, or each would time the other's work as its own.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
if hasattr(os, "sched_setaffinity"):
    _allowed = os.sched_getaffinity(0)
    _core = int(os.environ.get("PSORR_BENCH_CORE", min(_allowed)))
    if _core not in _allowed:
        raise SystemExit(f"PSORR_BENCH_CORE={_core} is not one of this machine's cores {sorted(_allowed)}")
    os.sched_setaffinity(0, {_core})
