"""The real recordings' gyro delay, checked independently of imu-attest (numpy and scipy only).

    pip install numpy scipy
    python3 tests/data/real/check_delays.py tests/data/real/*.csv.gz

Nothing here comes from the identifier. Body rates are computed from the reference angles by the
exact kinematics (R = Ry(yaw) Rz(pitch) Rx(roll), the contract's yaw -> pitch -> roll order;
Omega = R^T dR/dt, differentiated by central differences, a zero-phase operation). Two estimates
per gyro channel:

1. **Regression delay**: rates and gyro band-passed to 0.2-8 Hz by a zero-phase Butterworth
   (`sosfiltfilt`), each gyro channel regressed on the three rates shifted by a trial delay
   (exact FFT shift), over 3.0-5.6 ms in 0.01 ms steps; the delay with the least residual. The
   first and last 5 s (rest) are left out. Also per half of the record.
2. **Phase delay per band**: the 3x3 transfer matrix `H = S_xu S_uu^-1` from Welch cross-spectra
   (1024-sample Hann segments), and per diagonal element the delay `-arg H_ii / (2 pi f)`
   averaged over the bins of a band weighted by the input's power. A pure delay gives the same
   value in every band; a lag (a filter beyond a delay) gives a delay that falls with frequency.

Printed per run: the regression delays x / y / z (whole record, then each half) and the phase
delays per band, in ms.
"""
import gzip
import sys

import numpy as np
from scipy.signal import butter, csd, sosfiltfilt

BANDS_HZ = [(0.2, 0.7), (0.7, 1.5), (1.5, 3.0), (3.0, 6.0), (6.0, 10.0)]
TRIAL_DELAYS_S = np.arange(3.0, 5.6, 0.01) * 1e-3
REST_S = 5.0


def rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = {
        "x": [[o, z, z], [z, c, -s], [z, s, c]],
        "y": [[c, z, s], [z, o, z], [-s, z, c]],
        "z": [[c, -s, z], [s, c, z], [z, z, o]],
    }[axis]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def body_rates(t, roll, yaw, pitch):
    r = rot("y", yaw) @ rot("z", pitch) @ rot("x", roll)
    w = np.swapaxes(r, 1, 2) @ np.gradient(r, t, axis=0)
    return np.stack([w[:, 2, 1], w[:, 0, 2], w[:, 1, 0]], -1)


def shifted(x, tau, fs):
    n = len(x)
    spectrum = np.fft.rfft(x, 2 * n)
    f = np.fft.rfftfreq(2 * n, 1 / fs)
    return np.fft.irfft(spectrum * np.exp(-2j * np.pi * f * tau), 2 * n)[:n]


def band_passed_and_shifted(w, g, fs):
    """Rates and gyro band-passed once, and the rates shifted by every trial delay once (the
    whole record and its halves are slices of these)."""
    sos = butter(4, [0.2, 8.0], "bandpass", fs=fs, output="sos")
    wf, gf = sosfiltfilt(sos, w, axis=0), sosfiltfilt(sos, g, axis=0)
    shifts = [np.stack([shifted(wf[:, j], tau, fs) for j in range(3)], -1) for tau in TRIAL_DELAYS_S]
    return shifts, gf


def regression_delays(shifts, gf, keep):
    out = []
    for i in range(3):
        residuals = []
        for ws in shifts:
            k, *_ = np.linalg.lstsq(ws[keep], gf[keep, i], rcond=None)
            residuals.append(np.sum((gf[keep, i] - ws[keep] @ k) ** 2))
        out.append(TRIAL_DELAYS_S[int(np.argmin(residuals))] * 1e3)
    return out


def band_delays(w, g, fs):
    n = 1024
    s_uu = np.zeros((n // 2 + 1, 3, 3), complex)
    s_xu = np.zeros_like(s_uu)
    for i in range(3):
        for j in range(3):
            # scipy's csd(a, b) is E[conj(A) B]: S_uu[i, j] = E[U_i conj(U_j)] = csd(u_j, u_i).
            f, s_uu[:, i, j] = csd(w[:, j], w[:, i], fs=fs, nperseg=n)
            f, s_xu[:, i, j] = csd(w[:, j], g[:, i], fs=fs, nperseg=n)
    h = np.array([s_xu[k] @ np.linalg.inv(s_uu[k]) for k in range(len(f))])
    out = []
    for lo, hi in BANDS_HZ:
        m = (f >= lo) & (f < hi)
        row = []
        for i in range(3):
            weight = np.abs(s_uu[m, i, i])
            delay = -np.angle(h[m, i, i]) / (2 * np.pi * f[m])
            row.append(np.sum(weight * delay) / np.sum(weight) * 1e3)
        out.append(row)
    return out


def main(paths):
    for path in paths:
        d = np.loadtxt(gzip.open(path, "rt"), delimiter=",", skiprows=1)
        t = d[:, 0]
        fs = 1.0 / np.median(np.diff(t))
        w = body_rates(t, d[:, 1], d[:, 2], d[:, 3])
        g = d[:, 4:7]
        n, rest = len(t), int(REST_S * fs)
        whole = slice(rest, n - rest)
        halves = [slice(rest, n // 2), slice(n // 2, n - rest)]
        name = path.split("/")[-1].split(".")[0]
        fmt = lambda v: " / ".join(f"{x:.2f}" for x in v)  # noqa: E731
        shifts, gf = band_passed_and_shifted(w, g, fs)
        print(f"{name}: regression delay x / y / z {fmt(regression_delays(shifts, gf, whole))} ms; "
              f"halves {fmt(regression_delays(shifts, gf, halves[0]))} and "
              f"{fmt(regression_delays(shifts, gf, halves[1]))} ms")
        for (lo, hi), row in zip(BANDS_HZ, band_delays(w, g, fs)):
            print(f"  phase delay {lo:g}-{hi:g} Hz: x / y / z {fmt(row)} ms")


if __name__ == "__main__":
    main(sys.argv[1:])
