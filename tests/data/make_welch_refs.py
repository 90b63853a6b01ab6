#!/usr/bin/env python3
"""Generate tests/data/welch_scipy_refs.json: scipy.signal.csd reference values for tests/welch_scipy.rs.

Run once (pip install scipy numpy); the JSON is committed, so the Rust tests never need Python.
Deterministic: seeded numpy, fixed cases. The JSON stores the input signals themselves, and for
each case `pxy[f][a][b] = scipy.signal.csd(x_a, x_b, ...)[f]` (scipy's convention, conj(X_a) X_b);
the Rust side checks S[f][i][j] == pxy[f][j][i].
"""
import json
import pathlib

import numpy as np
import scipy
import scipy.signal as sig

FS = 200.0
N_SAMPLES = 2003  # odd, and leaves partial segments for most cases

rng = np.random.default_rng(20240611)
t = np.arange(N_SAMPLES) / FS
e = rng.standard_normal((3, N_SAMPLES))
# Cross-correlated channels: a common driver, a filtered + delayed copy, offsets, trends, a tone.
x0 = e[0] + 0.8 * np.sin(2 * np.pi * 12.5 * t) + 3.0
x1 = 0.6 * np.roll(sig.lfilter([0.5, 0.3], [1.0, -0.4], e[0]), 3) + 0.4 * e[1] - 0.002 * np.arange(N_SAMPLES)
x2 = 0.3 * e[2] + 0.5 * e[1] + 1.5 * t - 7.0 + 0.2 * np.cos(2 * np.pi * 31.0 * t)
signals = np.vstack([x0, x1, x2])

# (window, nperseg, overlap fraction, detrend): scipy window name and detrend argument.
CASES = [
    ("boxcar", 64, 0.0, "constant"),
    ("boxcar", 100, 0.5, False),
    ("hann", 64, 0.5, "constant"),
    ("hann", 128, 0.75, "linear"),
    ("hann", 256, 0.5, False),
    ("hamming", 64, 0.25, "linear"),
    ("hamming", 98, 0.0, "constant"),
    ("blackmanharris", 64, 0.5, "constant"),
    ("blackmanharris", 128, 0.75, False),
    ("blackmanharris", 50, 0.5, "linear"),
    ("hann", 90, 0.33, "linear"),  # noverlap = round(29.7) = 30
]
WINDOW_NAMES = {"boxcar": "rectangular", "hann": "hann", "hamming": "hamming",
                "blackmanharris": "blackman_harris"}
DETREND_NAMES = {False: "none", "constant": "mean", "linear": "linear"}


def case(window, nperseg, overlap, detrend):
    noverlap = int(np.floor(overlap * nperseg + 0.5))  # Rust rounds half away from zero
    n = signals.shape[0]
    pxy = None
    for a in range(n):
        for b in range(n):
            f, p = sig.csd(signals[a], signals[b], fs=FS, window=window, nperseg=nperseg,
                           noverlap=noverlap, detrend=detrend, scaling="density",
                           return_onesided=True, average="mean")
            if pxy is None:
                pxy = np.zeros((len(f), n, n), dtype=complex)
            pxy[:, a, b] = p
    return {
        "settings": {"segment_len": nperseg, "overlap": overlap, "window": WINDOW_NAMES[window],
                     "detrend": DETREND_NAMES[detrend]},
        "noverlap": noverlap,
        "n_segments": (N_SAMPLES - noverlap) // (nperseg - noverlap),
        "frequency_hz": f.tolist(),
        "pxy_re": pxy.real.tolist(),
        "pxy_im": pxy.imag.tolist(),
    }


def main():
    out = {
        "generator": f"tests/data/make_welch_refs.py, scipy {scipy.__version__}, numpy {np.__version__}",
        "convention": "pxy[f][a][b] = scipy.signal.csd(x_a, x_b)[f] = mean conj(X_a) X_b, scaled",
        "sample_rate_hz": FS,
        "signals": signals.tolist(),
        "cases": [case(*c) for c in CASES],
    }
    path = pathlib.Path(__file__).with_name("welch_scipy_refs.json")
    path.write_text(json.dumps(out, separators=(",", ":")) + "\n")
    print(f"wrote {path} ({path.stat().st_size} bytes, {len(CASES)} cases)")


if __name__ == "__main__":
    main()
