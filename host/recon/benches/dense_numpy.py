"""numpy's side of `cargo bench -p et-recon --bench dense`: for each `.npy` matrix named on
the command line (in the directory given first), the median seconds of `H @ dv` over 1 000
calls with the matrix warm, and over 30 with the caches evicted first (a 64 MB array
written), H as the peer keeps it (f64, C order) and dv the frame of matching length
(`dv{K}.npy`); and warm in f32 (the same matrix rounded, as et applies it). One JSON object a
line. Run with one BLAS thread (the bench sets
OMP_NUM_THREADS=1 and OPENBLAS_NUM_THREADS=1)."""
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

directory = Path(sys.argv[1])
buffer = np.zeros(64 << 20, dtype=np.uint8)


def median_seconds(f, n, before=lambda: None):
    """The median time of `n` calls of `f`, each after `before`."""
    times = []
    for _ in range(n):
        before()
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def evict():
    buffer[::64] += 1


for name in sys.argv[2:]:
    h = np.ascontiguousarray(np.load(directory / name))
    dv = np.load(directory / f"dv{h.shape[1]}.npy").reshape(-1)
    h32, dv32 = h.astype(np.float32), dv.astype(np.float32)
    h @ dv
    h32 @ dv32
    print(
        json.dumps(
            {
                "matrix": name,
                "shape": list(h.shape),
                "warm_s": median_seconds(lambda: h @ dv, 1000),
                "warm_f32_s": median_seconds(lambda: h32 @ dv32, 1000),
                "cold_s": median_seconds(lambda: h @ dv, 30, evict),
            }
        ),
        flush=True,
    )
