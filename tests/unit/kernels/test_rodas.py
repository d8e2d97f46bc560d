"""The RODAS 4(3) coefficients (screening.kernels.rodas), checked on the scalar test equation
``y' = z y`` (``h = 1``): one step of the method as its module states it gives the stability function
``R(z)``, which must agree with ``exp(z)`` to fourth order (third for the embedded solution) and
vanish as ``z -> -inf`` (L-stable, both solutions)."""

import numpy as np
import pytest

from screening.kernels import rodas as r

A = {(2, 1): r.A21, (3, 1): r.A31, (3, 2): r.A32, (4, 1): r.A41, (4, 2): r.A42, (4, 3): r.A43,
     (5, 1): r.A51, (5, 2): r.A52, (5, 3): r.A53, (5, 4): r.A54}
A.update({(6, j): A[(5, j)] for j in range(1, 5)})
A[(6, 5)] = 1.0
G = {(2, 1): r.G21, (3, 1): r.G31, (3, 2): r.G32, (4, 1): r.G41, (4, 2): r.G42, (4, 3): r.G43,
     (5, 1): r.G51, (5, 2): r.G52, (5, 3): r.G53, (5, 4): r.G54,
     (6, 1): r.G61, (6, 2): r.G62, (6, 3): r.G63, (6, 4): r.G64, (6, 5): r.G65}


def _step(z):
    """``(y_new, y_embedded)`` of one step from ``y = 1``: ``(1/GAMMA - z) u_i = z (1 + sum A_ij u_j)
    + sum G_ij u_j``; ``y_new = 1 + sum_j A_6j u_j + u_6``, the embedded one without ``u_6``."""
    u = {}
    for i in range(1, 7):
        rhs = z * (1.0 + sum(A.get((i, j), 0.0) * u[j] for j in range(1, i)))
        rhs += sum(G.get((i, j), 0.0) * u[j] for j in range(1, i))
        u[i] = rhs / (1.0 / r.GAMMA - z)
    y_new = 1.0 + sum(A[(6, j)] * u[j] for j in range(1, 6)) + u[6]
    return y_new, y_new - u[6]


@pytest.mark.parametrize("which, order", [(0, 4), (1, 3)])
def test_the_step_agrees_with_the_exponential_to_its_order(which, order):
    """The local error ``R(z) - exp(z)`` scales as ``z^(order + 1)``: halving ``z`` divides it by
    ``2^(order + 1)`` (to within 10 % at these small ``z``)."""
    err = [abs(_step(z)[which] - np.exp(z)) for z in (-0.02, -0.01)]
    assert err[0] / err[1] == pytest.approx(2.0 ** (order + 1), rel=0.1)


def test_both_solutions_are_l_stable():
    for which in (0, 1):
        assert abs(_step(-1e9)[which]) < 1e-6
        assert all(abs(_step(z)[which]) <= 1.0 for z in -np.logspace(-2, 6, 50))
