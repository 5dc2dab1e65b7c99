"""cairn.SO3 / SE3 / SE2 / Sim3 against formulas written here in numpy (Rodrigues, homogeneous
matrices), not against the C++ code they bind."""

import math

import numpy as np
import pytest

import cairn


def rodrigues(phi):
    angle = np.linalg.norm(phi)
    K = np.array([[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]])
    if angle < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + math.sin(angle) / angle * K + (1 - math.cos(angle)) / angle**2 * K @ K


def test_so3_exp_log_and_quaternion():
    phi = np.array([0.3, -0.2, 1.1])
    R = cairn.SO3.exp(phi)
    np.testing.assert_allclose(R.matrix(), rodrigues(phi), atol=1e-14)
    np.testing.assert_allclose(R.log(), phi, atol=1e-14)
    x, y, z, w = R.quaternion()
    angle = np.linalg.norm(phi)
    np.testing.assert_allclose([x, y, z], math.sin(angle / 2) * phi / angle, atol=1e-14)
    assert w == pytest.approx(math.cos(angle / 2), abs=1e-14)
    np.testing.assert_allclose(cairn.SO3.from_quaternion([x, y, z, w]).matrix(), R.matrix(), atol=1e-14)
    np.testing.assert_allclose((R * R.inverse()).matrix(), np.eye(3), atol=1e-14)


def test_se3_acts_on_points_as_its_matrix():
    T = cairn.SE3(cairn.SO3.exp([0.1, 0.2, -0.3]), [1.0, -2.0, 0.5])
    points = np.random.default_rng(1).normal(size=(50, 3))
    M = T.matrix()
    np.testing.assert_allclose(T * points, points @ M[:3, :3].T + M[:3, 3], atol=1e-14)
    np.testing.assert_allclose((T * T.inverse()).matrix(), np.eye(4), atol=1e-14)
    np.testing.assert_allclose(cairn.SE3.exp(T.log()).matrix(), M, atol=1e-14)
    np.testing.assert_allclose(cairn.SE3.from_matrix(M).matrix(), M, atol=1e-15)
    U = cairn.SE3.exp([0.3, 0.0, 0.1, 0.0, 0.2, 0.1])
    np.testing.assert_allclose((T * U).matrix(), M @ U.matrix(), atol=1e-14)
    # Adjoint: T exp(xi) T^-1 = exp(Adj xi).
    xi = np.array([0.1, -0.2, 0.3, 0.05, 0.02, -0.04])
    lhs = M @ cairn.SE3.exp(xi).matrix() @ np.linalg.inv(M)
    np.testing.assert_allclose(lhs, cairn.SE3.exp(T.Adj() @ xi).matrix(), atol=1e-13)


def test_se2_and_sim3():
    T = cairn.SE2(1.0, 2.0, 0.5)
    c, s = math.cos(0.5), math.sin(0.5)
    np.testing.assert_allclose(T.matrix(), [[c, -s, 1.0], [s, c, 2.0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(T * np.array([1.0, 0.0]), [1.0 + c, 2.0 + s], atol=1e-15)
    S = cairn.Sim3(cairn.SO3.exp([0.0, 0.0, 0.3]), [1.0, 0.0, 0.0], 2.0)
    p = np.array([1.0, 1.0, 1.0])
    np.testing.assert_allclose(S * p, 2.0 * rodrigues(np.array([0, 0, 0.3])) @ p + [1, 0, 0], atol=1e-14)
    np.testing.assert_allclose((S * S.inverse()).matrix(), np.eye(4), atol=1e-14)
    assert cairn.Sim3.exp(S.log()).scale == pytest.approx(2.0, rel=1e-14)


def test_wrong_shapes_are_value_errors():
    with pytest.raises(ValueError, match=r"\(3,\) or \(N, 3\)"):
        cairn.SE3() * np.zeros((4, 2))
    with pytest.raises(ValueError, match="unit norm"):
        cairn.SO3.from_quaternion([0.0, 0.0, 0.0, 2.0])
    with pytest.raises(TypeError):
        cairn.SE3.exp([1.0, 2.0])
