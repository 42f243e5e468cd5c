"""Where a skeleton's palm and fingers are: the parts the hand prior reasons about."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.errors import SkeletonError
from handdb.hand.skeletons import FINGERS, Skeleton
from handdb.vectors import cross, norm

#: Roles of joints that sit on the near-rigid palm (with the long fingers' MCP joints).
PALM_ROLES = frozenset({"wrist", "palm_fold", "palm_center", "cmc"})

#: Bones per finger below the palm that the sign model enumerates (2**3 sign states).
CHAIN_BONES = 3

#: Sine of the angle between two palm edges below which the palm counts as a line: far
#: below any hand's (the wrist-index and wrist-little edges meet at some 20 degrees) and
#: far above rounding (1e-16).
COLLINEAR_SINE = 1e-9


@dataclass(frozen=True)
class HandLayout:
    """The palm and finger chains of a skeleton.

    Attributes
    ----------
    palm_bones
        ``(P,) int64``: child joints of the bones inside the palm, topological order.
    wrist, index_mcp, little_mcp
        Joints spanning the palm (its normal is their cross product).
    fingers
        Finger names, thumb first.
    chains
        ``(F, 3) int64``: child joints of each finger's bones below the palm, base to tip.
    chain_bases
        ``(F,) int64``: the palm joint each chain hangs from.
    """

    palm_bones: np.ndarray
    wrist: int
    index_mcp: int
    little_mcp: int
    fingers: tuple[str, ...]
    chains: np.ndarray
    chain_bases: np.ndarray

    @property
    def is_thumb(self) -> np.ndarray:
        """``(F,) bool``."""
        return np.array([f == "thumb" for f in self.fingers])


def _on_palm(skeleton: Skeleton, joint: int) -> bool:
    role, finger = skeleton.roles[joint], skeleton.fingers[joint]
    return (joint == skeleton.root or role in PALM_ROLES
            or (role == "mcp" and finger != "thumb"))


def hand_layout(skeleton: Skeleton) -> HandLayout:
    """Find the palm and finger chains of ``skeleton``.

    Raises
    ------
    SkeletonError
        If the skeleton lacks the wrist or the index or little MCP joint, or a finger does
        not hang three bones below the palm.
    """
    palm = [j for j in range(skeleton.n_joints) if _on_palm(skeleton, j)]
    chains, bases = [], []
    for finger in FINGERS:
        chain = [j for j in skeleton.finger_chain(finger) if j not in palm]
        if len(chain) != CHAIN_BONES:
            raise SkeletonError(
                f"skeleton '{skeleton.name}': finger '{finger}' has {len(chain)} joints "
                f"below the palm; the hand prior needs {CHAIN_BONES}")
        chains.append(chain)
        bases.append(int(skeleton.parents[chain[0]]))
    return HandLayout(
        palm_bones=np.array([j for j in palm if skeleton.parents[j] >= 0], dtype=np.int64),
        wrist=skeleton.index("wrist"),
        index_mcp=skeleton.index("index_mcp"),
        little_mcp=skeleton.index("little_mcp"),
        fingers=FINGERS,
        chains=np.array(chains, dtype=np.int64),
        chain_bases=np.array(bases, dtype=np.int64),
    )


def unit_vectors(vectors: np.ndarray) -> np.ndarray:
    """Each vector over its length, ``(..., D) float64``; NaN where the length is 0.

    A zero vector has no direction: it comes out NaN (which the callers' NaN rules skip),
    not as numpy's 0/0 with a ``RuntimeWarning``.
    """
    vectors = np.asarray(vectors, dtype=np.float64)
    norms = norm(vectors)[..., None]
    return np.divide(vectors, norms, out=np.full_like(vectors, np.nan), where=norms > 0)


def palm_normals(wrist: np.ndarray, index_mcp: np.ndarray, little_mcp: np.ndarray,
                 hand: str) -> np.ndarray:
    """Unit normals of the palm towards its palmar side.

    Parameters
    ----------
    wrist, index_mcp, little_mcp
        ``(..., 3) float64``: the three joints that span the palm, any unit.
    hand
        ``"right"`` or ``"left"``: the right hand's palmar side is that of
        ``(index - wrist) x (little - wrist)``, the left hand's the opposite.

    Returns
    -------
    numpy.ndarray
        ``(..., 3) float64``; NaN where the three joints are collinear or coincide (a
        degenerate palm has no plane) or one is absent.
    """
    across, along = index_mcp - wrist, little_mcp - wrist
    normal = cross(across, along)
    spans = norm(across) * norm(along)
    sine = np.divide(norm(normal), spans, out=np.zeros_like(spans),
                     where=spans > 0)
    # rounding leaves collinear points a cross product of about 1e-16 of their spans,
    # which normalises into a direction that means nothing
    normal[~(sine > COLLINEAR_SINE)] = 0.0
    return unit_vectors(-normal if hand == "left" else normal)
