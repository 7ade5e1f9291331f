"""Renders from Python against the command line's: the same bytes, the same metadata, the same
error messages; Ctrl-C and bad input raise exceptions, the GIL is free while rendering."""
import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import manylights as ml

SPEC = "builtin:glossy-spheres?lights=64&radius=0.02"
FLAGS = dict(strategy="mis3-adaptive", spp=3, seed=5, width=40, height=24, n_max=6)


def cli_flags(**kw):
    out = []
    for k, v in kw.items():
        out += [f"--{k.replace('_', '-')}"] + ([] if v is True else [str(v)])
    return out


@pytest.mark.parametrize("spec, flags", [
    (SPEC, FLAGS),
    ("builtin:diffuse-quads", dict(strategy="tree+bsdf", spp=2, seed=1, width=32, height=20,
                                   light_points="solid-angle", sampler="sobol")),
])
def test_a_render_is_the_command_lines_bit_for_bit(cli, tmp_path, spec, flags):
    r = ml.render(spec, threads=2, **flags)
    exr = tmp_path / "cli.exr"
    done = cli("render", spec, *cli_flags(**flags), "--threads", 1, "--aux", "--quiet", "--out", exr)
    assert done.returncode == 0, done.stderr
    cli_image = ml.read_exr(exr)
    assert r.image.shape == (flags["height"], flags["width"], 3) and r.image.dtype == np.float32
    assert r.image.tobytes() == cli_image.tobytes()
    assert np.array_equal(r.light_mask, ml.read_mask(tmp_path / "cli.mask.png", r.image.shape))
    meta = json.loads((tmp_path / "cli.json").read_text())
    for key in ("scene_hash", "strategy_parameters", "resolved_strategy", "spp", "rays",
                "technique_samples", "sampler", "filter", "emission_rays", "camera"):
        assert r.metadata[key] == meta[key], key
    assert set(r.aux) == {n.split(".")[-2] for n in map(str, meta["aux_files"]) if n.endswith(".exr")}


def cli_error(cli, tmp_path, *args):
    done = cli("render", SPEC, *args, "--quiet", "--out", tmp_path / "x.exr")
    assert done.returncode != 0
    return done.stderr.splitlines()[0].removeprefix("error: ")


@pytest.mark.parametrize("py, args", [
    (dict(strategy="power", tau=0.5), ["--strategy", "power", "--tau", "0.5"]),
    (dict(strategy="mis3-adaptive", n_max="many"), ["--strategy", "mis3-adaptive", "--n-max", "many"]),
    (dict(strategy="no-such-strategy"), ["--strategy", "no-such-strategy"]),
    (dict(strategy="tree-split", tau=7), ["--strategy", "tree-split", "--tau", "7"]),
    (dict(spp=0), ["--spp", "0"]),
    (dict(sampler="nope"), ["--sampler", "nope"]),
])
def test_parameter_errors_are_value_errors_with_the_clis_message(cli, tmp_path, py, args):
    with pytest.raises(ValueError) as e:
        ml.render(SPEC, **py)
    assert str(e.value) == cli_error(cli, tmp_path, *args)


def test_bad_input_raises_python_exceptions(tmp_path):
    with pytest.raises(FileNotFoundError, match="no-such-file"):
        ml.load_scene("no-such-file.glb")
    (tmp_path / "dir.glb").mkdir()
    with pytest.raises(OSError, match="not a regular file"):
        ml.load_scene(tmp_path / "dir.glb")
    with pytest.raises(ValueError, match="unsupported scene format"):
        ml.load_scene(tmp_path)
    with pytest.raises(TypeError, match="spec"):
        ml.load_scene(None)
    with pytest.raises(TypeError, match="load_scene"):
        ml.Scene(SPEC)
    with pytest.raises(ValueError, match="builtin"):
        ml.load_scene("builtin:no-such-builtin")
    with pytest.raises(ValueError, match="output"):
        ml.render(SPEC, out="x.exr")
    with pytest.raises(ValueError):
        ml.render(SPEC, no_such_flag=1)
    with pytest.raises(ValueError, match="load_scene"):
        ml.render(ml.load_scene(SPEC), light_points="solid-angle")
    with pytest.raises(ValueError):
        ml.relmse(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))
    with pytest.raises(FileNotFoundError):
        ml.read_exr("no-such-file.exr")


