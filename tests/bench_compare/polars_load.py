"""Time polars.read_csv on a run CSV, for the README's Speed section (run by hand, not by CI).

    python3 tests/bench_compare/polars_load.py RUN.csv [REPEATS]

Prints the wall time of each read and the process's peak resident memory (which includes the
Python interpreter and the polars library, about 60-100 MB before any read).
"""

import resource
import sys
import time

import polars as pl


def main() -> None:
    path = sys.argv[1]
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    for _ in range(repeats):
        start = time.perf_counter()
        frame = pl.read_csv(path)
        wall = time.perf_counter() - start
        decoded = frame.estimated_size() / 1e6
        print(f"polars.read_csv: {frame.height} rows x {frame.width} columns in {wall:.3f} s "
              f"(decoded {decoded:.0f} MB)")
        del frame
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS {peak:.0f} MB (before reading: {before:.0f} MB); polars {pl.__version__}, "
          f"{pl.thread_pool_size()} threads")


if __name__ == "__main__":
    main()
