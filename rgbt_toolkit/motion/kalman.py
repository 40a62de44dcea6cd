"""The motion tracker: a constant-velocity Kalman filter on the target centre (paper Sec. III-C, "Motion Tracker").

State ``(p_x, v_x, p_y, v_y)``, transition ``A`` with unit time step, measurement ``H`` picking the two positions,
``Q = diag(25, 10, 25, 10)`` and ``R = diag(25, 25)`` (the paper's matrices). The authors build it with MATLAB's
``configureKalmanFilter('ConstantVelocity', pos, [1e5 1e5], [25 10], 25)`` at frame 2: state ``(x, 0, y, 0)``,
covariance ``1e5 I``, followed at once by a correction with that same position. From frame 3 on each frame is a
prediction, followed by a correction with the appearance tracker's position unless the motion tracker is in use.

Positions are in camera-compensated coordinates (see
:class:`~rgbt_toolkit.motion.camera_motion.CameraShiftAccumulator`): the caller converts with ``to_stable`` before
and ``to_image`` after.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class KalmanSettings:
    """Noise parameters of the motion tracker (paper Sec. III-C; authors' ``getDefaultParameters.m``)."""

    motion_noise: tuple[float, float] = (25.0, 10.0)  # Q diagonal for (position, velocity) per axis
    measurement_noise: float = 25.0  # R = 25 I
    initial_estimate_error: tuple[float, float] = (1e5, 1e5)  # initial covariance for (position, velocity)


class LinearKalman:
    """The textbook linear Kalman filter (``x``, ``P``, ``F``, ``H``, ``Q``, ``R`` as in filterpy, whose
    ``KalmanFilter`` it replaces: importing filterpy pulls in scipy.stats and cost 2 s of every `rgbt track`'s
    start-up). The covariance update uses Joseph's form, as filterpy does, so results agree to rounding."""

    def __init__(self, F: np.ndarray, H: np.ndarray, Q: np.ndarray, R: np.ndarray, P: np.ndarray,
                 x: np.ndarray) -> None:
        self.F, self.H, self.Q, self.R = F, H, Q, R
        self.P, self.x = P.astype(float), x.astype(float).reshape(-1, 1)

    def predict(self) -> None:
        self.x = self.F @ self.x
        self.P = self.F @ self.P @ self.F.T + self.Q

    def update(self, z: np.ndarray) -> None:
        innovation = z.reshape(-1, 1) - self.H @ self.x
        s = self.H @ self.P @ self.H.T + self.R
        gain = self.P @ self.H.T @ np.linalg.inv(s)
        self.x = self.x + gain @ innovation
        i_kh = np.eye(self.P.shape[0]) - gain @ self.H
        self.P = i_kh @ self.P @ i_kh.T + gain @ self.R @ gain.T


def _position(value: np.ndarray, name: str) -> np.ndarray:
    pos = np.asarray(value, dtype=np.float64).reshape(-1)
    if pos.shape != (2,) or not np.all(np.isfinite(pos)):
        raise InputError(f"{name} must be a finite (x, y) pair, got {value!r}")
    return pos


class ConstantVelocityKalman:
    """Constant-velocity Kalman filter on ``(x, y)`` (a :class:`LinearKalman` with the paper's matrices).

    Examples
    --------
    >>> kf = ConstantVelocityKalman()
    >>> kf.initialize((10.0, 20.0))          # frame 2: configure, then correct with the same position
    array([10., 20.])
    >>> predicted = kf.predict()             # frame 3: predict, then correct with the appearance result
    >>> kf.correct((12.0, 21.0)).round(2)
    array([12., 21.])
    """

    def __init__(self, settings: KalmanSettings = KalmanSettings()) -> None:
        self.settings = settings
        self._kf: LinearKalman | None = None

    def reset(self) -> None:
        """Forget the state (a new sequence); :meth:`initialize` must be called again."""
        self._kf = None

    @property
    def initialized(self) -> bool:
        """True once :meth:`initialize` has been called."""
        return self._kf is not None

    def _filter(self) -> LinearKalman:
        if self._kf is None:
            raise InputError("the Kalman filter is used before initialize(position) (the authors start it at frame 2)")
        return self._kf

    def initialize(self, position: np.ndarray) -> np.ndarray:
        """Start the filter at ``position`` with zero velocity, then correct with it (authors' frame-2 step).

        Returns the corrected position (equal to ``position``).
        """
        pos = _position(position, "initial position")
        s = self.settings
        kf = LinearKalman(
            F=np.array([[1.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]]),
            H=np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]),
            Q=np.diag([s.motion_noise[0], s.motion_noise[1]] * 2),
            R=np.eye(2) * s.measurement_noise,
            P=np.diag([s.initial_estimate_error[0], s.initial_estimate_error[1]] * 2),
            x=np.array([pos[0], 0.0, pos[1], 0.0]))
        self._kf = kf
        return self.correct(pos)

    def predict(self) -> np.ndarray:
        """Advance one frame; returns the predicted position ``(x, y)``."""
        kf = self._filter()
        kf.predict()
        return self.position

    def correct(self, position: np.ndarray) -> np.ndarray:
        """Correct with a measured position; returns the corrected position ``(x, y)``."""
        kf = self._filter()
        kf.update(_position(position, "measured position").reshape(2, 1))
        return self.position

    def step(self, measurement: np.ndarray | None) -> np.ndarray:
        """One frame of the authors' ``Kalman_filter_tracking``: predict, then correct unless ``measurement`` is None.

        Returns the corrected position, or the prediction when there is no measurement (motion tracker in use).
        """
        predicted = self.predict()
        return predicted if measurement is None else self.correct(measurement)

    def spread(self) -> float:
        """How far (px, one standard deviation per axis) the next measurement may lie from the current estimate by
        the filter's own account: ``sqrt(mean(diag(H P H^T + R)))``. Read after :meth:`predict` it is the spread of
        the prediction, about 10.5 px at steady state with the paper's matrices."""
        kf = self._filter()
        innovation = kf.H @ kf.P @ kf.H.T + kf.R
        return float(np.sqrt(np.mean(np.diag(innovation))))

    @property
    def position(self) -> np.ndarray:
        """Current position estimate ``(x, y)``."""
        x = self._filter().x
        return np.array([x[0, 0], x[2, 0]])

    @property
    def velocity(self) -> np.ndarray:
        """Current velocity estimate ``(v_x, v_y)`` in pixels per frame."""
        x = self._filter().x
        return np.array([x[1, 0], x[3, 0]])

    @property
    def covariance(self) -> np.ndarray:
        """Current 4x4 state covariance (order ``p_x, v_x, p_y, v_y``)."""
        return self._filter().P.copy()
