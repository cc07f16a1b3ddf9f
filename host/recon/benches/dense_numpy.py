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
for name in sys.argv[2:]:
    h = np.ascontiguousarray(np.load(directory / name))
    dv = np.load(directory / f"dv{h.shape[1]}.npy").reshape(-1)
    h @ dv
    warm = []
    for _ in range(1000):
        t = time.perf_counter()
        h @ dv
        warm.append(time.perf_counter() - t)
    h32, dv32 = h.astype(np.float32), dv.astype(np.float32)
    h32 @ dv32
    warm32 = []
    for _ in range(1000):
        t = time.perf_counter()
        h32 @ dv32
        warm32.append(time.perf_counter() - t)
    cold = []
    for _ in range(30):
        buffer[::64] += 1
        t = time.perf_counter()
        h @ dv
        cold.append(time.perf_counter() - t)
    print(
        json.dumps(
            {
                "matrix": name,
                "shape": list(h.shape),
                "warm_s": statistics.median(warm),
                "warm_f32_s": statistics.median(warm32),
                "cold_s": statistics.median(cold),
            }
        ),
        flush=True,
    )
