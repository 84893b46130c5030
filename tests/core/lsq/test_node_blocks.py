"""Node blocks of a swarm's normal matrix (rplearn.core.lsq.node_blocks): the band a reordering
gives, products and sparse copies that read only the blocks links can fill."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.lsq.factor import band_of
from rplearn.core.lsq.node_blocks import NodeBlocks


def _blocked(n_nodes, p, links, shared=0, seed=0):
    """A symmetric matrix whose node blocks are non-zero only on the diagonal and the links,
    with ``shared`` full rows and columns after them."""
    rng = np.random.default_rng(seed)
    n = n_nodes * p + shared
    a = np.zeros((n, n))
    for i, j in [(k, k) for k in range(n_nodes)] + list(links):
        block = rng.standard_normal((p, p))
        a[i * p : (i + 1) * p, j * p : (j + 1) * p] = block
        a[j * p : (j + 1) * p, i * p : (i + 1) * p] = block.T
    if shared:
        side = rng.standard_normal((n, shared))
        a[:, -shared:] = side
        a[-shared:, :] = side.T
    return 0.5 * (a + a.T)


RING = [(k, (k + 1) % 12) for k in range(12)] + [(k, (k + 2) % 12) for k in range(12)]
STAR = [(0, k) for k in range(1, 9)]


@pytest.mark.parametrize("links, shared", [(RING, 0), (STAR, 0), (STAR, 3)])
def test_the_block_product_is_the_dense_product(links, shared):
    n_nodes = 12 if links is RING else 9
    a = _blocked(n_nodes, 5, links, shared)
    product = NodeBlocks.of(n_nodes, 5, links).product(a)
    x = np.random.default_rng(1).standard_normal((a.shape[0], 4))
    np.testing.assert_allclose(product(x), a @ x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(product(x[:, 0]), a @ x[:, 0], rtol=1e-12, atol=1e-12)


def test_the_sparse_copy_is_the_scaled_matrix():
    a = _blocked(9, 4, STAR, shared=2)
    scale = np.random.default_rng(2).uniform(0.5, 2.0, a.shape[0])
    diagonal = np.linspace(0.0, 1.0, a.shape[0])
    sparse = NodeBlocks.of(9, 4, STAR).sparse(a, scale, diagonal)
    np.testing.assert_allclose(sparse.toarray(), scale[:, None] * a * scale[None, :] + np.diag(diagonal), atol=1e-14)


@pytest.mark.parametrize("n_nodes, p, links", [(12, 5, RING), (5, 3, [(0, 1), (1, 2), (2, 3), (3, 4)]), (4, 2, [])])
def test_the_band_read_by_node_blocks_is_the_reordered_band(n_nodes, p, links):
    """LAPACK's lower band storage of the scaled matrix in the band's column order, as an
    element-wise gather of the whole scaled matrix gives it."""
    a = _blocked(n_nodes, p, links)
    n = a.shape[0]
    rng = np.random.default_rng(3)
    s, diagonal = rng.uniform(0.5, 2.0, n), rng.uniform(0.0, 1.0, n)
    order, kd = NodeBlocks.of(n_nodes, p, links).band()
    scaled = s[:, None] * a * s[None, :] + np.diag(diagonal)
    k, j = np.arange(kd + 1)[:, None], np.arange(n)[None, :]
    expected = np.where(j + k < n, scaled[order[np.minimum(j + k, n - 1)], order[j]], 0.0)
    band = band_of(a, s, diagonal, order, kd, p)
    assert band.shape == (kd + 1, n) and band.flags.f_contiguous
    np.testing.assert_allclose(band, expected, atol=1e-14)
