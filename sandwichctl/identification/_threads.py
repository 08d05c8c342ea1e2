"""Independent refinements side by side on threads (private).

The simulation kernels of `_predictor` (numba, ``nogil``), scipy's filters
and BLAS release the GIL, so refinements of independent starts on long
records run on several cores at once. `ordered_map` returns the results
in the order of the starts, so what a search chooses does not depend on
which thread finished first: the same models as one after the other.
"""

from concurrent.futures import ThreadPoolExecutor

__all__ = []


def ordered_map(fn, items, workers=1):
    """[fn(item) for item in items], on up to `workers` threads."""
    items = list(items)
    if workers <= 1 or len(items) <= 1:
        return [fn(item) for item in items]
    with ThreadPoolExecutor(max_workers=min(workers, len(items))) as pool:
        return list(pool.map(fn, items))
