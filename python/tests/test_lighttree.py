"""The light tree and the BRDF-oriented selection on lights given as arrays: each sample's pmf is
the one `pmf` replays, and the samples' frequencies are the pmf (chi-square)."""
import math

import numpy as np
import pytest

import manylights as ml


def lights(n=300, seed=1):
    rng = np.random.default_rng(seed)
    pos = np.column_stack([rng.uniform(-2, 2, n), rng.uniform(2, 2.5, n), rng.uniform(-2, 2, n)])
    return ml.LightTree(pos, rng.uniform(1, 2, n), radii=0.02)


def chi_square_p(counts, expected):
    """p-value of Pearson's chi-square, bins with < 5 expected pooled into one (Wilson–Hilferty
    normal approximation of the chi-square tail)."""
    small = expected < 5
    obs = np.append(counts[~small], counts[small].sum())
    exp = np.append(expected[~small], expected[small].sum())
    keep = exp > 0
    assert np.all(obs[~keep] == 0), "a light with zero probability was sampled"
    obs, exp = obs[keep], exp[keep]
    stat, dof = float(((obs - exp) ** 2 / exp).sum()), len(exp) - 1
    z = ((stat / dof) ** (1 / 3) - (1 - 2 / (9 * dof))) / math.sqrt(2 / (9 * dof))
    return 0.5 * math.erfc(z / math.sqrt(2)), dof


def test_tree_samples_follow_their_pmf():
    tree, m = lights(), 200_000
    x, n = np.array([0.3, 0.0, -0.2]), np.array([0.0, 1.0, 0.0])
    u = np.random.default_rng(7).integers(0, 2**64, m, dtype=np.uint64)
    picked, pmf = tree.sample(x, n, u)
    assert picked.shape == (m,) and np.all(picked >= 0)
    # the pmf reported at sampling is the one replayed, bit for bit
    assert np.array_equal(pmf, tree.pmf(x, n, picked))
    p_all = tree.pmf(x, n, np.arange(len(tree)))
    assert abs(p_all.sum() - 1) < 1e-4
    p, dof = chi_square_p(np.bincount(picked, minlength=len(tree)).astype(float), p_all * m)
    assert dof > 50 and p > 1e-4, (p, dof)


def test_bo_samples_follow_their_pmf_at_a_glossy_point():
    tree, m = lights(), 100_000
    x, n = np.zeros(3), np.array([0.0, 1.0, 0.0])
    wo = np.array([0.6, 0.8, 0.0])
    seeds = np.random.default_rng(3).integers(0, 2**64, m, dtype=np.uint64)
    picked, pmf = tree.bo_sample(x, n, wo, 0.05, seeds, ks=0.8, kd=0.2)
    assert np.all(picked >= 0)
    replayed = tree.bo_pmf(x, n, wo, 0.05, picked, ks=0.8, kd=0.2)
    assert np.allclose(pmf, replayed, rtol=1e-5)
    p_all = tree.bo_pmf(x, n, wo, 0.05, np.arange(len(tree)), ks=0.8, kd=0.2)
    assert abs(p_all.sum() - 1) < 1e-4
    p, dof = chi_square_p(np.bincount(picked, minlength=len(tree)).astype(float), p_all * m)
    assert dof > 20 and p > 1e-4, (p, dof)


def test_a_thousand_points_are_one_call():
    tree, m = lights(), 1000
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(-2, 2, m), np.zeros(m), rng.uniform(-2, 2, m)])
    n = np.tile([0.0, 1.0, 0.0], (m, 1))
    picked, pmf = tree.sample(x, n, rng.random(m))
    assert picked.shape == pmf.shape == (m,)
    assert np.array_equal(pmf, tree.pmf(x, n, picked))
    wo = rng.normal(size=(m, 3)) + [0, 3, 0]
    bo, bo_pmf = tree.bo_sample(x, n, wo, rng.uniform(0.05, 0.5, m), rng.integers(0, 2**63, m))
    assert np.all((bo >= 0) & (bo_pmf > 0))


def test_bad_lights_and_queries_raise_value_errors():
    with pytest.raises(ValueError):
        ml.LightTree(np.zeros((0, 3)), np.zeros(0))
    with pytest.raises(ValueError):
        ml.LightTree([[0, 0, float("nan")]], [1.0])
    with pytest.raises(ValueError):
        ml.LightTree(np.zeros((3, 2)), np.ones(3))
    tree = lights(10)
    with pytest.raises(ValueError, match="not one of"):
        tree.pmf([0, 0, 0], [0, 1, 0], 10)
    with pytest.raises(ValueError):
        tree.sample([0, 0, 0], [0, 0, 0], [1])
    with pytest.raises(ValueError):
        tree.bo_sample([0, 0, 0], [0, 1, 0], [0, 1, 0], 0.0, [1])
    with pytest.raises(ValueError, match="finite non-zero"):
        tree.sample([0, 0, 0], [0, np.inf, 0], 0.5)
    with pytest.raises(ValueError, match="radii"):
        ml.LightTree(np.zeros((3, 3)), np.ones(3), radii=[1, 2])
    with pytest.raises(ValueError, match="m x 3"):
        tree.sample(np.zeros((2, 4, 3)), [0, 1, 0], 0.5)
    with pytest.raises(ValueError, match="max_cut"):
        tree.bo_sample([0, 0, 0], [0, 1, 0], [0, 1, 0], 0.3, [1], max_cut=-1)


def test_random_numbers_and_indices_are_checked_not_coerced():
    tree = lights(10)
    x, n = [0, 0, 0], [0, 1, 0]
    with pytest.raises(ValueError, match="floats must be in"):
        tree.sample(x, n, np.array([0.5, np.nan]))
    with pytest.raises(ValueError, match="non-negative"):
        tree.sample(x, n, -1)
    half = np.array([0.1, 0.5, 0.9])
    assert np.array_equal(tree.sample(x, n, half.astype(np.float16))[0],
                          tree.sample(x, n, half.astype(np.float16).astype(np.float64))[0])
    for light in (1.7, "2"):
        with pytest.raises(TypeError, match="integer"):
            tree.pmf(x, n, light)
        with pytest.raises(TypeError, match="integer"):
            tree.bo_pmf(x, n, [0, 1, 0], 0.3, light)
