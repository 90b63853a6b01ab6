"""Time the identifier's Welch matrices computed pair by pair with scipy.signal.csd (run by hand,
not by CI), for the README's Speed section.

    python3 tests/bench_compare/scipy_csd.py RUN.csv [SEGMENT]

The identifier computes, per block, the 6x6 one-sided Welch matrix of [u; x] (upper triangle:
21 pairs), for the gyro and the accelerometer block: 42 pairs of 12 channels. The inputs u come
from the observer, which scipy does not have; the timing does not depend on the values, so the
script uses the run's angles for u (a separate copy per block) and the block's outputs for x.
Settings as `imu-attest bench`: Hann window, segment SEGMENT (default 4096), overlap 50 %,
nfft = 4 x segment (the identifier's zero padding), mean detrend, density scaling.
"""

import sys
import time

import numpy as np
import polars as pl
import scipy
from scipy.signal import csd


def main() -> None:
    path = sys.argv[1]
    seg = int(sys.argv[2]) if len(sys.argv) > 2 else 4096
    frame = pl.read_csv(path)
    t = frame["t"].to_numpy()
    fs = (len(t) - 1) / (t[-1] - t[0])
    angles = ["roll", "yaw", "pitch"]
    blocks = {
        "gyro": [frame[c].to_numpy().copy() for c in angles + ["gx", "gy", "gz"]],
        "accel": [frame[c].to_numpy().copy() for c in angles + ["ax", "ay", "az"]],
    }
    kw = dict(fs=fs, window="hann", nperseg=seg, noverlap=seg // 2, nfft=4 * seg,
              detrend="constant", scaling="density")
    start = time.perf_counter()
    pairs = 0
    for channels in blocks.values():
        n = len(channels)
        s = np.zeros((4 * seg // 2 + 1, n, n), dtype=complex)
        for i in range(n):
            for j in range(i, n):
                # Ours S_ij = scipy csd(x_j, x_i) (see src/spectral/mod.rs).
                _, s[:, i, j] = csd(channels[j], channels[i], **kw)
                pairs += 1
    wall = time.perf_counter() - start
    print(f"scipy.signal.csd pair by pair: {pairs} pairs of {len(t)} samples, segment {seg}, "
          f"nfft {4 * seg}: {wall:.2f} s (scipy {scipy.__version__}, numpy {np.__version__})")


if __name__ == "__main__":
    main()
