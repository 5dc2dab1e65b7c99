"""cairn.ape / rpe / kitti_metric / align from Python against the numbers evo and the KITTI devkit
stored, as tests/eval/test_evo_reference.cpp and test_kitti_metric.cpp do in C++.

The expected values are read from evo's result archives (res_files/*.zip: stats.json and
error_array.npz, a single .npy despite its suffix) and from the devkit's output files at test
time; the TUM numbers are evo's, recomputed when the data was curated, as stored in
../shared/data/trajectories/README.md. None comes from cairn.
"""

import functools
import io
import json
import math
import pathlib
import zipfile

import numpy as np
import pytest

import cairn

EVO = pathlib.Path("trajectories/trajectories-evo-testdata")
DEVKIT = pathlib.Path("trajectories/kitti-devkit-reference/KITTI_00_ORB")

# The criterion: 1e-12 relative. Relative to what: the floating-point rounding of cairn
# and of evo's numpy differ by up to ~6e-13 of the error array's RMS on these files (the CLI
# measured 4.3e-13 m at most on KITTI 00 APE), which is up to 3.7e-12 relative to the smallest
# single errors (0.025-0.07 m). So every error-valued number must agree to 1e-12 of the larger of
# its own size and the array's RMS (a norm-wise relative error, as numpy's assert_allclose with
# atol), and sse to 1e-12 of itself. evo itself does not reproduce its archives bit for bit with
# another numpy (README.md, "Recomputation with current evo").
RTOL = 1e-12
STATISTICS = ("rmse", "mean", "median", "std", "min", "max")


@functools.lru_cache(maxsize=None)
def read(path: pathlib.Path, fmt: str) -> "cairn.Trajectory":
    """Each file is read once for the whole module (KITTI as written, unprojected, as evo)."""
    return cairn.read_trajectory(str(path), format=fmt)


def evo_archive(path: pathlib.Path):
    """stats.json and error_array of an evo result archive."""
    with zipfile.ZipFile(path) as archive:
        stats = json.loads(archive.read("stats.json"))
        errors = np.load(io.BytesIO(archive.read("error_array.npz")))
    assert isinstance(errors, np.ndarray) and errors.dtype == np.float64
    return stats, errors


def assert_close(actual: float, expected: float, scale: float, what: str) -> None:
    bound = RTOL * max(abs(expected), scale)
    assert abs(actual - expected) <= bound, f"{what}: cairn {actual!r} vs evo {expected!r} (bound {bound:.3g})"


def assert_statistics(statistics: dict, evo: dict) -> None:
    for key in STATISTICS:
        assert_close(statistics[key], evo[key], evo["rmse"], key)
    assert_close(statistics["sse"], evo["sse"], 0.0, "sse")


def assert_errors(errors: np.ndarray, evo_errors: np.ndarray, rmse: float) -> None:
    assert errors.shape == evo_errors.shape
    bound = RTOL * np.maximum(np.abs(evo_errors), rmse)
    worst = int(np.argmax(np.abs(errors - evo_errors) - bound))
    assert np.all(np.abs(errors - evo_errors) <= bound), (
        f"pair {worst}: cairn {errors[worst]!r} vs evo {evo_errors[worst]!r}")


@pytest.fixture
def kitti00(data):
    return read(data / EVO / "KITTI_00_gt.txt", "kitti"), read(data / EVO / "KITTI_00_ORB.txt", "kitti")


# ------------------------------------------------------------------------------------------------
# evo's archives and recomputations


def test_ape_kitti00_orb_se3_matches_evo_archive(data, kitti00):
    """evo_ape kitti KITTI_00_gt.txt KITTI_00_ORB.txt -a (translation part, SE(3) Umeyama)."""
    gt, orb = kitti00
    stats, evo_errors = evo_archive(data / EVO / "res_files/orb_ape.zip")
    ape = cairn.ape(gt, orb, align=True)
    assert evo_errors.shape == (4541,)
    assert_statistics(ape.statistics, stats)
    assert_errors(ape.errors, evo_errors, stats["rmse"])
    assert ape.statistics["count"] == 4541
    assert ape.pose_relation == "trans_part" and ape.unit == "m"
    assert not ape.association.by_time and len(ape.association) == 4541
    assert ape.alignment.method == "se3" and ape.alignment.scale == 1.0
    assert ape.reference.shape == ape.estimate.shape == (4541, 4, 4)
    assert ape.times.shape == (4541,)


