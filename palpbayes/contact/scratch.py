"""Scratch arrays reused from one hereditary-integral call to the next, per thread.

The power law's recursions work on (terms × samples) arrays: ~0.7 MB each for 4,000 samples
and 23 terms, a dozen of them per call.  A fresh array that large is memory the operating system
maps page by page on first touch (and glibc gives back when it is freed), and for these arrays
those page faults cost about as much as the arithmetic: ``benchmarks/bench_viscoelastic.py``
measured 8.5 ms a call with fresh arrays and 5.9 ms with glibc's trimming switched off (then
34 terms).
:func:`scratch` hands out the same memory again on the next call instead.  A helper module:
it registers no law.

Rules for callers: a scratch array is garbage on return (never zeroed unless asked), lives until
the next request of the same ``name`` in the same thread, and must never be returned or kept
by the caller; two arrays alive at once need two names.  At most :data:`SCRATCH_BYTES` are kept
per thread; a request beyond that gets a fresh array.
"""

from __future__ import annotations

import math
import threading

import numpy as np

__all__ = ["scratch", "SCRATCH_BYTES"]

#: Most bytes of scratch memory kept per thread [B].
SCRATCH_BYTES = 64 * 2**20


class _Buffers(threading.local):
    def __init__(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}


_BUFFERS = _Buffers()


def scratch(name: str, shape: tuple[int, ...], zero: bool = False) -> np.ndarray:
    """A C-contiguous float64 array of ``shape`` on this thread's buffer ``name`` (its
    contents are left over from the last use unless ``zero``)."""
    size = math.prod(shape)
    arrays = _BUFFERS.arrays
    buf = arrays.get(name)
    if buf is None or buf.size < size:
        kept = sum(a.nbytes for key, a in arrays.items() if key != name)
        if kept + 8 * size > SCRATCH_BYTES:
            return np.zeros(shape) if zero else np.empty(shape)
        buf = arrays[name] = np.empty(size)
    out = buf[:size].reshape(shape)
    if zero:
        out.fill(0.0)
    return out
