"""The samples an online estimate keeps of a stream: within bounds, however long it runs.

**Memory.**  The estimator's sums are per surface node, but a node the refinement adds needs
every sample fitted, and so do the relaxation flag and the model checks: the samples are kept,
within bounds, so that a long stream (an hour at 800 Hz is 2.9 million samples) does not grow
without end.  Before the contact :class:`KeptSamples` keeps the last
:data:`PRE_CONTACT_SAMPLES` (with the chunk being added): the baseline, the contact onset and
the fit read those, the same as reading a recording that starts there.  From the contact on
it keeps :data:`MAX_CONTACT_SAMPLES`; the samples after them still update the sums of the
surface nodes there are (exactly), but the grid is no longer refined and the relaxation flag
sees the samples kept, which the state flags (:meth:`KeptSamples.unkept_flag`).  The model
checks run on at most :data:`~palpbayes.online.adequacy.CHECK_SAMPLES` of the samples kept.
A press at the paper's 800 Hz (~4,000 samples) or an AFM approach (~2,000-12,000) is within
every bound, its estimates, stops and checks those of an estimator that keeps everything.
The estimator that keeps them is :class:`palpbayes.online.estimator.OnlineEstimator`.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

__all__ = ["PRE_CONTACT_SAMPLES", "MAX_CONTACT_SAMPLES", "KeptSamples", "checked_samples"]

#: Samples kept from before the contact, the last ones (25 s at 800 Hz, 1 s at 20 kHz): the
#: baseline, the contact onset and the fit read these (module docstring, "Memory").
PRE_CONTACT_SAMPLES = 20_000
#: Samples kept from the contact on (10 min at 800 Hz): later ones update the sums of the
#: surface nodes there are, but the grid is no longer refined (flagged).
MAX_CONTACT_SAMPLES = 500_000


def checked_samples(t, z, f) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A chunk of samples (times [s], tip heights [m], forces [N]) as 1-D float arrays of one
    length, all finite; else :class:`~palpbayes.errors.InputError`."""
    t, z, f = (np.atleast_1d(np.asarray(a, dtype=float)) for a in (t, z, f))
    if not (t.shape == z.shape == f.shape and t.ndim == 1):
        raise InputError(f"update: t, z and F must be 1-D of one length, got {t.shape}, "
                         f"{z.shape}, {f.shape}")
    if not (np.isfinite(t).all() and np.isfinite(z).all() and np.isfinite(f).all()):
        raise InputError("update: t, z and F must be finite (drop NaN samples first)")
    return t, z, f


class KeptSamples:
    """The samples kept (module docstring, "Memory"): the first :attr:`n` of :attr:`t`,
    :attr:`z` and :attr:`f` (arrays with room to grow); :attr:`seen` the samples added,
    :attr:`dropped` those dropped before the contact."""

    def __init__(self) -> None:
        self.t = np.empty(0)
        self.z = np.empty(0)
        self.f = np.empty(0)
        self.n = 0
        self.seen = self.dropped = 0

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The samples kept: times [s], tip heights [m], forces [N] (views)."""
        return self.t[:self.n], self.z[:self.n], self.f[:self.n]

    @property
    def unkept(self) -> int:
        """Samples after the contact beyond :data:`MAX_CONTACT_SAMPLES`, not kept."""
        return self.seen - self.dropped - self.n

    def add(self, t: np.ndarray, z: np.ndarray, f: np.ndarray, contact: int | None) -> None:
        """Count the new samples and keep them within the bounds of the module docstring
        ("Memory"): before the contact (``contact`` None, else the index of its first sample
        among those kept), all of them and the last :data:`PRE_CONTACT_SAMPLES` of the older
        ones; from the contact on, up to :data:`MAX_CONTACT_SAMPLES` samples."""
        self.seen += t.size
        if contact is None and self.n > PRE_CONTACT_SAMPLES:
            drop = self.n - PRE_CONTACT_SAMPLES
            for name in ("t", "z", "f"):
                a = getattr(self, name)
                a[:PRE_CONTACT_SAMPLES] = a[drop:self.n]
            self.n = PRE_CONTACT_SAMPLES
            self.dropped += drop
        elif contact is not None:
            room = max(contact + MAX_CONTACT_SAMPLES - self.n, 0)
            t, z, f = t[:room], z[:room], f[:room]
        self._append(t, z, f)

    def _append(self, t: np.ndarray, z: np.ndarray, f: np.ndarray) -> None:
        need = self.n + t.size
        if need > self.t.size:
            cap = max(need, 2 * self.t.size, 1024)
            for name in ("t", "z", "f"):
                old = getattr(self, name)
                new = np.empty(cap)
                new[: self.n] = old[: self.n]
                setattr(self, name, new)
        self.t[self.n:need], self.z[self.n:need], self.f[self.n:need] = t, z, f
        self.n = need

    def unkept_flag(self) -> str:
        """The state's flag of samples not kept ('' when every sample is kept)."""
        if not self.unkept:
            return ""
        return (f"more than {MAX_CONTACT_SAMPLES:,} samples in contact: the later "
                f"{self.unkept:,} update the estimate but are not kept, so the surface grid is "
                "no longer refined and the relaxation flag and the model checks see the first "
                "ones (send the approach and the indentation only)")
