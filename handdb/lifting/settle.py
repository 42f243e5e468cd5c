"""Choosing the palm's tilt, the thumb base's sign and every finger's signs over a clip.

A :class:`Case` is one set of hypotheses: the rigid palm's two states per frame
(:mod:`handdb.lifting.palm_states`), the thumb base's two positions under each, and the
hand prior's scores of every finger under each (:mod:`handdb.lifting.hand_prior`).
:func:`settle` chooses among them:

1. **Thumb base, prior only.** Under each tilt the thumb base takes the sign its height
   prior and its own finger's anatomy prefer; the tilt is then a chain over the frames
   (:func:`handdb.lifting.temporal.sign_posterior`) fed by the palm's own evidence and the
   fingers' votes.
2. **The clip's thumb height.** With each frame's two heights under the chosen tilt, the
   clip's height and spread are estimated (:func:`handdb.lifting.thumb_base.clip_heights`);
   each of the likelihood's modes is tried (steps 3) and the one whose solution scores
   best on anatomy, palm evidence and the height prior is kept.
3. **Thumb base, given the height.** Each frame's thumb-base sign has the log-odds of its
   two heights under the clip's, plus its finger's anatomy; the tilt hears them too; the
   tilt and then the thumb base's sign are chains over the frames.

:func:`finger_signs` then settles the fingers' signs under the chosen tilt exactly as the
hand prior and the temporal chains always have, and :func:`mirror_evidence` weighs the
solution against its clip-wide mirror image. A solution's score and that weighing keep
their terms per frame and source (:class:`handdb.lifting.evidence.Evidence`), so that the
clip's log-odds count correlated frames once per independent frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.lifting.evidence import Evidence
from handdb.lifting.hand_prior import FingerScores
from handdb.lifting.temporal import acceleration_spread, sign_posterior
from handdb.lifting.thumb_base import (
    clip_heights,
    log_normal,
    log_prior,
    outlier_density,
)

#: Smallest spread of a chain's frame-to-frame depth change, as a share of its bone length
#: (of the palm's mean bone length for the tilt).
TEMPORAL_FLOOR = 0.02

#: Largest say one finger has on a frame's palm tilt, nats: a finger the prior models badly
#: (an opposed thumb) or a mis-tracked one cannot outvote the others (on the real DHG
#: capture the thumb alone, confidently wrong, flipped the palm for half the clip).
FINGER_VOTE_CAP = 4.0

#: Largest say of the thumb base's height on a frame's tilt, nats.
THUMB_TILT_CAP = 4.0


@dataclass(frozen=True)
class Votes:
    """What the hand prior says of some fingers, per frame and palm state.

    Attributes
    ----------
    evidence
        ``(T, 2, F) float64``: log of the summed likelihood of each finger's sign states.
    best
        ``(T, 2, F) int64``: the most likely state.
    anatomy
        ``(T, 2, F) float64``: the anatomy score of that state.
    mirror_gap
        ``(T, 2, F) float64``: that less the anatomy of its mirror image (every sign
        flipped, under the other palm state); meaningful where the two palm states are
        mirror images.
    bone_log_odds
        ``(T, 2, F, 3) float64``: each bone's log-odds of the positive sign.
    """

    evidence: np.ndarray
    best: np.ndarray
    anatomy: np.ndarray
    mirror_gap: np.ndarray
    bone_log_odds: np.ndarray

    def fingers(self, which: np.ndarray | slice) -> Votes:
        """The votes of the fingers ``which`` (an index array or slice of axis 2)."""
        return Votes(*(getattr(self, name)[:, :, which] for name in VOTE_FIELDS))

    def swapped(self) -> Votes:
        """The votes with the two palm states exchanged."""
        return Votes(*(getattr(self, name)[:, ::-1] for name in VOTE_FIELDS))


#: The arrays of :class:`Votes`.
VOTE_FIELDS = ("evidence", "best", "anatomy", "mirror_gap", "bone_log_odds")


def votes_of(scores: FingerScores) -> Votes:
    """The :class:`Votes` of the hand prior's full scores."""
    top = np.take_along_axis(scores.anatomy, scores.best[..., None], axis=-1)[..., 0]
    n_states = scores.anatomy.shape[-1]
    mirror = np.take_along_axis(scores.anatomy[:, ::-1], (n_states - 1 - scores.best)[..., None],
                                axis=-1)[..., 0]
    return Votes(evidence=scores.evidence, best=scores.best, anatomy=top,
                 mirror_gap=top - mirror, bone_log_odds=scores.bone_log_odds)


