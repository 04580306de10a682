"""Exact intersection ratios of many pairs of oriented boxes at once (numpy, no loop over pairs).

box_overlap.intersection_ratio measures P = A n B pair by pair as the convex hull of the clipped edge
points (PSORR paper, section 2.1.4). This measures the same polytope for N pairs at once, hull-free:

* P is convex and bounded by pieces of the 12 face planes. The piece on a face F of box X is F's
  rectangle n Y: the rectangle clipped by Y's three slabs (Sutherland-Hodgman, in 2-D coordinates
  on F). Its vertices are exactly the clipped edge points box_overlap finds on F (F's corners inside
  Y, the ends of F's edges clipped by Y, Y's edges crossing F): these polygons are the facets of
  box_overlap's hull, computed, not sampled.
* vol(P) = 1/3 sum_F area(F) dist(c, plane of F) for any point c of P (the cones from c over the
  facets tile P). c is an area-weighted mean of facet points, so it is in P, every term is >= 0 and
  the sum is well conditioned however thin P or the boxes are.

Conditioning. Each face is clipped in its own box's frame, in metres, where coordinates are bounded by
the box sizes: a plane box 1 mm thick only gives narrow rectangles, which clipping does not mind. The
one delicate case is a face g of B (nearly) parallel to a face f of A on the same side: their crease
is ill-conditioned (rounding of 1e-17 m moves it by 1e-17 / tilt, 1 um at 1e-11 rad), and pieces of f
and g clipped separately would disagree on it, the strip between counting twice or not at all with a
full cone height. So a B face within ~25 degrees of an A axis is projected along that axis onto A's
face rectangle and cut there with the very same numbers that cut f's piece, taking the other side:
the two pieces tile the rectangle exactly, and a misplaced crease only moves volume between two
nearly equal planes. Flush and equal boxes (coplanar faces) are the limit of this, one shared cut.

Results thus equal box_overlap's up to rounding; the differences seen are its own: it counts points
within 1e-11 m of a box as inside, which moves its hull by up to ~1e-11 m (~1e-8 relative for 1 mm
boxes). As there, pairs nested within 1e-11 m give the smaller box's volume, touching boxes 0.
"""

from __future__ import annotations

import numpy as np

from psorr.errors import InvalidInputError

# The corner signs, and the slack within which one box counts as inside the other: nested pairs
# take the same shortcut as in the one-pair-at-a-time box_overlap, with the same answer.
from psorr.geometry.box_overlap import _SIGNS
from psorr.geometry.box_overlap import _TOL as _NESTED_TOL

_FLAT = 1e-12  # m: a P thinner than this on average (touching boxes, up to rounding) has volume 0
_BLOCK = 512  # pairs clipped at once
_PARALLEL = 0.9  # |cos| between a B axis and an A axis from which B's faces are projected onto A's

# The 6 faces of a box, index 2 k + (s > 0): normal axis k, side s; u, v are the in-plane axes.
_K = np.repeat(np.arange(3), 2)
_S = np.tile([-1.0, 1.0], 3)
_U, _V = (_K + 1) % 3, (_K + 2) % 3
_EYE = np.eye(3)
_RECT = np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])  # corners (u, v) in cyclic order


def _checked(arrays: dict[str, object]) -> list[np.ndarray]:
    out = []
    for name, value in arrays.items():
        try:
            out.append(np.asarray(value, dtype=np.float64))
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"{name} must be a float array: {exc}") from None
    n = len(out[0]) if out[0].ndim else -1
    if any(a.shape != (n, *tail) for a, tail in zip(out, [(3,), (3, 3), (3,)] * 2)):
        got = ", ".join(f"{k} {a.shape}" for k, a in zip(arrays, out))
        raise InvalidInputError("expected centers (N, 3), rotations (N, 3, 3) and extents (N, 3) with the same N "
                                f"for a and b; got {got}")
    for name, a in zip(arrays, out):
        if not np.isfinite(a).all():
            raise InvalidInputError(f"{name} must be finite; NaN or inf in row {np.argwhere(~np.isfinite(a))[0, 0]}")
        if name.startswith("extents") and (a < 0).any():
            raise InvalidInputError(f"{name} must be full side lengths >= 0 in metres; negative in row "
                                    f"{np.argwhere(a < 0)[0, 0]}")
    return out


