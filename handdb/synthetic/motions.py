"""Hand motions: joint-angle trajectories and wrist rotations, deterministic given a seed.

A :class:`Motion` holds, for ``T`` frames, the joint angles of :mod:`.kinematics`, the
rotation of the hand relative to the camera and the displacement of the root from its home
position. Wrist rotations turn the hand away from the palm facing the camera with the
fingers up (:data:`~handdb.synthetic.kinematics.PALM_TO_CAMERA`); every motion stays
within the joint limits.

Key poses are interpolated with monotone cubic (PCHIP) splines, which never overshoot
their key values, so a trajectory between poses within the limits stays within them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.spatial.transform import Rotation

from handdb.errors import ParameterError, UnknownNameError
from handdb.hand.anatomy import DIP_PIP_COUPLING
from handdb.synthetic.kinematics import (
    ANGLE_INDEX,
    ANGLE_LIMITS,
    ANGLE_NAMES,
    N_ANGLES,
    PALM_TO_CAMERA,
    clip_to_limits,
)

LONG_FINGERS = ("index", "middle", "ring", "little")


@dataclass(frozen=True)
class Motion:
    """A hand motion sampled at ``fps``.

    Attributes
    ----------
    name
        The motion's name (a key of :data:`MOTIONS`).
    fps
        Frames per second.
    angles
        ``(T, N_ANGLES) float64``, radians, :data:`~.kinematics.ANGLE_NAMES` order.
    root_rotation
        ``(T, 3, 3) float64``: hand frame to camera frame.
    root_offset
        ``(T, 3) float64``: displacement of the root from its home position, camera
        frame, in hand lengths (multiply by the hand's length for its units).
    """

    name: str
    fps: float
    angles: np.ndarray
    root_rotation: np.ndarray
    root_offset: np.ndarray

    @property
    def n_frames(self) -> int:
        """Number of frames ``T``."""
        return self.angles.shape[0]


def pose(**degrees: float) -> np.ndarray:
    """Return a pose vector ``(N_ANGLES,)`` radians from angles in degrees; others 0.

    ``pip`` and ``dip`` flexion of a long finger may be given as ``<finger>_curl``: the PIP
    flexion, with the DIP following at :data:`DIP_PIP_COUPLING` of it.
    """
    vector = np.zeros(N_ANGLES)
    for name, value in degrees.items():
        if name.endswith("_curl"):
            finger = name.removesuffix("_curl")
            vector[ANGLE_INDEX[f"{finger}_pip_flexion"]] = np.radians(value)
            vector[ANGLE_INDEX[f"{finger}_dip_flexion"]] = np.radians(DIP_PIP_COUPLING * value)
        else:
            vector[ANGLE_INDEX[name]] = np.radians(value)
    return vector


def _fingers(mcp: float, curl: float, **thumb: float) -> np.ndarray:
    """Return a pose with every long finger at one MCP flexion and curl (degrees)."""
    spec = {f"{f}_mcp_flexion": mcp for f in LONG_FINGERS}
    spec.update({f"{f}_curl": curl for f in LONG_FINGERS})
    return pose(**spec, **thumb)


#: Key poses of everyday gestures, radians. In ``PINCH`` the thumb and index tips of the
#: average hand come within about 10 mm, pad to pad (hands of other shapes come closer or
#: stay further apart).
OPEN = pose(thumb_cmc_abduction=10.0)
FIST = _fingers(80.0, 95.0, thumb_cmc_flexion=35.0, thumb_cmc_abduction=35.0,
                thumb_mcp_flexion=45.0, thumb_ip_flexion=50.0)
SPREAD = pose(index_mcp_abduction=15.0, ring_mcp_abduction=12.0, little_mcp_abduction=25.0,
              thumb_cmc_flexion=-10.0, thumb_cmc_abduction=40.0)
PINCH = pose(index_mcp_flexion=55.0, index_curl=60.0, middle_mcp_flexion=20.0,
             middle_curl=30.0, ring_mcp_flexion=20.0, ring_curl=30.0, little_mcp_flexion=20.0,
             little_curl=30.0, thumb_cmc_flexion=10.0, thumb_cmc_abduction=10.0,
             thumb_cmc_twist=20.0, thumb_mcp_flexion=40.0, thumb_ip_flexion=50.0)
POINT = FIST.copy()
POINT[[ANGLE_INDEX[f"index_{d}"] for d in ("mcp_flexion", "pip_flexion", "dip_flexion")]] = 0.0
GESTURES: dict[str, np.ndarray] = {
    "open": OPEN, "fist": FIST, "spread": SPREAD, "pinch": PINCH, "point": POINT,
}


def minimum_jerk(tau: np.ndarray) -> np.ndarray:
    """Evaluate the minimum-jerk profile ``10 t^3 - 15 t^4 + 6 t^5``, ``t`` in [0, 1]."""
    t = np.clip(tau, 0.0, 1.0)
    return t**3 * (10.0 - 15.0 * t + 6.0 * t**2)


def _wrist_rotation(euler_deg: np.ndarray) -> np.ndarray:
    """Hand-to-camera rotations ``(T, 3, 3)`` for wrist angles ``(T, 3)`` degrees.

    The columns are flexion (about the hand's ``x``), pronation (about ``y``, the forearm
    axis) and deviation (about ``z``, the palm normal), applied in the hand frame in that
    order, then :data:`PALM_TO_CAMERA`.
    """
    wrist = Rotation.from_euler("xyz", euler_deg, degrees=True).as_matrix()
    return PALM_TO_CAMERA @ wrist


def _keyframed(times: np.ndarray, keys: np.ndarray, n_frames: int, fps: float) -> np.ndarray:
    """Sample a PCHIP curve through ``keys`` ``(K, D)`` at ``times`` ``(K,)`` s, ``(T, D)``."""
    return PchipInterpolator(times, keys, axis=0, extrapolate=False)(np.arange(n_frames) / fps)


def _key_times(rng: np.random.Generator, duration: float, low: float, high: float) -> np.ndarray:
    """Key times from 0 until past ``duration`` seconds, ``low``-``high`` s apart."""
    gaps = rng.uniform(low, high, size=int(np.ceil(duration / low)) + 2)
    times = np.concatenate([[0.0], np.cumsum(gaps)])
    return times[: int(np.searchsorted(times, duration)) + 1]


#: Clench: share of the clip the fist is held at the end, and how many seconds each finger
#: starts closing before the index (a fist closes from the little-finger side, the thumb
#: last); the seed jitters each start by up to ``CLENCH_JITTER_S``.
CLENCH_HOLD_FRACTION = 0.1
CLENCH_LEAD_S = {"thumb": 0.0, "index": 0.0, "middle": 0.08, "ring": 0.16, "little": 0.24}
CLENCH_JITTER_S = 0.02


def clench(n_frames: int, fps: float, rng: np.random.Generator) -> Motion:
    """Close an open hand into a fist, the palm facing the camera and still.

    Every finger closes along a minimum-jerk profile over the same duration, the little
    finger first and the index and thumb last; the fist is held for the last
    ``CLENCH_HOLD_FRACTION`` of the clip.
    """
    t = np.arange(n_frames) / fps
    lead = np.array(list(CLENCH_LEAD_S.values()))
    lead = lead + rng.uniform(-CLENCH_JITTER_S, CLENCH_JITTER_S, size=lead.shape)
    start = lead.max() - lead
    closing = max(t[-1] * (1.0 - CLENCH_HOLD_FRACTION) - start.max(), 1.0 / fps)
    finger_of_angle = [list(CLENCH_LEAD_S).index(name.split("_")[0]) for name in ANGLE_NAMES]
    progress = minimum_jerk((t[:, None] - start[finger_of_angle]) / closing)
    angles = OPEN + progress * (FIST - OPEN)
    rotation = np.broadcast_to(PALM_TO_CAMERA, (n_frames, 3, 3)).copy()
    return Motion("clench", fps, angles, rotation, np.zeros((n_frames, 3)))


#: Rapid gestures: transition and hold durations (s), wrist excursions (degrees) as
#: flexion, pronation, deviation, and root drift (hand lengths) along camera x, y, z.
RAPID_TRANSITION_S = (0.12, 0.25)
RAPID_HOLD_S = (0.05, 0.3)
RAPID_WRIST_DEG = np.array([20.0, 40.0, 15.0])
RAPID_ROOT_DRIFT = np.array([0.08, 0.08, 0.04])


def rapid(n_frames: int, fps: float, rng: np.random.Generator) -> Motion:
    """Rapid gestures: fast switches between open, fist, spread, pinch and point.

    Each switch takes 0.12-0.25 s (finger joints reach about 1000 deg/s), each gesture is
    held 0.05-0.3 s, and the wrist turns at the same time, pronating up to +-40 deg,
    flexing up to +-20 deg and deviating up to +-15 deg, while the hand drifts a little.
    """
    duration = n_frames / fps
    n_gestures = int(np.ceil(duration / RAPID_TRANSITION_S[0])) + 1
    chosen = np.array(list(GESTURES.values()))[rng.integers(len(GESTURES), size=n_gestures)]
    steps = np.stack([rng.uniform(*RAPID_TRANSITION_S, n_gestures),
                      rng.uniform(*RAPID_HOLD_S, n_gestures)], axis=1).ravel()
    times = np.concatenate([[0.0], np.cumsum(steps)])
    keys = np.concatenate([OPEN[None], np.repeat(chosen, 2, axis=0)])
    last = int(np.searchsorted(times, duration)) + 1
    times, keys = times[:last], keys[:last]
    angles = _keyframed(times, keys, n_frames, fps)
    wrist_keys = rng.uniform(-1.0, 1.0, size=(len(times), 3)) * RAPID_WRIST_DEG
    wrist_keys[0] = 0.0
    rotation = _wrist_rotation(_keyframed(times, wrist_keys, n_frames, fps))
    offset_keys = rng.uniform(-1.0, 1.0, size=(len(times), 3)) * RAPID_ROOT_DRIFT
    offset_keys[0] = 0.0
    return Motion("rapid", fps, angles, rotation,
                  _keyframed(times, offset_keys, n_frames, fps))


#: Waving: frequency (Hz), wrist deviation amplitude (degrees), finger flutter (degrees).
WAVE_HZ = (1.2, 2.0)
WAVE_DEVIATION_DEG = (20.0, 30.0)
WAVE_FINGER_DEG = 15.0
WAVE_SWAY = 0.03


def wave(n_frames: int, fps: float, rng: np.random.Generator) -> Motion:
    """Waving goodbye: an open hand swinging side to side about the palm normal.

    The wrist deviates sinusoidally (1.2-2 Hz, +-20-30 deg); the fingers flex slightly and
    lag the swing, and the hand sways with it.
    """
    t = np.arange(n_frames) / fps
    phase = 2.0 * np.pi * rng.uniform(*WAVE_HZ) * t + rng.uniform(0.0, 2.0 * np.pi)
    amplitude = rng.uniform(*WAVE_DEVIATION_DEG)
    ramp = minimum_jerk(t / 0.5)
    euler = np.zeros((n_frames, 3))
    euler[:, 2] = ramp * amplitude * np.sin(phase)
    euler[:, 1] = ramp * 0.3 * amplitude * np.sin(phase - 0.5)
    flutter = np.radians(WAVE_FINGER_DEG) * ramp * 0.5 * (1.0 + np.sin(phase - 1.0))
    angles = np.tile(OPEN, (n_frames, 1))
    for finger in LONG_FINGERS:
        angles[:, ANGLE_INDEX[f"{finger}_mcp_flexion"]] += flutter
        angles[:, ANGLE_INDEX[f"{finger}_pip_flexion"]] += flutter
        angles[:, ANGLE_INDEX[f"{finger}_dip_flexion"]] += DIP_PIP_COUPLING * flutter
    offset = np.zeros((n_frames, 3))
    offset[:, 0] = WAVE_SWAY * ramp * np.sin(phase)
    return Motion("wave", fps, clip_to_limits(angles), _wrist_rotation(euler), offset)


#: Random motion: seconds between key poses, share of each joint's range it may use,
#: wrist excursion (degrees) and root drift (hand lengths, camera x, y, z).
RANDOM_KEY_S = (0.4, 0.9)
RANDOM_RANGE_SHARE = 0.8
RANDOM_WRIST_DEG = np.array([25.0, 35.0, 15.0])
RANDOM_ROOT_DRIFT = np.array([0.08, 0.08, 0.04])

#: How far (degrees) a key's DIP flexion may stray from the coupled value, and each
#: finger's abduction from the shared spread: small enough that neighbouring fingers,
#: which rest 5-7 deg apart, never cross.
RANDOM_DIP_SPREAD_DEG = 8.0
RANDOM_ABDUCTION_JITTER_DEG = {"index": 2.0, "middle": 1.5, "ring": 2.0, "little": 2.0}


def random_motion(n_frames: int, fps: float, rng: np.random.Generator) -> Motion:
    """Smooth random motion: key poses drawn within the joint limits every 0.4-0.9 s.

    Each key draws every flexion uniformly from the central ``RANDOM_RANGE_SHARE`` of its
    range; DIP flexion follows the PIP (:data:`DIP_PIP_COUPLING`) within a few degrees.
    The fingers spread together: one spread in [0, 1] a key opens every finger's
    abduction toward its upper limit, each within a few degrees, so fingers never cross.
    The wrist and the root wander smoothly too.
    """
    times = _key_times(rng, n_frames / fps, *RANDOM_KEY_S)
    n_keys = len(times)
    centre, half = ANGLE_LIMITS.mean(axis=1), np.diff(ANGLE_LIMITS, axis=1)[:, 0] / 2.0
    keys = centre + RANDOM_RANGE_SHARE * half * rng.uniform(-1.0, 1.0, (n_keys, N_ANGLES))
    spread = rng.uniform(0.0, 1.0, n_keys)
    for finger in LONG_FINGERS:
        pip, dip = ANGLE_INDEX[f"{finger}_pip_flexion"], ANGLE_INDEX[f"{finger}_dip_flexion"]
        jitter = np.radians(RANDOM_DIP_SPREAD_DEG) * rng.uniform(-1.0, 1.0, n_keys)
        keys[:, dip] = DIP_PIP_COUPLING * keys[:, pip] + jitter
        abduction = ANGLE_INDEX[f"{finger}_mcp_abduction"]
        opening = 0.0 if finger == "middle" else RANDOM_RANGE_SHARE * ANGLE_LIMITS[abduction, 1]
        wobble = np.radians(RANDOM_ABDUCTION_JITTER_DEG[finger]) * rng.uniform(-1.0, 1.0, n_keys)
        keys[:, abduction] = spread * opening + wobble
    keys = clip_to_limits(keys)
    wrist = rng.uniform(-1.0, 1.0, (n_keys, 3)) * RANDOM_WRIST_DEG
    drift = rng.uniform(-1.0, 1.0, (n_keys, 3)) * RANDOM_ROOT_DRIFT
    return Motion(
        "random", fps,
        _keyframed(times, keys, n_frames, fps),
        _wrist_rotation(_keyframed(times, wrist, n_frames, fps)),
        _keyframed(times, drift, n_frames, fps),
    )


#: The motions :func:`make_motion` knows, by name.
MOTIONS: dict[str, Callable[[int, float, np.random.Generator], Motion]] = {
    "clench": clench, "rapid": rapid, "wave": wave, "random": random_motion,
}


def make_motion(name: str, n_frames: int, fps: float = 30.0, seed: int = 0) -> Motion:
    """Generate the motion ``name`` over ``n_frames`` frames at ``fps``.

    Parameters
    ----------
    name
        One of :data:`MOTIONS`: ``clench``, ``rapid``, ``wave``, ``random``.
    n_frames
        Number of frames ``T`` (at least 2).
    fps
        Frames per second.
    seed
        Seed of the motion's random choices; equal seeds give equal motions.

    Returns
    -------
    Motion
    """
    if name not in MOTIONS:
        raise UnknownNameError("motion", str(name), tuple(MOTIONS))
    if n_frames < 2:
        raise ParameterError(f"n_frames must be at least 2, got {n_frames}")
    if not np.isfinite(fps) or fps <= 0:
        raise ParameterError(f"fps must be a positive number, got {fps}")
    return MOTIONS[name](int(n_frames), float(fps), np.random.default_rng(seed))
