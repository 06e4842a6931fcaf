# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True
# cython: initializedcheck=False
"""Compiled loops over (trial surface height × sample): the hot loop of the exact engine, the
least squares and the depth check (docs/reference.md, "Speed").

Built by pip at install (Cython, gcc); imported only through :mod:`palpbayes.shapekernel`,
which states the contract.  Every loop evaluates the contact law's shape function
s(d) = F/E* [m²] at the depth d = z_s − z [m] of every sample below each trial surface z_s,
either exactly as a power law g·d^m or by linear interpolation in a table on the nodes
d_i = d_top·(i/N)² (:class:`palpbayes.shapekernel.CompiledShape`), and sums what the caller
needs in the same pass, so that no (nodes × samples) array is ever formed.
"""

from libc.math cimport sqrt, pow

import numpy as np


cdef struct Law:
    int kind          # 0: g·d^m; 1: table
    double g
    double m
    const double* tab
    int n             # table intervals (n + 1 nodes)
    double inv_top    # 1 / d_top


cdef inline double _shape(double d, Law* law) noexcept nogil:
    cdef double x, w
    cdef const double* f
    cdef int i
    if d <= 0.0:
        return 0.0
    if law.kind == 0:
        if law.m == 1.5:
            return law.g * d * sqrt(d)
        if law.m == 1.0:
            return law.g * d
        if law.m == 2.0:
            return law.g * d * d
        return law.g * pow(d, law.m)
    # cubic (four-point Lagrange) in x = N·sqrt(d/d_top), in which the nodes are uniform
    # and the laws are smooth down to d = 0 (a power law d^m is x^(2m)): error O(N^-4)
    x = sqrt(d * law.inv_top) * law.n
    i = <int> x
    if i < 1:
        i = 1
    elif i > law.n - 2:
        i = law.n - 2
    w = x - i
    f = law.tab + i
    return (-w * (w - 1.0) * (w - 2.0) * f[-1] + 3.0 * (w + 1.0) * (w - 1.0) * (w - 2.0) * f[0]
            - 3.0 * (w + 1.0) * w * (w - 2.0) * f[1] + (w + 1.0) * w * (w - 1.0) * f[2]
            ) * (1.0 / 6.0)


cdef Law _law(int kind, double g, double m, const double[::1] table, double d_top):
    cdef Law law
    law.kind = kind
    law.g = g
    law.m = m
    law.tab = &table[0]
    law.n = table.shape[0] - 1
    law.inv_top = 1.0 / d_top
    return law


def shape_values(const double[::1] depth, int kind, double g, double m,
                 const double[::1] table, double d_top):
    """s(d) [m²] at every depth [m] (0 at non-positive depth)."""
    cdef Law law = _law(kind, g, m, table, d_top)
    cdef Py_ssize_t t, k = depth.shape[0]
    out = np.empty(k)
    cdef double[::1] o = out
    with nogil:
        for t in range(k):
            o[t] = _shape(depth[t], &law)
    return out




