"""``LightTree``: the light BVH of ``light-tree`` and the BRDF-oriented selection of ``samplers``
on lights given as numpy arrays, every query vectorised over arrays of shading points."""
import json

import numpy as np

from . import _native


def _knob_default(flag, kind):
    """A strategy knob's default, as the registry gives it (`manylights strategies --json`)."""
    for s in json.loads(_native.strategies()):
        for k in s["knobs"]:
            if k["flag"] == flag:
                return kind(k["default"])
    raise LookupError(flag)


# the renderer's BO cut: split while the cap integral exceeds delta, at most max_cut clusters
_DELTA = _knob_default("--delta", float)
_MAX_CUT = _knob_default("--max-cut", int)


def _vec(a, m, name):
    a = np.asarray(a, dtype=np.float32)
    try:
        return np.ascontiguousarray(np.broadcast_to(a, (m, 3)))
    except ValueError:
        raise ValueError(f"{name} must be {m} x 3 (or one 3-vector), got {a.shape}") from None


def _col(a, m, dtype=np.float32, name="argument"):
    a = np.asarray(a, dtype=dtype)
    try:
        return np.ascontiguousarray(np.broadcast_to(a, (m,)))
    except ValueError:
        raise ValueError(f"{name} must have {m} values (or one), got {a.shape}") from None


def _count(vectors, columns, names):
    """How many queries the arguments describe: the longest of them (the others broadcast)."""
    for v, name in zip(vectors, names):
        if np.ndim(v) > 2:
            raise ValueError(f"{name} must be an m x 3 array (or one 3-vector), got "
                             f"{np.shape(v)}")
    sizes = [np.shape(v)[0] for v in vectors if np.ndim(v) == 2]
    sizes += [np.size(c) for c in columns if np.ndim(c) >= 1]
    return max(sizes, default=1)


def _points(m, x, n):
    return _vec(x, m, "x"), _vec(n, m, "n")


def _bits(u, m):
    """64 random bits per query: non-negative integers as given, floats in [0, 1) scaled to
    64 bits."""
    u = np.asarray(u)
    if u.dtype.kind == "f":
        u = u.astype(np.float64)  # float16's u * 2^53 would overflow
        if not np.all((u >= 0) & (u < 1)):  # NaN fails both
            raise ValueError("u: floats must be in [0, 1)")
        u = np.floor(u * 2.0**53).astype(np.uint64) << np.uint64(11)
    elif u.dtype.kind == "i":
        if np.any(u < 0):
            raise ValueError("u: integers must be non-negative (64 random bits)")
    elif u.dtype.kind != "u":
        raise TypeError(f"u must be uint64 bits or floats in [0, 1), not {u.dtype}")
    return _col(u, m, np.uint64, "u")


def _lights(light, m):
    """Light indices: integers only (a float would be truncated without a word)."""
    a = np.asarray(light)
    if a.dtype.kind not in "iu":
        raise TypeError(f"light must be integer indices, not {a.dtype}")
    return _col(a, m, np.int64, "light")


def _cut(delta, max_cut):
    """The BO cut's parameters, checked here so that a bad one is named, not a conversion."""
    if isinstance(max_cut, (bool, np.bool_)) or not isinstance(max_cut, (int, np.integer)) \
            or max_cut < 1:
        raise ValueError(f"max_cut must be an integer ≥ 1, got {max_cut!r}")
    delta = float(delta)
    if not (np.isfinite(delta) and delta >= 0):
        raise ValueError(f"delta must be finite and ≥ 0, got {delta}")
    return delta, int(max_cut)


def _picks(data):
    lights, pmf = data
    return (np.frombuffer(lights, dtype=np.int64).copy(),
            np.frombuffer(pmf, dtype=np.float32).copy())


class LightTree:
    """A light tree (Conty Estevez & Kulla 2018) over ``n`` lights.

    ``positions`` (n x 3) and ``powers`` (n) are required; ``radii`` (spheres, else points)
    make each light's bounding box; ``normals`` (n x 3) make them one-sided emitters facing
    along the normal (Lambertian: ``theta_e`` pi/2), else they emit in every direction
    (``theta_o`` pi); ``theta_o`` gives a cone of normals of that half-angle around each normal;
    ``two_sided`` emits around -normal too. Scalars broadcast.
    """

    def __init__(self, positions, powers, radii=0.0, normals=None, theta_o=None,
                 theta_e=np.pi / 2, two_sided=False):
        p = np.asarray(positions, dtype=np.float32)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"positions must be n x 3, got {p.shape}")
        n = p.shape[0]
        r = _col(radii, n, name="radii")[:, None]
        axis = _vec((0, 0, 1) if normals is None else normals, n, "normals")
        if theta_o is None:
            theta_o = np.pi if normals is None else 0.0
        self._native = _native.LightTree(
            np.ascontiguousarray(p - r), np.ascontiguousarray(p + r), axis,
            _col(theta_o, n, name="theta_o"), _col(theta_e, n, name="theta_e"),
            _col(powers, n, name="powers"), _col(two_sided, n, np.uint8, "two_sided"))

    def __len__(self):
        return len(self._native)

    def sample(self, x, n, u):
        """One light per point ``x`` with normal ``n`` (m x 3, or one of each) by the tree's
        descent with random numbers ``u`` (m; uint64 bits or floats in [0, 1)): ``(light, pmf)``
        arrays, light -1 where every light is dark at ``x``."""
        m = _count([x, n], [u], ["x", "n"])
        x, n = _points(m, x, n)
        return _picks(self._native.sample(x, n, _bits(u, m)))

    def pmf(self, x, n, light):
        """The probability that ``sample`` at each ``(x, n)`` returns ``light``."""
        m = _count([x, n], [light], ["x", "n"])
        x, n = _points(m, x, n)
        return np.frombuffer(self._native.pmf(x, n, _lights(light, m)), dtype=np.float32).copy()

    def _shading(self, m, wo, alpha, ks, kd):
        return (_vec(wo, m, "wo"), _col(alpha, m, name="alpha"), _col(ks, m, name="ks"),
                _col(kd, m, name="kd"))

    def bo_sample(self, x, n, wo, alpha, u, ks=1.0, kd=0.0, delta=_DELTA, max_cut=_MAX_CUT):
        """BRDF-oriented selection (Liu et al. 2019) at shading points: position ``x``, normal
        ``n``, direction to the viewer ``wo``, GGX ``alpha``, luminances of the glossy (``ks``)
        and diffuse (``kd``) weights. ``u``: 64 random bits per point (it seeds that point's
        numbers). Returns ``(light, pmf)`` as ``sample`` does."""
        m = _count([x, n, wo], [alpha, u, ks, kd], ["x", "n", "wo"])
        x, n = _points(m, x, n)
        return _picks(self._native.bo_sample(
            x, n, self._shading(m, wo, alpha, ks, kd), _bits(u, m), *_cut(delta, max_cut)))

    def bo_pmf(self, x, n, wo, alpha, light, ks=1.0, kd=0.0, delta=_DELTA, max_cut=_MAX_CUT):
        """The probability that ``bo_sample`` with the same shading returns ``light``."""
        m = _count([x, n, wo], [alpha, light, ks, kd], ["x", "n", "wo"])
        x, n = _points(m, x, n)
        return np.frombuffer(self._native.bo_pmf(
            x, n, self._shading(m, wo, alpha, ks, kd), _lights(light, m), *_cut(delta, max_cut)),
            dtype=np.float32).copy()