def intersection_ratios(centers_a, rotations_a, extents_a, centers_b, rotations_b, extents_b,
                        min_thickness: float = 0.005) -> np.ndarray:
    """(N,) float64 in [0, 1]: per row, box_overlap.intersection_ratio(box a, box b, min_thickness).

    Centres (N, 3) m, rotations (N, 3, 3) with the axes as columns (assumed orthonormal, not
    re-checked), extents (N, 3) full side lengths in m, for the N pairs (a[i], b[i]). Every extent
    is first raised to at least `min_thickness` m about the box's centre; the result is then
    vol(a n b) / vol(a), and 0 where box a has no volume. Raises InvalidInputError for NaN or inf
    (naming the argument), negative extents, mismatched shapes or a bad min_thickness.
    """
    names = ("centers_a", "rotations_a", "extents_a", "centers_b", "rotations_b", "extents_b")
    ca, Ra, ea, cb, Rb, eb = _checked(dict(zip(names, (centers_a, rotations_a, extents_a,
                                                       centers_b, rotations_b, extents_b))))
    min_thickness = float(min_thickness)
    if not (np.isfinite(min_thickness) and min_thickness >= 0.0):
        raise InvalidInputError(f"min_thickness must be a finite length >= 0 in metres, got {min_thickness}")
    ea, eb = np.maximum(ea, min_thickness), np.maximum(eb, min_thickness)
    vol_a, vol_b = ea[:, 0] * ea[:, 1] * ea[:, 2], eb[:, 0] * eb[:, 1] * eb[:, 2]
    ha, hb = ea / 2, eb / 2
    M = np.swapaxes(Ra, 1, 2) @ Rb  # B's axes (columns) in A's frame
    t = np.einsum("ni,nij->nj", cb - ca, Ra)  # B's centre in A's frame
    # Each box's corners in the other's frame: x = M y + t in A's frame, y = M^T (x - t) in B's.
    b_in_a = (np.abs(t[:, None] + (_SIGNS * hb[:, None]) @ np.swapaxes(M, 1, 2))
              <= ha[:, None] + _NESTED_TOL).all((1, 2))
    a_in_b = (np.abs((_SIGNS * ha[:, None] - t[:, None]) @ M) <= hb[:, None] + _NESTED_TOL).all((1, 2))
    # The face axes of the separating-axis test: cheap, and they drop most disjoint pairs before clipping.
    absM = np.abs(M)
    apart = ((np.abs(t) > ha + (absM @ hb[..., None])[..., 0]).any(1)
             | (np.abs((t[:, None] @ M)[:, 0]) > (ha[:, None] @ absM)[:, 0] + hb).any(1))
    volume = np.where(b_in_a, vol_b, np.where(a_in_b, vol_a, 0.0))
    todo = np.flatnonzero((vol_a > 0) & (vol_b > 0) & ~b_in_a & ~a_in_b & ~apart)
    for start in range(0, len(todo), _BLOCK):  # small temporaries stay in cache and reuse memory: 1.5x faster
        block = todo[start:start + _BLOCK]
        volume[block] = _polytope_volume(ha[block], hb[block], M[block], t[block])
    volume = np.minimum(volume, np.minimum(vol_a, vol_b))
    ratio = np.divide(volume, vol_a, out=np.zeros_like(volume), where=vol_a > 0)
    return np.clip(ratio, 0.0, 1.0)