def test_rpe_kitti00_orb_10m_consecutive_matches_evo_archive(data, kitti00):
    """evo_rpe kitti KITTI_00_gt.txt KITTI_00_ORB.txt -d 10 -u m (consecutive pairs, not aligned)."""
    gt, orb = kitti00
    stats, evo_errors = evo_archive(data / EVO / "res_files/orb_rpe.zip")
    rpe = cairn.rpe(gt, orb, delta=10.0, delta_unit="m")
    assert evo_errors.shape == (353,)
    assert_statistics(rpe.statistics, stats)
    assert_errors(rpe.errors, evo_errors, stats["rmse"])
    assert rpe.alignment.method == "none"
    assert rpe.pairs.shape == (353, 2) and rpe.pairs.dtype == np.int64
    # Consecutive pairs: each pair starts where the previous one ended.
    np.testing.assert_array_equal(rpe.pairs[1:, 0], rpe.pairs[:-1, 1])
    assert rpe.times.shape == (353,)


def test_rpe_is_invariant_under_se3_alignment(data, kitti00):
    """An SE(3) alignment cannot change a relative error: the aligned RPE is evo's unaligned one."""
    gt, orb = kitti00
    stats, evo_errors = evo_archive(data / EVO / "res_files/orb_rpe.zip")
    rpe = cairn.rpe(gt, orb, delta=10.0, delta_unit="m", align=True)
    assert rpe.alignment.method == "se3"
    assert_statistics(rpe.statistics, stats)
    assert_errors(rpe.errors, evo_errors, stats["rmse"])


# README.md, "Recomputation with current evo": APE translation part, SE(3) Umeyama, evo's time
# association with t_max_diff 0.01 s (evo commit 26d0953). No archive exists for these pairs.
TUM_CASES = {
    "fr1_xyz": ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt", 785, 788, dict(
        rmse=0.013470088849733684, mean=0.012024498709110232, median=0.011183186775061124,
        std=0.006070809205890603, min=0.0009550461813177855, max=0.03475954589500919, sse=0.14243298549147998)),
    "fr2_desk": ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt", 2174, 2893, dict(
        rmse=0.008118977562044912, mean=0.007491776870216138, median=0.0074146298293169075,
        std=0.0031290695070393085, min=0.00034963619840676515, max=0.024299593694384707, sse=0.14330528992359753)),
}


@pytest.mark.parametrize("case", sorted(TUM_CASES))
def test_tum_ape_associates_by_time_and_matches_evo(data, case):
    reference_file, estimate_file, pairs, max_pairs, evo_stats = TUM_CASES[case]
    ape = cairn.ape(read(data / EVO / reference_file, "tum"), read(data / EVO / estimate_file, "tum"), align=True)
    assert ape.association.by_time
    assert len(ape.association) == pairs and ape.association.max_pairs == max_pairs
    assert ape.association.reference_indices.shape == ape.association.estimate_indices.shape == (pairs,)
    assert_statistics(ape.statistics, evo_stats)
    assert ape.statistics["count"] == pairs
    assert ape.times[0] == 0.0 and np.all(np.diff(ape.times) >= 0)


# ------------------------------------------------------------------------------------------------
# The KITTI devkit's own output (kitti-devkit-reference/, run on the same files)

# The devkit prints with %f: a value agrees when it rounds to the printed one.
PRINTED = 5e-7 + 1e-12