def pick_states(first: Votes, second: Votes) -> Votes:
    """Votes whose palm state 0 is ``first``'s state 0 and state 1 ``second``'s state 1."""
    return Votes(*(np.stack([getattr(first, name)[:, 0], getattr(second, name)[:, 1]], axis=1)
                   for name in VOTE_FIELDS))


@dataclass(frozen=True)
class Case:
    """One set of hypotheses the signs are chosen among.

    The thumb (finger 0 of :class:`~handdb.hand.layout.HandLayout`) is kept apart from the
    other fingers: its votes depend on which side of its parent the thumb base lies.

    Attributes
    ----------
    depth
        ``(T, 2, K) float64``, clip units: the rigid palm's joints' depths relative to the
        root, in each palm state.
    evidence
        ``(T,) float64``, nats: the palm's own log-odds of state 0.
    others
        The hand prior's votes of every finger but the thumb.
    thumb
        The thumb's votes ``(T, 2, 1)`` with its base on sign 0 (deeper) and sign 1; the
        same twice without a thumb base of its own.
    thumb_dz
        ``(2, T, 2) float64``, clip units: depth of the thumb base relative to its parent,
        per sign and palm state; ``None`` without a thumb base.
    heights
        ``(2, T, 2) float64``, palm lengths: the thumb base's height over the palm plane,
        per sign and palm state; ``None`` without a thumb base.
    mirrored
        Whether palm state 1 stands for state 0's mirror image (plane fits): the clip-wide
        mirror is then weighed by :func:`mirror_evidence`. A template's two chiralities
        are separate cases instead.
    shape_log_likelihood
        Nats: how well the case's palm shape fits the average hand's, once for the clip
        (a template's arch; 0 for plane fits, whose arch is in ``evidence``).
    """

    depth: np.ndarray
    evidence: np.ndarray
    others: Votes
    thumb: tuple[Votes, Votes]
    thumb_dz: np.ndarray | None
    heights: np.ndarray | None
    mirrored: bool
    shape_log_likelihood: float = 0.0


@dataclass(frozen=True)
class Settled:
    """The tilt and thumb base :func:`settle` chose, with the solution's score.

    Attributes
    ----------
    state
        ``(T,) int64``: the palm state of each frame.
    tilt_log_odds
        ``(T,) float64``: posterior log-odds of state 0.
    thumb_sign
        ``(T, 2) int64``: the thumb base's sign under each palm state (under the chosen
        one, from its chain); zeros without a thumb base.
    thumb_log_odds
        ``(T,) float64``: posterior log-odds of sign 0 under the chosen state; NaN without
        a thumb base.
    height, spread
        The clip's thumb-base height and spread, palm lengths (NaN without a thumb base).
    evidence
        The solution's log-likelihood: per frame, the anatomy of each finger's best states
        (the other fingers, then the thumb), the palm evidence of the chosen tilt and the
        thumb base's height; for the clip, the height's prior and the palm shape's.
    """

    state: np.ndarray
    tilt_log_odds: np.ndarray
    thumb_sign: np.ndarray
    thumb_log_odds: np.ndarray
    height: float
    spread: float
    evidence: Evidence

    @property
    def score(self) -> float:
        """Nats: the evidence summed, frames counted as independent."""
        return self.evidence.total()


@dataclass(frozen=True)
class _Tallies:
    """A case's votes summed once: the other fingers' and the thumb's per base sign."""

    others_vote: np.ndarray       # (T,): the other fingers' capped votes for state 0
    others_anatomy: np.ndarray    # (T, 2, F - 1)
    thumb_evidence: np.ndarray    # (2, T, 2)
    thumb_anatomy: np.ndarray     # (2, T, 2)

    @classmethod
    def of(cls, case: Case) -> _Tallies:
        """Sum ``case``'s votes."""
        others = case.others
        vote = np.clip(others.evidence[:, 0] - others.evidence[:, 1], -FINGER_VOTE_CAP,
                       FINGER_VOTE_CAP).sum(axis=1)
        return cls(others_vote=vote, others_anatomy=others.anatomy,
                   thumb_evidence=np.stack([v.evidence[..., 0] for v in case.thumb]),
                   thumb_anatomy=np.stack([v.anatomy[..., 0] for v in case.thumb]))


