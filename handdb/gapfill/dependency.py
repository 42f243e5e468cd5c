"""Which joint a missing joint follows: the thesis's dependency maps, from the skeleton.

The thesis's methods 3 to 5 watch a *dependency* of the missing point and copy its turns.
Method 3 uses the *interfinger* neighbour: the joint of the same role on the next finger
toward the little finger (the little finger, having none, looks back at the ring finger).
Methods 4 and 5 use the *intrafinger* neighbour: the joint's parent on the same finger. A
joint without such a neighbour (the thumb for method 3; the base of a finger and the palm
points for methods 4 and 5) depends on itself, which makes those methods fall back to
method 2's rule for it.
"""

from __future__ import annotations

import numpy as np

from handdb.hand.skeletons import FINGERS, Skeleton

#: Fingers whose joints have an interfinger neighbour, from the thumb side.
LONG_FINGERS: tuple[str, ...] = FINGERS[1:]


def interfinger_neighbours(skeleton: Skeleton) -> np.ndarray:
    """Return the joint each joint depends on in the thesis's method 3.

    Returns
    -------
    numpy.ndarray
        ``(J,) int64``: for a joint of the index, middle or ring finger, the joint of the
        same role on the next finger toward the little finger; for the little finger, the
        same joint of the ring finger; for the thumb, the palm and any joint whose role
        the neighbouring finger lacks, the joint itself.
    """
    neighbours = np.arange(skeleton.n_joints)
    by_finger_role = {(f, r): j for j, (f, r) in enumerate(zip(skeleton.fingers, skeleton.roles,
                                                               strict=True))}
    next_finger = dict(zip(LONG_FINGERS, (*LONG_FINGERS[1:], LONG_FINGERS[-2]), strict=True))
    for j, (finger, role) in enumerate(zip(skeleton.fingers, skeleton.roles, strict=True)):
        if finger in next_finger:
            neighbours[j] = by_finger_role.get((next_finger[finger], role), j)
    return neighbours


def intrafinger_parents(skeleton: Skeleton) -> np.ndarray:
    """Return the joint each joint depends on in the thesis's methods 4 and 5.

    Returns
    -------
    numpy.ndarray
        ``(J,) int64``: a joint's parent when the parent lies on the same finger, else
        the joint itself (the base joint of each finger, the palm points).
    """
    joints = np.arange(skeleton.n_joints)
    parents = skeleton.parents
    fingers = np.asarray(skeleton.fingers)
    same_finger = (parents >= 0) & (fingers[np.maximum(parents, 0)] == fingers) & (
        fingers != "palm"
    )
    return np.where(same_finger, parents, joints)