def _polytope_volume(ha, hb, M, t) -> np.ndarray:
    """(n,) volume in m^3 of A n B; half extents ha, hb (n, 3) m, B's axes M (n, 3, 3) and centre t (n, 3) m
    in A's frame. 12 facet jobs per pair (A's 6 faces, then B's), each a rectangle of half sides (hu, hv)
    in plane coordinates (u, v), three clips lo < a u + b v + c <= hi, and the map x = o + u eu + v ev
    into A's frame (eu, ev need not be unit: |eu x ev| is the area scale of a projected face).
    """
    n = len(ha)
    r = np.arange(n)[:, None]
    along = (t[:, None] @ M)[:, 0]  # B's coordinates are y_j = M[:, j] . x - along_j
    ones = np.ones((n, 6))
    # A's faces: clipped by B's slabs, first by the one most parallel to the face normal.
    first = np.abs(M).argmax(2)[:, _K]
    offset_a = _S * ha[:, _K]
    a_clips = [(M[r, _U, j], M[r, _V, j], M[r, _K, j] * offset_a - along[r, j], -hb[r, j], hb[r, j])
               for j in (first, (first + 1) % 3, (first + 2) % 3)]
    a_map = (offset_a[..., None] * _EYE[_K], _EYE[_U] * ones[..., None], _EYE[_V] * ones[..., None])
    a_rect = (ha[:, _U], ha[:, _V])

    # B's faces in B's frame, clipped by A's slabs x_k = M[k] . y + t_k.
    offset_b = _S * hb[:, _K]
    b_clips = [(M[:, k, _U], M[:, k, _V], M[:, k, _K] * offset_b + t[:, k, None], -ha[:, k, None] * ones,
                ha[:, k, None] * ones) for k in range(3)]
    Mt = np.swapaxes(M, 1, 2)  # row j: B's axis j in A's frame
    b_map = (t[:, None] + offset_b[..., None] * Mt[:, _K], Mt[:, _U], Mt[:, _V])
    b_rect = (hb[:, _U], hb[:, _V])

    # B's faces near-parallel to A's axis k instead: on A's face (k, s) on their side, beyond f's first cut.
    k = np.abs(M).argmax(1)[:, _K]
    cos = M[r, k, _K]
    projected = np.abs(cos) > _PARALLEL
    face = 2 * k + (_S * cos > 0)  # that A face; the opposite one is face ^ 1
    a1, b1, c1, _, _ = (x[r, face] for x in a_clips[0])
    # g is inside A between f, which lies beyond it (the complement of f's cut, same bound), and the
    # opposite face, where B's coordinate is c_far - c1 lower: one slab in f's coordinate.
    depth = c1 - a_clips[0][2][r, face ^ 1]
    up, hbj = _S > 0, hb[:, _K]
    p_clips = [(a1, b1, c1, np.where(up, hbj, depth - hbj), np.where(up, hbj + depth, -hbj))]
    ku, kv = (k + 1) % 3, (k + 2) % 3
    # On g, x_k = q0 + qu u + qv v; B's other two slabs are taken there.
    q0, qu, qv = (offset_b + along[:, _K]) / cos, -M[r, ku, _K] / cos, -M[r, kv, _K] / cos
    for j in ((_K + 1) % 3, (_K + 2) % 3):
        p_clips.append((M[r, ku, j] + M[r, k, j] * qu, M[r, kv, j] + M[r, k, j] * qv,
                        M[r, k, j] * q0 - along[r, j], -hb[r, j], hb[r, j]))
    ek = _EYE[k]
    p_map = (q0[..., None] * ek, _EYE[ku] + qu[..., None] * ek, _EYE[kv] + qv[..., None] * ek)
    p_rect = (ha[r, ku], ha[r, kv])

    def pick(p, b):
        return np.where(projected.reshape(projected.shape + (1,) * (b.ndim - 2)), p, b)

    def jobs(a_part, p_part, b_part):  # A's 6 faces, then B's 6 (projected or in B's frame)
        return [np.concatenate([a, pick(p, b)], 1) for a, p, b in zip(a_part, p_part, b_part)]

    clips = [[x.ravel() for x in jobs(*trio)] for trio in zip(a_clips, p_clips, b_clips)]
    o, eu, ev = jobs(a_map, p_map, b_map)
    area_uv, mean = _clipped_area(*(x.ravel() for x in jobs(a_rect, p_rect, b_rect)), clips)
    area_uv, mean = area_uv.reshape(n, 12), mean.reshape(n, 12, 1)
    point = o + mean.real * eu + mean.imag * ev
    normal = np.cross(eu, ev)
    area = area_uv * np.linalg.norm(normal, axis=-1)
    total = area.sum(1)
    c = (area[..., None] * point).sum(1) / np.where(total > 0, total, 1.0)[:, None]
    volume = (area_uv * np.abs(((point - c[:, None]) * normal).sum(-1))).sum(1) / 3
    return np.where(volume > _FLAT * total, volume, 0.0)