def test_kitti_metric_kitti00_orb_matches_devkit_output(data, kitti00):
    gt, orb = kitti00
    devkit = np.loadtxt(data / DEVKIT / "errors_00.txt", ndmin=2)  # first_frame r_err t_err length speed
    kitti = cairn.kitti_metric(gt, orb)
    segments = kitti.segments
    assert devkit.shape == (3283, 5) and segments["first_frame"].shape == (3283,)
    np.testing.assert_array_equal(segments["first_frame"], devkit[:, 0].astype(np.int64))
    np.testing.assert_array_equal(segments["length_m"], devkit[:, 3])
    np.testing.assert_allclose(segments["rotation_error_rad_per_m"], devkit[:, 1], rtol=0, atol=PRINTED)
    np.testing.assert_allclose(segments["translation_error_m_per_m"], devkit[:, 2], rtol=0, atol=PRINTED)
    np.testing.assert_allclose(segments["speed_m_per_s"], devkit[:, 4], rtol=0, atol=PRINTED)

    t_err, r_err = np.loadtxt(data / DEVKIT / "stats.txt")
    assert abs(kitti.translation_error_m_per_m - t_err) <= PRINTED
    assert abs(kitti.rotation_error_rad_per_m - r_err) <= PRINTED
    assert kitti.translation_error_percent == pytest.approx(100 * kitti.translation_error_m_per_m, rel=1e-15)
    assert kitti.rotation_error_deg_per_m == pytest.approx(math.degrees(kitti.rotation_error_rad_per_m), rel=1e-15)

    tl = np.loadtxt(data / DEVKIT / "plot_error/00_tl.txt")
    rl = np.loadtxt(data / DEVKIT / "plot_error/00_rl.txt")
    per_length = kitti.per_length
    np.testing.assert_array_equal(per_length["length_m"], tl[:, 0])
    assert per_length["reported_by_devkit"].all()
    np.testing.assert_allclose(per_length["translation_error_m_per_m"], tl[:, 1], rtol=0, atol=PRINTED)
    np.testing.assert_allclose(per_length["rotation_error_rad_per_m"], rl[:, 1], rtol=0, atol=PRINTED)


# ------------------------------------------------------------------------------------------------
# Alignment against a transform we chose


