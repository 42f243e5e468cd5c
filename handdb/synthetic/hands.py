"""The hands synthetic clips are made of: one drawn from the population, or the thesis's."""

from __future__ import annotations

import numpy as np

from handdb.errors import BoneLengthError
from handdb.hand.model import HandModel, build_hand_model
from handdb.hand.population import sample_shape
from handdb.hand.shape import HandShape, mean_shape
from handdb.hand.skeletons import load_skeleton

#: Units of the thesis's Maya hand (its lengths are taken as centimetres).
THESIS_UNITS = "cm"


def make_hand(skeleton: str = "mediapipe21", hand_length_mm: float | None = None,
              seed: int | None = None, hand: str = "right") -> HandModel:
    """A hand of anatomically plausible shape, lengths in mm.

    Parameters
    ----------
    skeleton
        Preset name (``mediapipe21``, ``dhg22``, ``thesis21``).
    hand_length_mm
        Wrist crease to middle fingertip, mm; ``None``: the average hand's when ``seed``
        is ``None``, else drawn with the rest of the hand.
    seed
        ``None`` gives the average hand (:func:`~handdb.hand.shape.mean_shape`); an
        integer draws one hand of the population (:func:`~handdb.hand.population.sample_shape`).
    hand
        ``"right"`` or ``"left"``.
    """
    if seed is None:
        shape = mean_shape() if hand_length_mm is None else mean_shape(hand_length_mm)
    else:
        shape = sample_shape(np.random.default_rng(seed), hand_length_mm)
    return build_hand_model(hand, skeleton=skeleton, shape=shape)


def thesis_hand(hand: str = "right") -> HandModel:
    """The thesis's Maya hand: ``thesis21`` with exactly its appendix segment lengths (cm).

    Its palm is flat, as in the Maya scene, and its thumb hangs from the palm fold; the
    bones point where the average hand's do.
    """
    skeleton = load_skeleton("thesis21")
    average = mean_shape()
    flat = HandShape({joint: point * (1.0, 1.0, 0.0) for joint, point in average.points.items()},
                     THESIS_UNITS, average.thumb_pronation_deg)
    flat = HandShape({**flat.points, "thumb_cmc": flat.point("palm_fold")}, THESIS_UNITS,
                     flat.thumb_pronation_deg)
    missing = sorted(set(skeleton.bone_names) - set(skeleton.reference_lengths))
    if missing:
        raise BoneLengthError(f"thesis21 reference lengths miss bones {', '.join(missing)}")
    return build_hand_model(hand, dict(skeleton.reference_lengths), skeleton=skeleton,
                            shape=flat)
