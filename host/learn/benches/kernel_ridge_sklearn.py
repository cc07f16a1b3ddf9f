"""scikit-learn's side of `cargo bench -p et-learn --bench learn -- kernel_ridge`: the same
shapes (2 000 x 192 training rows, 500 rows to predict, random normal features, a smooth map
to three targets), Gaussian-kernel ridge with the same lambda. Run with one BLAS thread:

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python host/learn/benches/kernel_ridge_sklearn.py
"""
import time

import numpy as np
from sklearn.kernel_ridge import KernelRidge

rng = np.random.default_rng(7)
x = rng.standard_normal((2000, 192))
test = rng.standard_normal((500, 192))
t = np.stack([np.sin(x[:, 0]) * 40, np.tanh(x[:, 1] * x[:, 2]) * 40, np.abs(x[:, 3])], 1)
# gamma = width / median squared distance; for standard normal rows that median is 2 x 192.
model = KernelRidge(kernel="rbf", alpha=1e-2, gamma=0.5 / 384)
fits, predicts = [], []
for _ in range(5):
    start = time.perf_counter()
    model.fit(x, t)
    fits.append(time.perf_counter() - start)
    start = time.perf_counter()
    model.predict(test)
    predicts.append(time.perf_counter() - start)
print(f"scikit-learn fit: {np.median(fits):.3f} s, predict 500 rows: {np.median(predicts) * 1e3:.1f} ms (medians of 5)")
