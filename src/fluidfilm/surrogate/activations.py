"""Hidden-layer activations defined by arithmetic alone, with their derivatives (NumPy or torch arrays alike).

``pade_tanh`` is tanh's [5/4] Pade approximant (a convergent of Lambert's continued fraction) taken as an
activation in its own right:

    f(x) = x (945 + 105 x^2 + x^4) / (945 + 420 x^2 + 15 x^4)

It is smooth and increasing on the whole line (f'(x) > 0 everywhere; f' has its least value about 0.0046 near
|x| = 3.9), within 4e-4 of tanh for |x| < 3, and grows like x / 15 beyond, where tanh saturates.  Networks
trained with it (the universal bearing's: ``surrogate.universal_fit``) are evaluated without approximation error (round-off only) by
6 vector operations and one division per 8 units (``surrogate.kernels.pade_tanh64``), where a tanh exact to
round-off costs 19 and one (``tanh64``).

Examples
--------
>>> import numpy as np
>>> f, df, d2f = pade_tanh(np.array([0.0, 1.0, 3.0]))
>>> np.round(f, 4).tolist(), np.round(df, 4).tolist()
([0.0, 0.7616, 0.9955], [1.0, 0.42, 0.0107])
"""
from __future__ import annotations

__all__ = ["pade_tanh", "HIDDEN_ACTIVATIONS"]

#: hidden-layer activations the universal networks can be trained with (``conf/universal.yaml``: train.activation)
HIDDEN_ACTIVATIONS = ("tanh", "pade_tanh")


def pade_tanh(A):
    """The ``pade_tanh`` activation's values and first and second derivatives (f, f', f'') at ``A``."""
    x2 = A * A
    n, d = 945.0 + x2 * (105.0 + x2), 945.0 + x2 * (420.0 + 15.0 * x2)
    f = A * n / d
    # f = P / d with P = A n: f' = (P' - f d') / d, f'' = (P'' - 2 f' d' - f d'') / d
    dP, d2P = n + 2.0 * x2 * (105.0 + 2.0 * x2), A * (630.0 + 20.0 * x2)
    dd, d2d = A * (840.0 + 60.0 * x2), 840.0 + 180.0 * x2
    df = (dP - f * dd) / d
    return f, df, (d2P - 2.0 * df * dd - f * d2d) / d
