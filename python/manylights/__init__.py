"""The manylights many-light renderer from Python.

Render a scene with any strategy of the registry into numpy arrays, score images with the
experiment harness's own metrics, re-read the committed results, and sample lights of your own
with the light tree and the BRDF-oriented selection. The Rust side is ``manylights._native``.
"""
import json
import os
import warnings

import numpy as np

from . import _native
from ._native import read_exr as _read_exr
from .lighttree import LightTree
from .results import load_results

__all__ = [
    "Render", "Scene", "SceneWarning", "LightTree", "load_scene", "render", "strategies", "read_exr", "read_mask",
    "relmse", "mse", "flip", "load_results",
]

# render's flags that write files: ml.render returns what they would hold
_OUTPUT_FLAGS = {"out", "png", "exposure", "aux", "stats", "quiet"}


class SceneWarning(UserWarning):
    """What a scene file holds that the renderer does not model (skipped), as the command
    line prints it: ``load_scene`` warns once per item."""


class Scene:
    """A loaded scene (``load_scene``); ``info()`` is ``manylights info --json``."""

    def __init__(self, native):
        if not isinstance(native, _native.Scene):
            raise TypeError("a Scene comes from manylights.load_scene(spec), not from "
                            f"Scene({type(native).__name__})")
        self._native = native

    spec = property(lambda self: self._native.spec)
    camera = property(lambda self: self._native.camera)
    light_points = property(lambda self: self._native.light_points)

    def info(self):
        return json.loads(self._native.info_json())

    def __repr__(self):
        return repr(self._native)


def load_scene(spec, camera=None, light_points=None):
    """A glTF, pbrt or TOML file, or ``builtin:NAME?key=value&...``; ``camera`` picks one by
    name; ``light_points`` is render's ``--light-points`` (how points on triangle lights are
    drawn), a property of the loaded scene."""
    if not isinstance(spec, (str, os.PathLike)):
        raise TypeError(f"spec must be a path or a 'builtin:NAME' string, not "
                        f"{type(spec).__name__}")
    scene = Scene(_native.load_scene(os.fspath(spec), camera, light_points))
    for w in scene._native.warnings:
        warnings.warn(w, SceneWarning, stacklevel=2)
    return scene


def _array(data, dtype, shape):
    """A writable array of the bytes a native call returned."""
    return np.frombuffer(data, dtype=dtype).reshape(shape).copy()


class Render:
    """A render: ``image`` (H x W x 3 float32, linear), ``light_fraction`` (H x W: the share of
    the pixel's camera samples that saw a light), ``light_mask`` (where any did; the harness
    leaves those pixels out of its "unlit" metrics), ``aux`` (name -> H x W float32) and
    ``metadata`` (what ``manylights render`` writes in its JSON)."""

    def __init__(self, out):
        h, w = out["height"], out["width"]
        self.image = _array(out["image"], np.float32, (h, w, 3))
        self.light_fraction = _array(out["light_fraction"], np.float32, (h, w))
        # as the CLI's mask PNG quantises it, so that masks from Python and from files agree
        self.light_mask = np.floor(np.clip(self.light_fraction, 0, 1) * 255 + 0.5) > 0
        self.aux = {k: _array(v, np.float32, (h, w)) for k, v in out["aux"]}
        self.metadata = json.loads(out["metadata"])

    def __repr__(self):
        m = self.metadata
        return (f"Render({m['strategy']}, {m['width']}x{m['height']}, {m['spp']} spp, "
                f"{m['wall_seconds']:.2f} s)")


def _flags(strategy, spp, time_budget, seed, width, height, threads, params):
    named = {"strategy": strategy, "spp": spp, "time_budget": time_budget, "seed": seed,
             "width": width, "height": height, "threads": threads}
    argv = []
    for name, value in list(named.items()) + list(params.items()):
        flag = name.replace("_", "-")
        if name in _OUTPUT_FLAGS:
            raise ValueError(f"`{name}` is the command line's output flag: ml.render returns "
                             "the image, light mask, aux channels and metadata instead")
        if isinstance(value, (bool, np.bool_)):
            value = bool(value)
        if value is None or value is False:
            continue
        # `--flag=value`, so that a negative number is read as the flag's value (and refused
        # with the flag's own message), not as another flag
        argv.append(f"--{flag}" if value is True else f"--{flag}={value}")
    return argv