def _clipped_area(hu, hv, clips):
    """Area in (u, v) units and vertex mean u + i v of the rectangles [-hu, hu] x [-hv, hv] (m,)
    after the clips lo < a u + b v + c <= hi, each of a, b, c, lo, hi (m,).

    A polygon is a row of complex points u + i v (one array to stack, scatter and gather instead of
    two), the first `count` holding the vertices in cyclic order and the rest repeats of the last
    (zero-length edges), so that all are clipped in lock step. Polygons left with under 3 vertices
    have no area and are dropped, which halves the later clips.
    """
    z = np.empty((len(hu), 4), complex)
    z.real, z.imag = _RECT[:, 0] * hu[:, None], _RECT[:, 1] * hv[:, None]
    count, live = np.full(len(hu), 4), np.arange(len(hu))
    for clip in clips:
        z, count, kept = _clip(z, count, *(x[live] for x in clip))
        live = live[kept]
    dz = z - z[:, :1]  # about a vertex, for precision
    area, mean = np.zeros(len(hu)), np.zeros(len(hu), complex)
    area[live] = 0.5 * np.abs((dz.conj() * np.roll(dz, -1, -1)).imag.sum(-1))
    mean[live] = z.mean(-1)  # inside the (convex) polygon: all that c needs
    return area, mean


def _clip(z, count, a, b, c, lo, hi):
    m, K = z.shape
    nxt = np.r_[1:K, 0]  # slot K-1 holds the last vertex (or a repeat of it): the closing edge
    d = a[:, None] * z.real + b[:, None] * z.imag + c[:, None]
    d_next, z_next = d[:, nxt], z[:, nxt]
    # Half-open (lo, hi]: a projected B face beyond A's face bound keeps exactly what A's face drops,
    # also where the two lie in one plane (flush boxes), so no piece counts twice.
    low_in, high_in = d > lo[:, None], d <= hi[:, None]
    keep = low_in & high_in & (np.arange(K) < count[:, None])  # repeats would only add repeats
    cross_low, cross_high = low_in != low_in[:, nxt], high_in != high_in[:, nxt]
    step = d_next - d  # nonzero wherever a crossing is flagged
    step = np.where(step == 0.0, 1.0, step)
    # (bound - d) / step, the same expression for both bounds: a projected B face cut at A's face
    # bound as `lo` gets bit for bit the points that A's face got from it as `hi`, and vice versa.
    t_low = np.clip((lo[:, None] - d) / step, 0.0, 1.0)
    t_high = np.clip((hi[:, None] - d) / step, 0.0, 1.0)
    rising = step > 0  # an edge crossing both bounds meets the one on its starting side first
    t1, t2 = np.where(rising, t_low, t_high), np.where(rising, t_high, t_low)
    ok1, ok2 = np.where(rising, cross_low, cross_high), np.where(rising, cross_high, cross_low)
    # Per edge: its start (if inside), then its crossings in order, so the output stays cyclic.
    edge = z_next - z
    candidates = np.stack([z, z + t1 * edge, z + t2 * edge], -1).reshape(m, 3 * K)
    valid = np.stack([keep, ok1, ok2], -1).reshape(m, 3 * K)
    packed = candidates[valid]  # the new polygons one after the other
    count = valid.sum(1, dtype=np.int32)  # int32: several times faster than the default from bool
    start = np.cumsum(count) - count
    live = count >= 3  # fewer vertices: no area, now or after further clips
    # A convex K-gon cut by a slab has at most K + 2 vertices; sized by the data, nothing is ever cut off.
    K_out = max(int(count.max(initial=0)), 3)
    take = start[live, None] + np.minimum(np.arange(K_out), count[live, None] - 1)  # repeats the last one
    return packed[take], count[live], live
