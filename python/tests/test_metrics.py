"""The metrics are the harness's: a committed table cell's relMSE and ꟻLIP come out of a render
from Python to the last digit; and they follow their definitions."""
import json
import math

import numpy as np
import pytest

import manylights as ml


def reference_dir(repo, scene, width, height, strategy, spp, seed):
    for manifest in (repo / "references").glob("*/manifest.json"):
        ident = json.loads(manifest.read_text())["identity"]
        if (ident["scene"], ident["width"], ident["height"], ident["strategy"], ident["spp"],
                ident["seed"], ident["args"]) == (scene, width, height, strategy, spp, seed, []):
            return manifest.parent
    pytest.skip(f"no committed reference of {scene} at {width}x{height}")


def test_a_committed_cell_is_reproduced_to_the_last_digit(repo):
    cells = ml.load_results(repo / "results" / "quick")
    cell = next(c for c in cells if c["id"] == "diffuse-quads__power_bsdf__spp4__seed0")
    assert cell["budget"] == "spp" and cell["strategy_args"] is None
    scene = ml.load_scene("builtin:diffuse-quads")
    r = ml.render(scene, strategy=cell["strategy_name"], spp=cell["spp"], seed=cell["seed"],
                  width=cell["width"], height=cell["height"])
    ref_dir = reference_dir(repo, "builtin:diffuse-quads", 96, 64, "power+bsdf", 4096, 1000000)
    ref = ml.read_exr(ref_dir / "ref.exr")
    unlit = ~(ml.read_mask(ref_dir / "mask.png", ref.shape) | r.light_mask)
    assert unlit.sum() == cell["unlit_pixels"]
    assert ml.relmse(r.image, ref, unlit) == cell["rel_mse_unlit"]
    assert ml.mse(r.image, ref, unlit) == cell["mse_unlit"]
    assert ml.relmse(r.image, ref) == cell["rel_mse_all"]
    assert ml.flip(r.image, ref, unlit) == cell["flip_unlit"]


def test_metrics_follow_their_definitions():
    rng = np.random.default_rng(2)
    ref = rng.uniform(0, 2, (6, 5, 3)).astype(np.float32)
    img = (ref + rng.normal(0, 0.1, ref.shape)).astype(np.float32)
    x, r = img.astype(np.float64), ref.astype(np.float64)
    assert math.isclose(ml.relmse(img, ref), np.mean((x - r) ** 2 / (r * r + 0.01)), rel_tol=1e-12)
    assert math.isclose(ml.mse(img, ref), np.mean((x - r) ** 2), rel_tol=1e-12)
    mask = np.zeros((6, 5), bool)
    mask[2:4] = True
    expected = np.mean(((x - r) ** 2 / (r * r + 0.01))[mask])
    assert math.isclose(ml.relmse(img, ref, mask), expected, rel_tol=1e-12)
    assert ml.flip(ref, ref) == 0.0
    score, fmap = ml.flip(img, ref, map=True)
    assert fmap.shape == (6, 5) and 0 < score <= 1 and math.isclose(score, fmap.mean(), rel_tol=1e-5)


def test_no_pixels_is_an_error_not_a_perfect_score():
    img = np.ones((4, 4, 3), np.float32)
    for metric in (ml.relmse, ml.mse, ml.flip):
        with pytest.raises(ValueError, match="no pixel"):
            metric(img, img, np.zeros((4, 4), bool))
        with pytest.raises(ValueError, match="empty"):
            metric(np.zeros((0, 0, 3)), np.zeros((0, 0, 3)))


def test_load_results_reads_numbers_and_json(repo):
    cells = ml.load_results(repo / "results" / "quick" / "cells.csv")
    assert len(cells) > 100
    c = cells[0]
    assert isinstance(c["spp"], int) and isinstance(c["rel_mse_unlit"], float)
    assert isinstance(c["strategy_parameters"], dict) and isinstance(c["code_dirty"], bool)
    with pytest.raises(FileNotFoundError):
        ml.load_results(repo / "results" / "no-such-experiment")
