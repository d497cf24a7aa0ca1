"""The twin's contact quadrature (:meth:`flexdigit.twin.contact.TissueContact.points`), compiled.

numba, because the quadrature is ~60 numpy operations on arrays of a few dozen numbers: at the batch sizes of a
Newton solve (1-20 shapes) numpy spends ~200 us a call in dispatch and temporaries for ~2 us of arithmetic, and a
palpation study calls it ~9,000 times. The same elementwise IEEE operations in the same order as the numpy
reference (``TissueContact._points_numpy``; the cumulative sums run in order, as ``np.cumsum`` does; no fast-math,
so no fused multiply-adds), so the same bits: ``tests/twin/test_contact.py`` checks them equal.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["contact_points"]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def contact_points(psi, link_start, link_len, chain_link_len, sign, gap, lo, hi, k, gauss_t, gauss_w):
    """``(s, w, delta, k)``, each (B, L * M * G), of the quadrature points on the links that reach into the body
    anywhere in the batch (L of them, in order), against its M pieces, G Gauss points each."""
    b, n = psi.shape
    x = np.empty((b, n + 2))
    depth = np.empty((b, n + 2))
    for i in range(b):
        x[i, 0] = 0.0
        x[i, 1] = link_len[0] + 0.0
        depth[i, 0] = sign * 0.0 - gap
        depth[i, 1] = sign * 0.0 - gap
        cx = 0.0
        cy = 0.0
        for j in range(n):
            cx += chain_link_len[j] * np.cos(psi[i, j])
            cy += chain_link_len[j] * np.sin(psi[i, j])
            x[i, j + 2] = link_len[0] + cx
            depth[i, j + 2] = sign * cy - gap
    first, last = lo[0], hi[hi.size - 1]
    chosen = np.zeros(n + 1, dtype=np.bool_)
    for j in range(n + 1):
        for i in range(b):
            if (
                max(depth[i, j], depth[i, j + 1]) > 0
                and max(x[i, j], x[i, j + 1]) >= first
                and min(x[i, j], x[i, j + 1]) <= last
            ):
                chosen[j] = True
                break
    links = np.flatnonzero(chosen)
    m, g = lo.size, gauss_t.size
    p = links.size * m * g
    s_out, w_out, d_out, k_out = np.empty((b, p)), np.empty((b, p)), np.empty((b, p)), np.empty((b, p))
    for i in range(b):
        col = 0
        for j in links:
            x0, x1, d0, d1 = x[i, j], x[i, j + 1], depth[i, j], depth[i, j + 1]
            dx = x1 - x0
            root = d0 / (d0 - d1) if d0 != d1 else 0.0
            for q in range(m):
                if dx > 0:
                    ta = (lo[q] - x0) / dx
                    tb = (hi[q] - x0) / dx
                else:
                    ta = 0.0 if x0 >= lo[q] else 1.0
                    tb = 1.0 if x0 <= hi[q] else 0.0
                ta = min(max(ta, 0.0), 1.0)
                tb = min(max(tb, 0.0), 1.0)
                if d0 <= 0 and d1 > 0:
                    ta = max(ta, root)
                if d0 > 0 and d1 <= 0:
                    tb = min(tb, root)
                span = 0.0 if (tb <= ta or (d0 <= 0 and d1 <= 0)) else tb - ta
                for r in range(g):
                    t = ta + span * gauss_t[r]
                    s_out[i, col] = link_start[j] + t * link_len[j]
                    w_out[i, col] = span * gauss_w[r] * link_len[j]
                    d_out[i, col] = max(d0 + t * (d1 - d0), 0.0)
                    k_out[i, col] = k[q]
                    col += 1
    return s_out, w_out, d_out, k_out
