"""Markers to rigid groups from the distance spreads D (Ringer & Lasenby 2004, Sec. 3, steps 1-6)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Grouping:
    """A marker-to-group association.

    Attributes:
        groups: Marker indices per group, each sorted, groups ordered by their first marker.
        inconsistent: Rigid pairs (n1, n2) whose markers were already in two different groups
            (step 4): forcing one of them onto one segment gives an alternative grouping.
        ungrouped: Markers with no rigid partner.
    """

    groups: list[list[int]]
    inconsistent: list[tuple[int, int]]
    ungrouped: list[int]


def group_markers(spread: NDArray[np.float64], rigid_sd: float) -> Grouping:
    """Steps 1-6: visit the pairs by increasing sqrt(D) and grow groups.

    Only pairs with sqrt(D_{n1,n2}) <= ``rigid_sd`` are visited (the rest are not rigid).
    For each pair: neither marker grouped -> a new group (2); one grouped -> the other joins
    it (3), here only if it is rigid to every member already in it, so that a marker near a
    joint does not chain two segments; both grouped in different groups -> an inconsistency (4).
    """
    n = len(spread)
    label = np.full(n, -1)
    groups: list[list[int]] = []
    inconsistent: list[tuple[int, int]] = []
    i_idx, j_idx = np.triu_indices(n, 1)
    values = spread[i_idx, j_idx]
    for k in np.argsort(values, kind="stable"):
        if values[k] > rigid_sd:
            break
        a, b = int(i_idx[k]), int(j_idx[k])
        if label[a] < 0 and label[b] < 0:
            label[[a, b]] = len(groups)
            groups.append([a, b])
        elif label[a] < 0 or label[b] < 0:
            new, old = (a, b) if label[a] < 0 else (b, a)
            members = groups[label[old]]
            if spread[new, members].max() <= rigid_sd:
                label[new] = label[old]
                members.append(new)
            else:
                inconsistent.append((a, b))
        elif label[a] != label[b]:
            inconsistent.append((a, b))
    return Grouping(
        sorted(sorted(g) for g in groups), inconsistent, [int(m) for m in np.flatnonzero(label < 0)]
    )


def force_pair(grouping: Grouping, pair: tuple[int, int]) -> Grouping:
    """The alternative grouping in which the groups of an inconsistent pair are one (an ungrouped marker joins)."""
    ga, gb = (next((g for g in grouping.groups if m in g), [m]) for m in pair)
    if ga is gb:
        return grouping
    merged = [g for g in grouping.groups if g is not ga and g is not gb] + [sorted(ga + gb)]
    rest = [p for p in grouping.inconsistent if p != pair]
    return Grouping(sorted(merged), rest, [m for m in grouping.ungrouped if m not in pair])


def settle(grouping: Grouping, spread: NDArray[np.float64], rigid_sd: float) -> Grouping:
    """Take each alternative whose merged group is still rigid, in the order D found them.

    Forcing a pair together adds no error when every distance across the two groups keeps
    sqrt(D) <= ``rigid_sd`` (one rigid body that steps 1-6 happened to start twice), and a
    large one otherwise: the alternatives kept are those that do not raise the rigid error.
    """
    for pair in grouping.inconsistent:
        merged = force_pair(grouping, pair)
        if merged is grouping:
            continue
        group = next(g for g in merged.groups if pair[0] in g)
        if spread[np.ix_(group, group)].max() <= rigid_sd:
            grouping = merged
    return grouping
