"""How often objects are born and how often lost ones come back, learned from the take.

A chain of boxes a lost object took after a miss is weighed as a return against a newcomer
(``returns``). Besides the chain's density under each, the two differ in their prior odds:
per frame a new object appears at rate lambda_B (births per frame), and a lost object comes
back at rate h (returns per object-frame spent unseen). The newcomer pays

    b = -log(lambda_B / h) = log h - log lambda_B

on top of its density: the log prior odds of a return against a newcomer.

Both rates are counted like P_D (``likelihood.DetectionRates``) over the windows solved so
far, each from a weak prior of ``PRIOR_EVENTS`` events in ``PRIOR_EXPOSURE`` frames, the
same for both, so that before any count b = 0 (equal odds):

    lambda_B = (births + e) / (frames + x),     h = (returns + e) / (unseen object-frames + x).

Births are the new objects kept whose first box is after the take's first frame (those at
its start were there already); a return is an object-frame where an object unseen in the
frame before takes a box, out of every object-frame following an unseen one (newcomers not
yet seen are not lost objects and do not count). Where people enter often and lost ones
rarely come back (a walking camera, MOT17-05) b < 0 favours newcomers; where the same people
hide behind one another and come back (the crossing scene of the tests) b > 0 favours returns.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

Ints = NDArray[np.int_]

PRIOR_EVENTS, PRIOR_EXPOSURE = 1.0, 10.0  # one birth per 10 frames, one return per 10 unseen object-frames


@dataclass(frozen=True)
class BirthRates:
    """Counts of births and returns so far (module doc).

    Attributes:
        births: New objects kept whose first box is after the take's first frame.
        frames: Frames counted.
        returns: Object-frames where an object unseen in the frame before took a box.
        unseen: Object-frames following a frame the object was unseen.
    """

    births: float = 0.0
    frames: float = 0.0
    returns: float = 0.0
    unseen: float = 0.0

    @property
    def birth_rate(self) -> float:
        """lambda_B, births per frame."""
        return (self.births + PRIOR_EVENTS) / (self.frames + PRIOR_EXPOSURE)

    @property
    def return_rate(self) -> float:
        """h, returns per object-frame after an unseen one."""
        return (self.returns + PRIOR_EVENTS) / (self.unseen + PRIOR_EXPOSURE)

    @property
    def newcomer_cost(self) -> float:
        """b = log h - log lambda_B, added to a newcomer's entry."""
        return float(np.log(self.return_rate) - np.log(self.birth_rate))

    def counted(self, births: int, frames: int, last_seen: Ints, taken: Ints, template_frame: int,
                lost: NDArray[np.bool_]) -> BirthRates:
        """These counts plus one window.

        Args:
            births: New objects kept in the window whose first box is after the take's first frame.
            frames: Frames of the window after its template.
            last_seen: ``(N,)`` frame each object was last seen before the window.
            taken: ``(N, M)`` the box each object took, -1 unseen (as in ``objects.advance``).
            template_frame: t0.
            lost: ``(N,)`` the objects that may return (not newcomers first seen after t0).
        """
        seen = taken >= 0
        before = np.c_[(last_seen >= template_frame)[:, None], seen[:, :-1]]  # seen in the frame before
        after_gap = ~before & lost[:, None]
        return replace(self, births=self.births + births, frames=self.frames + frames,
                       returns=self.returns + int((after_gap & seen).sum()), unseen=self.unseen + int(after_gap.sum()))
