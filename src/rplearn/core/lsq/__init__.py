"""The joint least-squares engine of :mod:`rplearn.core` (paper Sec. IV-B, V-A).

=====================  ==========================================================================
module                 holds
=====================  ==========================================================================
statistics
``normal_equations``   :class:`NormalEquations`: ``X^T X``, ``X^T y``, ``y^T y`` per link, streamed
``link_statistics``    the products of links' feature blocks that fill them
``runtime``            :class:`StatisticsRuntime`: their worker pool, block buffers, fork hook
``node_blocks``        which node blocks of ``X^T X`` can be non-zero
``block_sums``         :class:`BlockSums`: sums per time block, an error drifting over seconds
solve
``solver``             :func:`solve`, :func:`fit_joint`, :func:`identifiability`: gauge, KKT path
``solver_large``       the path above ``LARGE_COLUMNS`` columns: one factor, lazy covariance
``solution``           :class:`JointSolution`, :class:`FitReport`, :class:`GaugeNote`
``closing``            :func:`close_solution`: the closing arithmetic both paths share
``level``              the level a regularised solve shrinks toward (the data's own)
``penalty``            smoothness penalty weights, nested sub-problems
factorisations
``factor``             :class:`ConstrainedFactor` over the :class:`Factor` variants
``refined``            a float32 Cholesky factor with solves refined to float64
``spectrum``           rank and condition number, exact or estimated
``products``           products with the normal matrix in scipy's BLAS; an SPD inverse by Cholesky
``solver_cholesky``    one Cholesky factor: solves, inverse, gauge-constrained inverse (lock released)
selection
``selection``          order and smoothing by grouped cross-validation
``shifted``            the statistics of the data less a known fit (a prior's deviation)
``selection_folds``    the folds of the selection, and each one's share of the variance inflation
``selection_result``   :class:`Selection`, :class:`CurvePoint`
``ties``               the points the held-out units cannot tell apart (choice, spread)
=====================  ==========================================================================

Its public names are exported by :mod:`rplearn.core` (``from rplearn.core import fit_joint``);
this package lists none of its own. It may import the maths modules at the top of
``rplearn.core`` (geometry, bases, links, thread control), which never import it
(tests/test_architecture.py).
"""

from __future__ import annotations

__all__: list[str] = []