@pytest.mark.parametrize("name", ["spp", "seed", "width", "threads"])
def test_a_negative_number_is_refused_by_its_flags_name(name):
    kw = dict(spp=1, width=8, height=8)
    kw[name] = -1
    with pytest.raises(ValueError, match=f"--{name}"):
        ml.render(SPEC, **kw)


def test_numpy_booleans_are_flags_and_a_spec_may_start_with_a_dash(tmp_path, monkeypatch):
    on = ml.render(SPEC, strategy="mis3-adaptive", spp=1, width=8, height=8, reproduce=np.bool_(True))
    assert on.metadata["strategy_parameters"]["reproduce"] is True
    off = ml.render(SPEC, strategy="mis3-adaptive", spp=1, width=8, height=8, reproduce=np.bool_(False))
    assert off.metadata["strategy_parameters"]["reproduce"] is False
    monkeypatch.chdir(tmp_path)
    (tmp_path / "-tri.pbrt").write_text(TRIANGLE_PBRT)
    with pytest.warns(ml.SceneWarning):
        scene = ml.load_scene("-tri.pbrt")
    r = ml.render(scene, spp=1, width=8, height=8)
    assert r.metadata["scene"] == "-tri.pbrt"


TRIANGLE_PBRT = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [45]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
AreaLightSource "diffuse" "rgb L" [4 4 4]
Shape "trianglemesh" "integer indices" [0 1 2] "point P" [-1 -1 0 1 -1 0 0 1 0]
AttributeEnd
Shape "trianglemesh" "integer indices" [0 1 2] "point P" [-3 -3 -1 3 -3 -1 0 3 -1]
WorldEnd
"""


def test_what_a_scene_file_holds_unmodelled_is_a_warning(tmp_path):
    path = tmp_path / "tri.pbrt"
    path.write_text(TRIANGLE_PBRT)
    with pytest.warns(ml.SceneWarning, match=r"tri.pbrt:4: LightSource \"infinite\""):
        scene = ml.load_scene(path)
    assert scene.info()["stats"]["warnings"] == [str(w) for w in scene._native.warnings]


def test_returned_arrays_are_the_callers_to_change():
    r = ml.render(SPEC, strategy="mis3-adaptive", spp=1, width=8, height=8)
    assert r.aux
    for a in [r.image, r.light_fraction, *r.aux.values(), ml.flip(r.image, r.image, map=True)[1]]:
        a[...] = 0


def test_the_scene_and_strategies_are_the_clis(cli):
    scene = ml.load_scene(SPEC)
    info = json.loads(cli("info", SPEC, "--json").stdout)
    assert scene.info() == info
    listed = json.loads(cli("strategies", "--json").stdout)
    assert ml.strategies() == listed
    assert any(k["flag"] == "--n-max" for s in listed if s["name"] == "mis3-adaptive" for k in s["knobs"])


def test_ctrl_c_stops_a_render_with_keyboard_interrupt():
    scene = ml.load_scene(SPEC)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        ml.render(scene, strategy="mis3-adaptive", spp=100000, width=64, height=64)
    assert time.monotonic() - start < 10, "the render stopped long after Ctrl-C"
    # the next render runs as usual
    assert ml.render(scene, spp=1, width=8, height=8).metadata["spp"] == 1


def test_the_gil_is_released_while_rendering():
    scene = ml.load_scene(SPEC)
    done, seen = threading.Event(), []
    ticks = 0

    def work():
        ml.render(scene, spp=64, width=64, height=64, progress=seen.append)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.005)
    t.join()
    assert ticks >= 5, "the main thread did not run while the render did"
    assert seen and seen == sorted(seen) and seen[-1] == 64
