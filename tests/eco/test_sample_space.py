"""The GMM sample space keeps its Gram matrix and distances by bookkeeping (one product with the store per frame);
they must equal the products recomputed from the stored components, through every kind of insertion."""

import numpy as np

from rgbt_toolkit.eco.sample_space import SampleSpace


def test_gram_and_distances_stay_exact_through_merges_and_replacements():
    rng = np.random.default_rng(11)
    length, n = 40, 6
    ipw = rng.uniform(0.5, 2.0, length).astype(np.float32).astype(np.float64)  # the store keeps float32 weights
    space = SampleSpace(n, length, ipw, learning_rate=0.2, min_weight=0.02, dtype=np.complex128)
    kinds = set()
    for k in range(120):
        centre = rng.integers(0, 3)  # three clusters, so merges into the nearest happen, and far jumps
        x = (centre * 5 + rng.standard_normal(length) * (0.2 if k % 7 else 6.0)
             + 1j * rng.standard_normal(length)).astype(np.complex128)
        info = space.add(x)
        kinds.add((info["new"] is not None, info["merged"] is not None))
        s = space.samples[: space.count]
        gram = (np.conj(s) * ipw) @ s.T
        np.testing.assert_allclose(space.gram[: space.count, : space.count], gram.real, rtol=1e-9, atol=1e-9)
        d = np.diag(gram.real)[:, None] + np.diag(gram.real)[None] - 2 * gram.real
        off = ~np.eye(space.count, dtype=bool)
        np.testing.assert_allclose(space.distance[: space.count, : space.count][off], np.maximum(d, 0)[off],
                                   rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(space.weights.sum(), 1.0)
    # every path was taken: new slot, merge into the nearest, and two merged with the new one in the freed slot
    assert {(True, False), (False, True), (True, True)} <= kinds


def test_one_product_with_the_store_per_sample(monkeypatch):
    rng = np.random.default_rng(5)
    space = SampleSpace(4, 30, np.ones(30), learning_rate=0.3, min_weight=1e-6, dtype=np.complex128)
    calls = []
    real = space._gram_column
    monkeypatch.setattr(space, "_gram_column", lambda x: calls.append(1) or real(x))
    for k in range(40):
        space.add(rng.standard_normal(30) * (1 + 10 * (k % 5 == 0)) + 0j)
    assert len(calls) == 40  # merges reuse the products they already have (ECO's update_distance_matrix)
