"""A probability for every label from the margins of its alternatives.

Read the window objective as a negative log-likelihood in units of ``scale``:
P(Q) = exp(-E(Q) / scale) / Z over the feasible readings Q (Ringer & Lasenby's path
probability, eq. 13, is exactly such a product of per-step likelihoods; the window's arc
costs are its negative logarithms up to constants). The probability that object n holds
slot u at frame t is the marginal

    P(Q_n(t) = u) = sum_{Q: Q_n(t) = u} exp(-E(Q) / s) / sum_Q exp(-E(Q) / s).

Keep in each sum only its largest term (the max-marginal, or Viterbi, approximation):
the best reading through u costs E(P) + Delta(n, t, u) (``margins``), so, with c the
chosen slot and Delta(n, t, c) = 0,

    p(n, t) = 1 / (1 + sum_{u != c} exp(-Delta(n, t, u) / s)).

It is 1/2 at an exact tie with one alternative, above 1 - e^{-d} when every alternative
is d units dearer, and below 1/2 when an alternative is cheaper than the chosen reading
(Delta < 0: P was not the optimum). Readings that leave the label where it is (a copied
point, ``same_place``) count for it, not against it. Evaluated as a logistic of a log-sum-exp, so a large
negative Delta gives 0 rather than an overflow.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.special import expit


def label_probability(
    margin: NDArray[np.float64], chosen: NDArray[np.intp], same: NDArray[np.bool_], scale: float = 1.0,
) -> NDArray[np.float64]:
    """``(N, M)`` p(n, t) from ``margin`` ``(N, M, K)`` and the chosen slots ``(N, M)``.

    Args:
        margin: Delta(n, t, u), inf for slots that are no alternative.
        chosen: The chosen slot of every object and frame.
        same: ``(N, M, K)`` slots that put the label where the chosen one does
            (``same_place``): their readings count for the label, not against it.
        scale: Cost units per nat of log-likelihood.
    """
    if not scale > 0:
        raise ValueError(f"confidence scale must be positive, got {scale}")
    alternative = -margin / scale
    np.put_along_axis(alternative, chosen[..., None], -np.inf, axis=2)
    with np.errstate(divide="ignore"):  # log(0) = -inf: no such slot
        support = np.logaddexp(0.0, _log_sum_exp(np.where(same, alternative, -np.inf)))
        against = _log_sum_exp(np.where(same, -np.inf, alternative))
    probability: NDArray[np.float64] = expit(support - against)
    return probability


def _log_sum_exp(terms: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(N, M)`` log sum_u exp(terms[..., u]), -inf where every term is -inf."""
    top = terms.max(axis=2, keepdims=True)
    shift = np.where(np.isfinite(top), top, 0.0)  # all -inf: no term, the sum is 0
    with np.errstate(divide="ignore"):  # log(0) = -inf is the right answer there
        total: NDArray[np.float64] = (shift + np.log(np.exp(terms - shift).sum(axis=2, keepdims=True)))[..., 0]
    return total


def nearest_alternative(
    margin: NDArray[np.float64], chosen: NDArray[np.intp], same: NDArray[np.bool_],
) -> NDArray[np.float64]:
    """``(N, M)`` min over u != chosen (and not in ``same``) of Delta(n, t, u): the margin of
    each label (inf if none)."""
    others = np.where(same, np.inf, margin)
    np.put_along_axis(others, chosen[..., None], np.inf, axis=2)
    nearest: NDArray[np.float64] = others.min(axis=2)
    return nearest