def settle(case: Case, palm_floor: float, thumb_floor: float) -> Settled:
    """Choose each frame's palm tilt and thumb-base sign (steps 1-3 of the module docstring).

    Parameters
    ----------
    case
        The hypotheses.
    palm_floor, thumb_floor
        Clip units: smallest spread of the palm's and the thumb base's frame-to-frame
        depth change (:func:`handdb.lifting.temporal.acceleration_spread`).
    """
    tallies = _Tallies.of(case)
    if case.heights is None:
        return _settle_round(case, tallies, palm_floor, thumb_floor, None, np.nan, np.nan)
    first = _settle_round(case, tallies, palm_floor, thumb_floor, log_prior(case.heights),
                          np.nan, np.nan)
    frames = np.arange(len(first.state))
    modes, spread = clip_heights(case.heights[:, frames, first.state])
    tried = [_settle_round(case, tallies, palm_floor, thumb_floor,
                           log_normal(case.heights, mode, spread), mode, spread)
             for mode in modes]
    return max(tried, key=lambda s: s.score)


def _state_lead(height_ll: np.ndarray) -> np.ndarray:
    """How much more likely palm state 0 makes each frame's thumb-base height than state 1.

    ``height_ll`` ``(2, T, 2)``: log-likelihood of each sign's height under each state.
    Returns ``(T,)`` nats, 0 in a frame whose thumb base has no height (nothing seen).
    """
    known = np.isfinite(height_ll).all(axis=(0, 2))
    lead = np.zeros(height_ll.shape[1])
    ll = height_ll[:, known]
    lead[known] = (np.logaddexp(ll[0, :, 0], ll[1, :, 0])
                   - np.logaddexp(ll[0, :, 1], ll[1, :, 1]))
    return lead


def _settle_round(case: Case, tallies: _Tallies, palm_floor: float, thumb_floor: float,
                  height_ll: np.ndarray | None, height: float, spread: float) -> Settled:
    """One pass of the tilt chain and, given a clip height, the thumb base's chain.

    ``height_ll`` ``(2, T, 2)`` scores each sign's height under each palm state: the prior
    alone (``height`` NaN: no thumb chain, no score) or the clip's height; ``None``
    without a thumb base.
    """
    n_frames = len(case.evidence)
    frames, states = np.arange(n_frames), np.arange(2)
    sign = np.zeros((n_frames, 2), dtype=np.int64)
    tilt = case.evidence + tallies.others_vote
    values = case.depth
    base_odds = np.zeros((n_frames, 2))
    if height_ll is not None and case.thumb_dz is not None:
        own = height_ll + tallies.thumb_evidence
        base_odds = own[0] - own[1]                                      # (T, 2)
        sign = (base_odds < 0).astype(np.int64)
        if np.isfinite(height):
            tilt = tilt + np.clip(_state_lead(height_ll), -THUMB_TILT_CAP, THUMB_TILT_CAP)
        base_dz = case.thumb_dz[sign, frames[:, None], states]           # (T, 2)
        values = np.concatenate([values, base_dz[..., None]], axis=-1)
    thumb_vote = tallies.thumb_evidence[sign, frames[:, None], states]   # (T, 2)
    tilt = tilt + np.clip(thumb_vote[:, 0] - thumb_vote[:, 1], -FINGER_VOTE_CAP,
                          FINGER_VOTE_CAP)
    chain = values[:, None]                                              # (T, 1, 2, K)
    tilt_odds = sign_posterior(tilt[:, None], chain,
                               acceleration_spread(chain[:, :, 0], np.array([palm_floor])))[:, 0]
    state = (tilt_odds < 0).astype(np.int64)
    thumb_odds = np.full(n_frames, np.nan)
    thumb_ll, height_prior = np.zeros(n_frames), 0.0
    if height_ll is not None and case.thumb_dz is not None and case.heights is not None \
            and np.isfinite(height):
        chain = case.thumb_dz[:, frames, state].T[:, None, :, None]      # (T, 1, 2, 1)
        thumb_odds = sign_posterior(base_odds[frames, state][:, None], chain,
                                    acceleration_spread(chain[:, :, 0],
                                                        np.array([thumb_floor])))[:, 0]
        sign[frames, state] = (thumb_odds < 0).astype(np.int64)
        chosen = case.heights[sign[frames, state], frames, state]
        known = np.isfinite(chosen)
        thumb_ll[known] = np.log(np.exp(log_normal(chosen[known], height, spread))
                                 + outlier_density())
        height_prior = float(log_prior(height))
    frame_terms = np.column_stack([
        tallies.others_anatomy[frames, state],
        tallies.thumb_anatomy[sign[frames, state], frames, state],
        np.where(state == 0, 0.5, -0.5) * case.evidence,
        thumb_ll,
    ])
    return Settled(state=state, tilt_log_odds=tilt_odds, thumb_sign=sign,
                   thumb_log_odds=thumb_odds, height=height, spread=spread,
                   evidence=Evidence(frame_terms, height_prior + case.shape_log_likelihood))