def cross_sums(const double[::1] nodes, const double[::1] z, const double[:, ::1] C,
               int kind, double g, double m, const double[::1] table, double d_top,
               bint lag):
    """Per trial surface z_s = ``nodes[g]`` [m], with s_t = s(z_s − z_t) over the samples in
    time order and the fixed columns ``C`` (k, q <= 4):

    ss = Σ s_t², sc_j = Σ s_t·C_tj, n_contact = #{s_t > 0}, s_first = s_0, s_last = s_(k−1),
    and with ``lag``: l00 = Σ_(t≥1) s_t·s_(t−1), l0c_j = Σ_(t≥1) s_t·C_(t−1)j,
    lc0_j = Σ_(t≥1) s_(t−1)·C_tj (the lag-one cross-products of the AR(1) likelihood).
    """
    cdef Law law = _law(kind, g, m, table, d_top)
    cdef Py_ssize_t G = nodes.shape[0], k = z.shape[0], q = C.shape[1]
    cdef Py_ssize_t i, t, j
    if q > 4:
        raise ValueError(f"cross_sums takes at most 4 fixed columns, got {q}")
    ss_a = np.zeros(G)
    sc_a = np.zeros((G, q))
    l00_a = np.zeros(G)
    l0c_a = np.zeros((G, q))
    lc0_a = np.zeros((G, q))
    first_a = np.zeros(G)
    last_a = np.zeros(G)
    nc_a = np.zeros(G, dtype=np.int64)
    cdef double[::1] ss = ss_a, l00 = l00_a, s_first = first_a, s_last = last_a
    cdef double[:, ::1] sc = sc_a, l0c = l0c_a, lc0 = lc0_a
    cdef long long[::1] nc = nc_a
    cdef double zs, s, prev, acc_ss, acc_l
    cdef double a_sc[4]
    cdef double a_l0c[4]
    cdef double a_lc0[4]
    cdef long long count
    if k == 0:
        return ss_a, sc_a, l00_a, l0c_a, lc0_a, first_a, last_a, nc_a
    with nogil:
        for i in range(G):
            zs = nodes[i]
            prev = 0.0
            acc_ss = 0.0
            acc_l = 0.0
            count = 0
            for j in range(4):
                a_sc[j] = 0.0
                a_l0c[j] = 0.0
                a_lc0[j] = 0.0
            s_first[i] = _shape(zs - z[0], &law)
            for t in range(k):
                s = _shape(zs - z[t], &law)
                if s != 0.0:
                    acc_ss += s * s
                    count += 1
                    for j in range(q):
                        a_sc[j] += s * C[t, j]
                    if lag and t > 0:
                        acc_l += s * prev
                        for j in range(q):
                            a_l0c[j] += s * C[t - 1, j]
                if lag and prev != 0.0:  # prev = 0 at t = 0
                    for j in range(q):
                        a_lc0[j] += prev * C[t, j]
                prev = s
            s_last[i] = prev
            ss[i] = acc_ss
            l00[i] = acc_l
            nc[i] = count
            for j in range(q):
                sc[i, j] = a_sc[j]
                l0c[i, j] = a_l0c[j]
                lc0[i, j] = a_lc0[j]
    return ss_a, sc_a, l00_a, l0c_a, lc0_a, first_a, last_a, nc_a


def scale_rss(const double[::1] nodes, const double[::1] z, const double[::1] f,
              int kind, double g, double m, const double[::1] table, double d_top):
    """The paper's profile least squares at each trial surface ``nodes[g]`` [m]: E*(z_s) =
    Σ s·f / Σ s² [Pa] and L(z_s) = Σ (f − E*·s)² [N²], the second summed from the residuals
    themselves (a second pass: no cancellation near a perfect fit); L = Σ f², E* = 0 where no
    sample is in contact."""
    cdef Law law = _law(kind, g, m, table, d_top)
    cdef Py_ssize_t G = nodes.shape[0], k = z.shape[0]
    cdef Py_ssize_t i, t
    rss_a = np.empty(G)
    est_a = np.empty(G)
    cdef double[::1] rss = rss_a, est = est_a
    cdef double zs, s, ss, sf, ff, e, r, acc
    ff = 0.0
    with nogil:
        for t in range(k):
            ff += f[t] * f[t]
        for i in range(G):
            zs = nodes[i]
            ss = 0.0
            sf = 0.0
            for t in range(k):
                s = _shape(zs - z[t], &law)
                ss += s * s
                sf += s * f[t]
            if ss > 0.0:
                e = sf / ss
                acc = 0.0
                for t in range(k):
                    r = f[t] - e * _shape(zs - z[t], &law)
                    acc += r * r
                rss[i] = acc
                est[i] = e
            else:
                rss[i] = ff
                est[i] = 0.0
    return rss_a, est_a