def render(scene, strategy="power+bsdf", spp=None, time_budget=None, seed=0, width=None,
           height=None, threads=None, progress=None, **params):
    """Renders ``scene`` (a ``Scene`` or a spec) as ``manylights render`` with the same flags
    does, bit for bit: ``params`` are the strategy's knobs and render's other flags, by their
    names with ``_`` for ``-`` (``n_max=8``, ``reproduce=True``, ``sampler="sobol"``).
    A bad flag or value raises ``ValueError`` with the command line's message. Ctrl-C stops the
    render (``KeyboardInterrupt``); ``progress(spp_done)`` is called as passes finish."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene, params.pop("camera", None), params.pop("light_points", None))
    for name in ("camera", "light_points"):
        if name in params and params.pop(name) != getattr(scene, name):
            raise ValueError(f"give {name} to load_scene, which loads the scene for it")
    argv = ["--out=unused.exr", f"--light-points={scene.light_points}"]
    if scene.camera is not None:
        argv.append(f"--camera={scene.camera}")
    argv += _flags(strategy, spp, time_budget, seed, width, height, threads, params)
    # the spec after `--`: one that starts with `-` is still the scene
    argv += ["--", scene.spec]
    return Render(_native.render(scene._native, argv, progress))


def strategies():
    """Every strategy: name, description, knobs (flag, default, help) and emission rays, as
    ``manylights strategies --json`` lists them."""
    return json.loads(_native.strategies())


def read_exr(path):
    """A linear EXR as an H x W x 3 float32 array."""
    w, h, data = _read_exr(os.fspath(path))
    return _array(data, np.float32, (h, w, 3))


def read_mask(path, shape):
    """A light mask PNG (``render --aux``'s ``.mask.png``, a reference's ``mask.png``) of
    ``shape`` (H, W): True where the camera sees a light."""
    h, w = (int(v) for v in shape[:2])
    if h < 1 or w < 1:
        raise ValueError(f"shape must be (H, W) with H, W ≥ 1, got {tuple(shape)}")
    return ~np.frombuffer(_native.read_mask_png(os.fspath(path), w, h), dtype=bool).reshape(h, w)


def _pair(img, ref, mask):
    img = np.ascontiguousarray(img, dtype=np.float32)
    ref = np.ascontiguousarray(ref, dtype=np.float32)
    if img.ndim != 3 or img.shape[2] != 3 or img.shape != ref.shape:
        raise ValueError(f"expected two H x W x 3 images, got {img.shape} and {ref.shape}")
    h, w = img.shape[:2]
    if h == 0 or w == 0:
        raise ValueError(f"the images are empty ({h} x {w})")
    if mask is not None:
        mask = np.ascontiguousarray(mask, dtype=bool)
        if mask.shape != (h, w):
            raise ValueError(f"the mask is {mask.shape}, the images {h} x {w}")
        if not mask.any():
            raise ValueError("the mask keeps no pixel: the error over no pixels is undefined")
        mask = mask.view(np.uint8)
    return img, ref, w, h, mask


def relmse(img, ref, mask=None):
    """Mean over pixels and channels of (x - r)^2 / (r^2 + 0.01), over the pixels where ``mask``
    is true (all without one): the harness's relMSE. For its "unlit" columns the mask is
    ``~(ref_light_mask | render.light_mask)``."""
    return _native.error_metrics(*_pair(img, ref, mask))[0]


def mse(img, ref, mask=None):
    """Mean over pixels and channels of (x - r)^2, over the pixels where ``mask`` is true."""
    return _native.error_metrics(*_pair(img, ref, mask))[1]


def flip(img, ref, mask=None, map=False):
    """HDR-FLIP of ``img`` against ``ref`` (mean over the pixels ``mask`` keeps), the harness's;
    with ``map=True`` also the per-pixel H x W error in [0, 1]."""
    img, ref, w, h, mask = _pair(img, ref, mask)
    data, mean = _native.hdr_flip(img, ref, w, h, mask)
    if map:
        return mean, _array(data, np.float32, (h, w))
    return mean
