import numpy as np
import pytest
from scipy.optimize import rosen, rosen_der

from skills.perception.light.mlp import Ensemble, Mlp
from skills.perception.light.scg import scg


def test_scg_minimises_a_quadratic_in_about_n_steps():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(6, 6))
    h = a @ a.T + 6 * np.eye(6)
    b = rng.normal(size=6)
    res = scg(lambda x: 0.5 * x @ h @ x - b @ x, lambda x: h @ x - b, np.zeros(6), max_iter=60, gtol=1e-6)
    assert res.converged
    assert np.allclose(res.x, np.linalg.solve(h, b), atol=1e-6)


def test_scg_on_rosenbrock():
    res = scg(rosen, rosen_der, np.array([-1.2, 1.0]), max_iter=2000, gtol=1e-8)
    assert np.allclose(res.x, [1.0, 1.0], atol=1e-4)
    assert all(b <= a + 1e-12 for a, b in zip(res.history, res.history[1:]))  # never goes up


def test_scg_stops_on_callback():
    res = scg(rosen, rosen_der, np.array([-1.2, 1.0]), max_iter=1000, callback=lambda k, x, f: k >= 5)
    assert res.iterations == 5 and not res.converged


def test_mlp_gradient_matches_finite_differences():
    rng = np.random.default_rng(1)
    net = Mlp.create(10, 5, seed=2)
    x = rng.normal(size=(7, 10))
    y = rng.integers(0, 8, 7)
    theta = net.get()
    _, g = net.loss_and_grad(theta, x, y, 1e-3)
    eps = 1e-6
    for i in rng.choice(theta.size, 25, replace=False):
        t1, t2 = theta.copy(), theta.copy()
        t1[i] += eps
        t2[i] -= eps
        num = (net.loss_and_grad(t1, x, y, 1e-3)[0] - net.loss_and_grad(t2, x, y, 1e-3)[0]) / (2 * eps)
        assert g[i] == pytest.approx(num, rel=1e-4, abs=1e-7)


def test_mlp_learns_three_bit_patterns(tmp_path):
    """Eight states from three noisy 'lamp' brightnesses: the shape of the light task."""
    rng = np.random.default_rng(3)
    y = rng.integers(0, 8, 800)
    bits = ((y[:, None] >> np.arange(3)) & 1).astype(float)
    x = np.repeat(bits, 4, axis=1) * 0.6 + rng.normal(0, 0.15, (800, 12)) - 0.3
    net = Mlp.create(12, 10, seed=0)
    net.train(x[:600], y[:600], max_iter=200)
    assert (net.predict(x[600:]) == y[600:]).mean() > 0.97
    net.save(tmp_path / "m.npz")
    again = Mlp.load(tmp_path / "m.npz")
    assert np.allclose(again.probabilities(x[600:]), net.probabilities(x[600:]), atol=1e-5)
    assert np.allclose(again.probabilities(x[:3]).sum(axis=1), 1.0)


def _bits_task(seed, n, noise=0.15):
    rng = np.random.default_rng(seed)
    y = rng.integers(0, 8, n)
    bits = ((y[:, None] >> np.arange(3)) & 1).astype(float)
    return np.repeat(bits, 4, axis=1) * 0.6 + rng.normal(0, noise, (n, 12)) - 0.3, y


def test_ensemble_reads_like_its_members_and_round_trips(tmp_path):
    x, y = _bits_task(4, 900, noise=0.3)
    members = []
    for k in range(3):
        m = Mlp.create(12, 10, seed=k)
        m.train(x[:300 * k + 300][-300:], y[:300 * k + 300][-300:], max_iter=150)
        members.append(m)
    ens = Ensemble(members)
    xt, yt = _bits_task(5, 1000, noise=0.3)
    p = ens.probabilities(xt)
    assert np.allclose(p.sum(axis=1), 1.0)
    # the normalised geometric mean: a state all members favour stays favoured
    agree = np.all([m.predict(xt) == members[0].predict(xt) for m in members], axis=0)
    assert np.array_equal(ens.predict(xt)[agree], members[0].predict(xt)[agree])
    # it reads at least as well as its average member on new samples
    acc = (ens.predict(xt) == yt).mean()
    assert acc >= np.mean([(m.predict(xt) == yt).mean() for m in members])
    ens.save(tmp_path / "e.npz")
    again = Ensemble.load(tmp_path / "e.npz")
    assert len(again.members) == 3 and again.n_out == 8
    assert np.allclose(again.probabilities(xt), p, atol=1e-5)


def test_a_single_network_file_loads_as_an_ensemble_of_one(tmp_path):
    x, y = _bits_task(6, 300)
    net = Mlp.create(12, 10, seed=0)
    net.train(x, y, max_iter=100)
    net.save(tmp_path / "m.npz")
    one = Ensemble.load(tmp_path / "m.npz")
    assert len(one.members) == 1
    assert np.allclose(one.probabilities(x), net.probabilities(x), atol=1e-5)
