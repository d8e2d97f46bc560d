"""Coefficients of RODAS (Hairer & Wanner), the L-stable, stiffly accurate Rosenbrock pair of order 4(3).

One home for the tableau, in the transformed form of Hairer & Wanner (*Solving ODEs II*, 2nd ed.,
Springer 1996, sec. VI.4, eqs. (4.12)-(4.13) and the RODAS coefficients of their code ``rodas.f``).
With ``M = I / (GAMMA h) - J`` (``J = df/dy`` at the step's start) the six stages are::

    M u_i = f(t + C_i h, y + sum_{j<i} A_ij u_j) + sum_{j<i} (G_ij / h) u_j + D_i h df/dt

with ``C_5 = C_6 = 1``, ``A_6j = A_5j`` (``j < 5``), ``A_65 = 1``; the solution is
``y_new = y + sum_j A_6j u_j + u_6`` (stiffly accurate: the last stage value) and ``u_6`` is
the difference to the embedded third-order solution, the local error estimate.  ``D_5 = D_6 = 0``.

Properties (Hairer & Wanner, table VI.4.1 and sec. VI.4): order 4 (embedded 3) for ODEs with the
exact Jacobian, L-stable (``R(inf) = 0``) and so is the embedded method, which makes the error
estimate meaningful on stiff components; stiffly accurate (index-1 DAEs to order 3).
"""

from __future__ import annotations

__all__ = []

#: Diagonal ``gamma`` of the method [1].
GAMMA = 0.25
C2, C3, C4 = 0.386, 0.21, 0.63
D1, D2, D3, D4 = 0.25, -0.1043, 0.1035, -0.0362
A21 = 1.544
A31, A32 = 0.9466785280815826, 0.2557011698983284
A41, A42, A43 = 3.314825187068521, 2.896124015972201, 0.9986419139977817
A51, A52, A53, A54 = 1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950
G21 = -5.6688
G31, G32 = -2.430093356833875, -0.2063599157091915
G41, G42, G43 = -0.1073529058151375, -9.594562251023355, -20.47028614809616
G51, G52, G53, G54 = 7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160
G61, G62, G63, G64, G65 = 8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, \
    -6.058818238834054

#: Step-size control for the error ``err`` of an order-3 estimate: ``h_new = h SAFETY err^(-1/4)``,
#: the factor clipped to ``[FAC_MIN, FAC_MAX]`` (not above 1 right after a rejection).
SAFETY, FAC_MIN, FAC_MAX, EXPONENT = 0.9, 0.2, 6.0, 0.25
#: Relative increment of the forward-difference Jacobian (about the square root of the unit roundoff).
JACOBIAN_STEP = 1.5e-8
