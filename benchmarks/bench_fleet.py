"""Speed-up of fleet identification (issue 16, item 4).

Eight data sets of N = 3,000 samples (the paper plant with growing
backlash widths, SNR 100), identified

- serially: ``[sw.identify(...) for ...]`` in this process;
- by ``sw.identify_many`` in 2 local worker processes, cold (the pool is
  started by the call: each worker imports sandwichctl) and warm (the
  pool kept from the previous call);
- by ``sw.identify_many`` on a dask ``LocalCluster`` of 2 single-threaded
  worker processes (if dask.distributed is installed), cold (the first
  call on a new cluster: the workers import sandwichctl; one run) and
  warm; with the workers' ``MALLOC_TRIM_THRESHOLD_`` unset, and with
  dask's default 65536, which makes every identification about 1.4x
  slower.

Every figure is the median of repeated runs in this one process; the
speed-up is the serial time over the parallel one. The machine has the
cores `os.cpu_count()` says, shared with other work, so 2x is the
ceiling.

Run: python benchmarks/bench_fleet.py
"""

import os
import statistics
import sys
import time
import warnings

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.identification import fleet               # noqa: E402
from _timing import print_table                            # noqa: E402

N_SETS, N, WORKERS = 8, 3_000, 2


def datasets():
    plant = sw.examples.paper_plant()
    out = []
    for k in range(N_SETS):
        co = plant.coefficients
        scale = 1 + 0.25 * k
        co['D1'], co['D2'] = scale * co['D1'], scale * co['D2']
        axis = sw.SandwichSystem.from_coefficients(**co)
        u = sw.examples.paper_input(N, seed=k)
        y = sw.examples.add_noise(axis.simulate(u).outputs, 100, seed=100 + k)
        out.append((u, y))
    return out, plant.orders


def timed(func, repeat, reset=None, warmup=0):
    """Medians over `repeat` runs of `func()` (a list of results): the wall
    time and the identifications' own time (the sum of ``res.elapsed``);
    `reset()`, untimed, before each run (a cold start)."""
    for _ in range(warmup):
        func()
    walls, works = [], []
    for _ in range(repeat):
        if reset is not None:
            reset()
        start = time.perf_counter()
        results = func()
        walls.append(time.perf_counter() - start)
        works.append(sum(r.elapsed for r in results))
    return statistics.median(walls), statistics.median(works)


def main():
    threads = os.environ.get('OPENBLAS_NUM_THREADS', 'unset')
    load = os.getloadavg()[0]
    warnings.simplefilter('ignore')          # speed only
    sets, orders = datasets()
    serial, serial_work = timed(lambda: [sw.identify(u, y, **orders)
                                         for u, y in sets], 5, warmup=1)
    rows = [['serial sw.identify (this process)', 1, f'{serial:.2f} s',
             f'{serial_work:.2f} s', '1.00']]

    def row(how, wall, work):
        rows.append([how, WORKERS, f'{wall:.2f} s', f'{work:.2f} s',
                     f'{serial / wall:.2f}'])

    def local():
        return sw.identify_many(sets, **orders, processes=WORKERS)

    row('identify_many, processes (cold: pool started)',
        *timed(local, 3, reset=lambda: fleet._POOL.shutdown(wait=True)))
    row('identify_many, processes (warm: pool kept)', *timed(local, 5))
    fleet._POOL.shutdown(wait=True)
    try:
        import dask
        import distributed
    except ImportError:
        rows.append(['identify_many, dask LocalCluster', WORKERS,
                     'not installed', '', ''])
    else:
        # dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536,
        # which fixes glibc's mmap threshold at 128 KiB: every array above
        # it is mapped and unmapped anew. First the cluster without it
        # (the recommended setting), then dask's default. (The nanny also
        # sets the variable in this process, hence the pop.)
        for label, env in (('MALLOC_TRIM_THRESHOLD_ unset', None),
                           ("dask's default environment", 65536)):
            os.environ.pop('MALLOC_TRIM_THRESHOLD_', None)
            key = 'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_'
            with dask.config.set({key: env}), distributed.LocalCluster(
                    n_workers=WORKERS, threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=40) as cluster, \
                    distributed.Client(cluster) as client:
                def on_dask():
                    return sw.identify_many(sets, **orders, client=client)
                row(f'identify_many, dask, {label} (cold: new workers)',
                    *timed(on_dask, 1))
                row(f'identify_many, dask, {label} (warm)',
                    *timed(on_dask, 5))
    print(f"Fleet identification: {N_SETS} data sets of N = {N:,} (paper "
          f"plant, SNR 100), medians of repeats; {os.cpu_count()} cores, "
          f"load average {load:.2f} at the start; OPENBLAS_NUM_THREADS="
          f"{threads} here, 1 in the workers\n")
    print_table(['how', 'workers', 'median time', 'identify time (sum)',
                 'speed-up'], rows)
    print("\nidentify time (sum): the identifications' own time, summed; "
          "above the serial one when\nthe workers did not each have a free "
          "core. Starting the dask cluster (about 1-2 s) is not timed.")


if __name__ == '__main__':
    main()