def chosen_votes(case: Case, settled: Settled) -> tuple[np.ndarray, np.ndarray]:
    """Every finger's bone log-odds ``(T, F, 3)`` and best state ``(T, F)`` as settled.

    The fingers in layout order (the thumb first), under each frame's chosen palm state and
    the thumb base's settled sign.
    """
    frames, state = np.arange(len(settled.state)), settled.state
    sign = settled.thumb_sign[frames, state]
    thumb_odds = np.stack([v.bone_log_odds[frames, state] for v in case.thumb])[sign, frames]
    thumb_best = np.stack([v.best[frames, state] for v in case.thumb])[sign, frames]
    return (np.concatenate([thumb_odds, case.others.bone_log_odds[frames, state]], axis=1),
            np.concatenate([thumb_best, case.others.best[frames, state]], axis=1))


def finger_signs(bone_log_odds: np.ndarray, chain_dz: np.ndarray,
                 floor: np.ndarray) -> np.ndarray:
    """Posterior log-odds of each finger bone's positive sign under the chosen tilt.

    Parameters
    ----------
    bone_log_odds
        ``(T, F, 3) float64``: each frame's own log-odds (:func:`chosen_votes`).
    chain_dz
        ``(T, F * 3, 2, 1) float64``, clip units: the depth each finger bone spans under
        either sign.
    floor
        ``(F * 3,) float64``, clip units: smallest spread of each bone's depth change.

    Returns
    -------
    numpy.ndarray
        ``(T, F, 3) float64``.
    """
    odds = sign_posterior(bone_log_odds.reshape(len(bone_log_odds), -1), chain_dz,
                          acceleration_spread(chain_dz[:, :, 0], floor))
    return odds.reshape(bone_log_odds.shape)


def mirror_evidence(case: Case, settled: Settled) -> Evidence:
    """A solution's log-likelihood ratio against its clip-wide mirror, mirrored palm states.

    The mirror flips the tilt, the thumb base and every finger state at once; it changes
    the anatomy of the fingers (:attr:`Votes.mirror_gap`), the palm's evidence of each
    frame and the thumb height's sign, which its prior weighs. The sources are those of
    :attr:`Settled.evidence`; the thumb base's height under the clip's is unchanged.
    """
    frames, state = np.arange(len(settled.state)), settled.state
    sign = settled.thumb_sign[frames, state]
    thumb_gap = np.stack([v.mirror_gap[frames, state, 0] for v in case.thumb])[sign, frames]
    frame_terms = np.column_stack([case.others.mirror_gap[frames, state], thumb_gap,
                                   np.where(state == 0, case.evidence, -case.evidence),
                                   np.zeros(len(frames))])
    prior = float(log_prior(settled.height) - log_prior(-settled.height)) \
        if np.isfinite(settled.height) else 0.0
    return Evidence(frame_terms, prior)
