"""Timing helper shared by the benchmark scripts."""

import statistics
import time


def median_time(func, repeat=7, warmup=1):
    """Median wall time of `func()` in seconds over `repeat` runs."""
    for _ in range(warmup):
        func()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def print_table(headers, rows):
    """Print rows as an aligned plain-text table."""
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(len(headers))]
    line = '  '.join('-' * w for w in widths)
    print('  '.join(h.ljust(w) for h, w in zip(cells[0], widths)))
    print(line)
    for row in cells[1:]:
        print('  '.join(c.rjust(w) for c, w in zip(row, widths)))
