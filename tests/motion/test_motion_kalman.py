"""Constant-velocity Kalman motion tracker (paper Sec. III-C, authors' Kalman_filter_tracking.m)."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.kalman import ConstantVelocityKalman, KalmanSettings

A = np.array([[1.0, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
H = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0]])
Q = np.diag([25.0, 10, 25, 10])  # paper Eq. for Q
R = np.diag([25.0, 25])  # paper Eq. for R


def _reference_run(first, measurements):
    """MATLAB vision.KalmanFilter written out: configure at frame 2 + correct, then predict (+ correct)."""
    x = np.array([first[0], 0.0, first[1], 0.0])
    p = np.eye(4) * 1e5

    def correct(x, p, z):
        k = p @ H.T @ np.linalg.inv(H @ p @ H.T + R)
        return x + k @ (z - H @ x), (np.eye(4) - k @ H) @ p

    x, p = correct(x, p, np.asarray(first, float))
    out = []
    for z in measurements:
        x, p = A @ x, A @ p @ A.T + Q
        if z is not None:
            x, p = correct(x, p, np.asarray(z, float))
        out.append(H @ x)
    return np.array(out), p


def test_paper_matrices():
    kf = ConstantVelocityKalman()
    kf.initialize((0.0, 0.0))
    np.testing.assert_array_equal(kf._kf.F, A)
    np.testing.assert_array_equal(kf._kf.H, H)
    np.testing.assert_array_equal(kf._kf.Q, Q)
    np.testing.assert_array_equal(kf._kf.R, R)
    assert KalmanSettings().initial_estimate_error == (1e5, 1e5)


def test_matches_written_out_filter_with_gaps():
    rng = np.random.default_rng(0)
    truth = np.array([[50 + 3 * t, 80 - 2 * t] for t in range(1, 25)], float)
    meas = [tuple(p + rng.normal(0, 2, 2)) for p in truth]
    for t in (8, 9, 10, 11, 17):  # motion tracker in use: prediction only
        meas[t] = None
    expected, p_ref = _reference_run((50.0, 80.0), meas)
    kf = ConstantVelocityKalman()
    np.testing.assert_allclose(kf.initialize((50.0, 80.0)), [50.0, 80.0], atol=1e-2)
    got = np.array([kf.step(None if z is None else np.array(z)) for z in meas])
    np.testing.assert_allclose(got, expected, atol=1e-9)
    np.testing.assert_allclose(kf.covariance, p_ref, rtol=1e-9)


def test_initial_correction_shrinks_position_variance():
    kf = ConstantVelocityKalman()
    kf.initialize((1.0, 2.0))
    # 1e5 prior and measurement variance 25 combine to 1 / (1 / 1e5 + 1 / 25)
    assert kf.covariance[0, 0] == pytest.approx(1.0 / (1.0 / 1e5 + 1.0 / 25.0))
    assert kf.covariance[1, 1] == pytest.approx(1e5)


def test_constant_velocity_is_learned_and_extrapolated():
    kf = ConstantVelocityKalman()
    kf.initialize((0.0, 0.0))
    for t in range(1, 15):
        kf.predict()
        kf.correct((4.0 * t, -1.0 * t))
    np.testing.assert_allclose(kf.velocity, [4.0, -1.0], atol=0.05)
    predicted = [kf.predict() for _ in range(3)]  # occlusion: three frames of prediction only
    np.testing.assert_allclose(predicted[-1], [4.0 * 17, -17.0], atol=0.5)


def test_reset_for_a_new_sequence():
    kf = ConstantVelocityKalman()
    kf.initialize((5.0, 5.0))
    kf.reset()
    assert not kf.initialized
    np.testing.assert_allclose(kf.initialize((50.0, 60.0)), [50.0, 60.0], atol=1e-2)
    np.testing.assert_allclose(kf.velocity, [0.0, 0.0])


def test_errors():
    kf = ConstantVelocityKalman()
    assert not kf.initialized
    with pytest.raises(InputError, match="before initialize"):
        kf.predict()
    with pytest.raises(InputError, match="finite"):
        kf.initialize((np.nan, 1.0))


def test_matches_filterpy_on_a_noisy_track():
    """Our numpy filter against filterpy's KalmanFilter (a second implementation, kept for this test only)."""
    filterpy = pytest.importorskip("filterpy.kalman")
    from rgbt_toolkit.motion.kalman import ConstantVelocityKalman

    rng = np.random.default_rng(3)
    ours = ConstantVelocityKalman()
    ours.initialize((5.0, -2.0))
    ref = filterpy.KalmanFilter(dim_x=4, dim_z=2)
    ref.F = np.array([[1.0, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
    ref.H = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0]])
    ref.Q, ref.R = np.diag([25.0, 10, 25, 10]), 25 * np.eye(2)
    ref.P, ref.x = np.diag([1e5, 1e5, 1e5, 1e5]), np.array([[5.0], [0], [-2.0], [0]])
    ref.update(np.array([[5.0], [-2.0]]))
    for k in range(40):
        z = np.array([5 + 3 * k, -2 + 0.5 * k]) + rng.normal(0, 4, 2)
        ref.predict()
        assert np.allclose(ours.predict(), ref.x[[0, 2], 0])
        if k % 7 != 3:  # some frames without a measurement (motion tracker in use)
            ref.update(z.reshape(2, 1))
            assert np.allclose(ours.correct(z), ref.x[[0, 2], 0])
    assert np.allclose(ours.covariance, ref.P)


def test_spread_is_the_predicted_measurements_standard_deviation():
    """After predict, ``spread`` is the innovation's standard deviation; at steady state it solves the filter's
    Riccati equation (SciPy's solver as the second implementation), and it grows while only predicting."""
    from scipy.linalg import solve_discrete_are

    prior = solve_discrete_are(A.T, H.T, Q, R)  # steady-state covariance after predict
    steady = np.sqrt(np.mean(np.diag(H @ prior @ H.T + R)))
    kf = ConstantVelocityKalman()
    kf.initialize((5.0, 5.0))
    spreads = []
    for k in range(40):
        kf.predict()
        spreads.append(kf.spread())
        kf.correct((5.0 + 2 * k, 5.0))
    assert spreads[0] > spreads[5] > spreads[-1] * 0.999
    assert spreads[-1] == pytest.approx(steady, rel=1e-6)
    assert 10.0 < spreads[-1] < 11.0  # the paper's Q and R: about 10.5 px per axis
    coasting = []
    for _ in range(3):  # motion mode: predictions without corrections
        kf.predict()
        coasting.append(kf.spread())
    assert coasting[0] == pytest.approx(spreads[-1]) and coasting[0] < coasting[1] < coasting[2]