def random_poses(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    poses = np.tile(np.eye(4), (n, 1, 1))
    for k in range(n):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        poses[k, :3, :3] = q * np.sign(np.linalg.det(q))
        poses[k, :3, 3] = rng.uniform(-10, 10, size=3)
    return poses


def rotation(axis, angle: float) -> np.ndarray:
    """Rodrigues' formula: the rotation by angle (rad) about axis."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def test_align_sim3_recovers_the_similarity_that_made_the_reference():
    estimate = random_poses(50, seed=7)
    R, t, scale = rotation([1.0, 2.0, -0.5], 0.9), np.array([1.0, -2.0, 3.0]), 2.5
    reference = estimate.copy()
    reference[:, :3, :3] = R @ estimate[:, :3, :3]
    reference[:, :3, 3] = scale * estimate[:, :3, 3] @ R.T + t

    alignment = cairn.align(reference, estimate, method="sim3")
    np.testing.assert_allclose(alignment.R, R, atol=1e-12)
    np.testing.assert_allclose(alignment.t, t, atol=1e-11)
    assert alignment.scale == pytest.approx(scale, rel=1e-12)
    np.testing.assert_allclose(alignment.matrix[:3, :3], scale * R, atol=1e-11)
    assert alignment.pairs_used == 50
    np.testing.assert_allclose(alignment.apply(estimate), reference, atol=1e-11)
    np.testing.assert_allclose(alignment.apply(estimate[3]), reference[3], atol=1e-11)

    x = estimate[:, :3, 3].T
    R_u, t_u, c_u = cairn.umeyama(x, reference[:, :3, 3].T, True)
    np.testing.assert_allclose(R_u, R, atol=1e-12)
    np.testing.assert_allclose(t_u, t, atol=1e-11)
    assert c_u == pytest.approx(scale, rel=1e-12)


def test_align_origin_puts_the_first_poses_together():
    estimate = random_poses(5, seed=3)
    reference = random_poses(5, seed=4)
    alignment = cairn.align(reference, estimate, method="origin")
    assert alignment.method == "origin" and alignment.pairs_used == 1
    np.testing.assert_allclose(alignment.apply(estimate[0]), reference[0], atol=1e-12)


def test_ape_with_sim3_alignment_of_a_scaled_copy_is_zero():
    reference = random_poses(20, seed=11)
    estimate = reference.copy()
    estimate[:, :3, 3] *= 0.5
    ape = cairn.ape(cairn.Trajectory(reference), cairn.Trajectory(estimate), align=True, correct_scale=True)
    assert ape.alignment.method == "sim3" and ape.alignment.scale == pytest.approx(2.0, rel=1e-12)
    assert ape.statistics["max"] < 1e-12


# ------------------------------------------------------------------------------------------------
# Bad input: ValueError with a message that says what was wrong


def test_wrong_array_shapes_name_the_argument():
    poses = random_poses(4, seed=1)
    with pytest.raises(ValueError, match=r"^reference: expected an array of shape \(N, 4, 4\), found \(4, 3, 4\)"):
        cairn.align(poses[:, :3, :], poses)
    with pytest.raises(ValueError, match=r"^estimate: expected an array of shape \(N, 4, 4\)"):
        cairn.align(poses, poses.reshape(4, 16))
    with pytest.raises(ValueError, match=r"^poses: "):
        cairn.align(poses, poses).apply(np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"^x: expected an array of shape \(m, n\)"):
        cairn.umeyama(np.zeros(3), np.zeros((3, 1)), False)
    with pytest.raises(ValueError, match=r"x and y must have the same shape"):
        cairn.umeyama(np.zeros((3, 4)), np.zeros((3, 5)), False)
    with pytest.raises(ValueError, match=r"^lengths_m: expected a 1-D array"):
        cairn.kitti_metric(cairn.Trajectory(poses), cairn.Trajectory(poses), lengths_m=np.ones((2, 2)))


def test_mismatched_lengths_without_stamps_raise_cairns_message():
    poses = random_poses(6, seed=2)
    with pytest.raises(ValueError,
                       match=r"needs equal lengths: the reference has 6 poses, the estimate 5.*\[size mismatch\]"):
        cairn.ape(cairn.Trajectory(poses), cairn.Trajectory(poses[:5]))
    with pytest.raises(ValueError, match=r"alignment needs paired poses: 6 reference and 5 estimated"):
        cairn.align(poses, poses[:5])


def test_no_common_timestamps_raise_cairns_message():
    poses = random_poses(6, seed=2)
    times = np.arange(6, dtype=float)
    reference = cairn.Trajectory(poses, times=times)
    estimate = cairn.Trajectory(poses, times=times + 100.0)
    with pytest.raises(ValueError, match=r"no timestamps match between the reference .*\[no overlapping timestamps\]"):
        cairn.rpe(reference, estimate)
    # evo's t_offset moves the estimate's stamps back onto the reference's.
    assert len(cairn.ape(reference, estimate, t_offset=-100.0).association) == 6


def test_unknown_names_list_the_valid_ones():
    trajectory = cairn.Trajectory(random_poses(6, seed=5))
    with pytest.raises(ValueError, match=r"pose_relation: unknown name 'translation'; expected one of "
                                         r"'trans_part', 'angle_rad', 'angle_deg', 'rot_part', 'full'"):
        cairn.ape(trajectory, trajectory, pose_relation="translation")
    with pytest.raises(ValueError, match=r"delta_unit: unknown unit 'd'; expected 'f' \(frames\) or 'm'"):
        cairn.rpe(trajectory, trajectory, delta_unit="d")
    with pytest.raises(ValueError,
                       match=r"method: unknown alignment 'rigid'; expected one of 'se3', 'sim3', 'se2', 'origin'"):
        cairn.align(random_poses(3, seed=1), random_poses(3, seed=2), method="rigid")


def test_evaluation_options_cairn_cannot_honour_are_refused():
    trajectory = cairn.Trajectory(random_poses(6, seed=5))
    with pytest.raises(ValueError, match=r"align_origin cannot be combined with align"):
        cairn.ape(trajectory, trajectory, align=True, align_origin=True)
    with pytest.raises(ValueError, match=r"correct_scale without align is evo's scale-only correction"):
        cairn.ape(trajectory, trajectory, correct_scale=True)
    with pytest.raises(ValueError, match=r"n_to_align must be -1 \(all pairs\) or >= 1, found 0"):
        cairn.ape(trajectory, trajectory, align=True, n_to_align=0)
    with pytest.raises(ValueError, match=r"delta in frames must be a whole number.*\[invalid options\]"):
        cairn.rpe(trajectory, trajectory, delta=1.5)
    with pytest.raises(ValueError, match=r"selects no pose pair among 6 paired poses.*\[no pairs\]"):
        cairn.rpe(trajectory, trajectory, delta=6)
    with pytest.raises(ValueError, match=r"shorter than the shortest segment.*\[no pairs\]"):
        cairn.kitti_metric(trajectory, trajectory)


def test_degenerate_alignment_is_a_value_error():
    poses = np.tile(np.eye(4), (5, 1, 1))
    poses[:, 0, 3] = np.arange(5.0)  # all positions on the x axis: the rotation about it is free
    with pytest.raises(ValueError, match=r"degenerate point covariance.*\[degenerate\]"):
        cairn.align(poses, poses, method="se3")
    with pytest.raises(ValueError, match=r"\[degenerate\]"):
        cairn.ape(cairn.Trajectory(poses), cairn.Trajectory(poses), align=True)
