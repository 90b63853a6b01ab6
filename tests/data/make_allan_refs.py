"""Reference values for tests/noise_allantools.rs, computed once with allantools and scipy.

    pip install allantools==2024.06 numpy scipy
    python3 tests/data/make_allan_refs.py > tests/data/allan_refs.json

Three seeded rate series (white; white plus a random walk; white plus a slow sinusoid and a
flicker-like sum of first-order processes) at 50 Hz, their overlapping Allan deviations
(`allantools.oadev`, data_type "freq"), the equivalent degrees of freedom of NIST SP 1065 Table 5
(`allantools.edf_simple`, for the noise types where it follows the table) and the one-sigma
intervals (`allantools.confidence_interval`), and chi-square quantiles (`scipy.stats.chi2.ppf`).
"""
import json

import allantools
import numpy as np
import scipy.stats

RATE = 50.0
N = 3000
rng = np.random.default_rng(20261124)
white = rng.normal(0.0, 1e-3, N)
walk = np.cumsum(rng.normal(0.0, 2e-5, N)) + rng.normal(0.0, 5e-4, N)
t = np.arange(N) / RATE
flicker = np.zeros(N)
for corner in [0.01, 0.1, 1.0, 10.0]:
    a = np.exp(-2 * np.pi * corner / RATE)
    e = rng.normal(0.0, 1e-4 * np.sqrt(1 - a * a), N)
    x = np.zeros(N)
    for i in range(1, N):
        x[i] = a * x[i - 1] + e[i]
    flicker += x
flicker += 3e-4 * np.sin(2 * np.pi * 0.3 * t) + rng.normal(0.0, 2e-4, N) + 5.0

ms = [1, 2, 3, 4, 6, 8, 11, 16, 23, 32, 45, 64, 91, 128, 181, 256, 362, 512, 724]
series = []
for name, y in [("white", white), ("walk", walk), ("flicker", flicker)]:
    taus, adev, _, ns = allantools.oadev(y, rate=RATE, data_type="freq", taus=np.array(ms) / RATE)
    got_ms = [int(round(tau * RATE)) for tau in taus]
    series.append({"name": name, "rate_hz": RATE, "y": [float(v) for v in y],
                   "m": got_ms, "adev": [float(v) for v in adev]})

# Phase points of a 3000-sample rate series: 3001.
edf = []
ci = []
for alpha in [2, 0, -2]:
    for m in [1, 4, 16, 64, 256, 724]:
        value = float(allantools.edf_simple(N + 1, m, alpha))
        edf.append({"n": N + 1, "m": m, "alpha": alpha, "edf": value})
        lo, hi = allantools.confidence_interval(1e-3, value, ci=0.6826894921370859)
        ci.append({"adev": 1e-3, "edf": value, "lo": float(lo), "hi": float(hi)})

quantiles = []
for dof in [0.8, 1.0, 2.5, 7.0, 33.3, 150.0, 1234.5, 98765.0]:
    for p in [1e-5, 0.0013, 0.15865525393145707, 0.5, 0.8413447460685429, 0.9987]:
        quantiles.append({"p": p, "dof": dof, "x": float(scipy.stats.chi2.ppf(p, dof))})

print(json.dumps({"source": f"allantools {allantools.__version__}, scipy {scipy.__version__}",
                  "series": series, "edf": edf, "ci": ci, "chi2_quantiles": quantiles}))
