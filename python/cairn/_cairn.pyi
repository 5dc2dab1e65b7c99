"""Type stubs of cairn._cairn (the C++ extension), re-exported by the cairn package.

Written by hand beside the bindings (python/src/*.cpp); python/tests/test_stubs.py checks that
every public name of the module is declared here and that nothing declared here is missing.
"""

import os
import typing
from typing import Any, Callable, Iterator, Literal, Mapping, Optional, Sequence, overload

import numpy
import numpy as np
import numpy.typing
import numpy.typing as npt

__version__: str

F64 = npt.NDArray[numpy.float64]
F32 = npt.NDArray[numpy.float32]
I64 = npt.NDArray[numpy.int64]
ArrayLike = npt.ArrayLike

class ParseError(ValueError):
    """Bad input: str() names the file, the line (or byte offset) and what was expected."""
    file: str
    line: int
    detail: str

# --- core: Lie groups -------------------------------------------------------------------------

class SO3:
    def __init__(self) -> None: ...
    @staticmethod
    def from_matrix(R: ArrayLike) -> SO3: ...
    @staticmethod
    def from_quaternion(xyzw: ArrayLike) -> SO3: ...
    @staticmethod
    def from_rpy(roll: float, pitch: float, yaw: float) -> SO3: ...
    @staticmethod
    def exp(phi: ArrayLike) -> SO3: ...
    def log(self) -> F64: ...
    def inverse(self) -> SO3: ...
    def matrix(self) -> F64: ...
    def quaternion(self) -> F64: ...
    def to_rpy(self) -> F64: ...
    def angle(self) -> float: ...
    def Adj(self) -> F64: ...
    @staticmethod
    def hat(phi: ArrayLike) -> F64: ...
    @staticmethod
    def vee(Phi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian(phi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian_inverse(phi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian(phi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian_inverse(phi: ArrayLike) -> F64: ...
    @overload
    def __mul__(self, other: SO3) -> SO3: ...
    @overload
    def __mul__(self, points: ArrayLike) -> F64: ...

class SE3:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, rotation: SO3 | ArrayLike, translation: ArrayLike) -> None: ...
    @staticmethod
    def from_matrix(T: ArrayLike) -> SE3: ...
    @staticmethod
    def exp(xi: ArrayLike) -> SE3: ...
    def log(self) -> F64: ...
    def inverse(self) -> SE3: ...
    def matrix(self) -> F64: ...
    def matrix3x4(self) -> F64: ...
    @property
    def rotation(self) -> SO3: ...
    @property
    def translation(self) -> F64: ...
    def Adj(self) -> F64: ...
    @staticmethod
    def hat(xi: ArrayLike) -> F64: ...
    @staticmethod
    def vee(Xi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian(xi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian_inverse(xi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian(xi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian_inverse(xi: ArrayLike) -> F64: ...
    @overload
    def __mul__(self, other: SE3) -> SE3: ...
    @overload
    def __mul__(self, points: ArrayLike) -> F64: ...

class SE2:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, x: float, y: float, theta: float) -> None: ...
    @staticmethod
    def from_matrix(T: ArrayLike) -> SE2: ...
    @staticmethod
    def exp(xi: ArrayLike) -> SE2: ...
    def log(self) -> F64: ...
    def inverse(self) -> SE2: ...
    def matrix(self) -> F64: ...
    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...
    @property
    def theta(self) -> float: ...
    @property
    def translation(self) -> F64: ...
    def Adj(self) -> F64: ...
    @staticmethod
    def hat(xi: ArrayLike) -> F64: ...
    @staticmethod
    def vee(Xi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian(xi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian(xi: ArrayLike) -> F64: ...
    @overload
    def __mul__(self, other: SE2) -> SE2: ...
    @overload
    def __mul__(self, point: ArrayLike) -> F64: ...

class Sim3:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, rotation: SO3, translation: ArrayLike, scale: float) -> None: ...
    @overload
    def __init__(self, T: SE3, scale: float = 1.0) -> None: ...
    @staticmethod
    def from_matrix(S: ArrayLike) -> Sim3: ...
    @staticmethod
    def exp(xi: ArrayLike) -> Sim3: ...
    def log(self) -> F64: ...
    def inverse(self) -> Sim3: ...
    def matrix(self) -> F64: ...
    @property
    def scale(self) -> float: ...
    @property
    def rotation(self) -> SO3: ...
    @property
    def translation(self) -> F64: ...
    def to_se3(self) -> SE3: ...
    def Adj(self) -> F64: ...
    @staticmethod
    def hat(xi: ArrayLike) -> F64: ...
    @staticmethod
    def vee(Xi: ArrayLike) -> F64: ...
    @staticmethod
    def left_jacobian(xi: ArrayLike) -> F64: ...
    @staticmethod
    def right_jacobian(xi: ArrayLike) -> F64: ...
    @overload
    def __mul__(self, other: Sim3) -> Sim3: ...
    @overload
    def __mul__(self, points: ArrayLike) -> F64: ...

# --- io: trajectories, pose graphs, point clouds, bags ----------------------------------------

class Trajectory:
    def __init__(self, poses: ArrayLike, times: Optional[ArrayLike] = None,
                 stamps_ns: Optional[ArrayLike] = None) -> None: ...
    @property
    def poses(self) -> F64: ...
    @property
    def stamps_ns(self) -> I64: ...
    @property
    def times(self) -> F64: ...
    @property
    def positions(self) -> F64: ...
    def has_times(self) -> bool: ...
    def __len__(self) -> int: ...

def read_trajectory(path: str, format: Optional[Literal["tum", "kitti", "euroc"]] = None,
                    times: str = "") -> Trajectory: ...
def write_trajectory(path: str, trajectory: Trajectory, format: Optional[Literal["tum", "kitti", "euroc"]] = None,
                     times: str = "") -> None: ...

class PoseGraph:
    @property
    def dimension(self) -> int: ...
    @property
    def ids(self) -> I64: ...
    @property
    def poses(self) -> F64: ...
    @property
    def edges(self) -> I64: ...
    @property
    def measurements(self) -> F64: ...
    @property
    def information(self) -> F64: ...
    @property
    def fixed(self) -> list[int]: ...
    @property
    def warnings(self) -> list[str]: ...

def read_graph(path: str, format: Optional[Literal["g2o", "toro"]] = None,
               information: Literal["project", "keep", "reject"] = "project") -> PoseGraph: ...
def write_graph(path: str, graph: PoseGraph, format: Optional[Literal["g2o", "toro"]] = None) -> None: ...

class PointCloud:
    def __init__(self, points: ArrayLike, intensity: Optional[ArrayLike] = None,
                 time_s: Optional[ArrayLike] = None, ring: Optional[ArrayLike] = None) -> None: ...
    @property
    def points(self) -> F32: ...
    @property
    def intensity(self) -> F32: ...
    @property
    def time_s(self) -> F32: ...
    @property
    def ring(self) -> npt.NDArray[numpy.uint16]: ...
    def __len__(self) -> int: ...

def read_point_cloud(path: str) -> PointCloud: ...
def write_point_cloud(path: str, cloud: PointCloud) -> None: ...

def bag_info(path: str) -> dict: ...
def read_bag_poses(path: str, topic: str) -> Trajectory: ...

class BagPointClouds:
    def __init__(self, path: str, topic: str) -> None: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[tuple[int, PointCloud]]: ...
    def __next__(self) -> tuple[int, PointCloud]: ...

# --- backend: pose-graph optimisation ---------------------------------------------------------

class OptimizeResult:
    @property
    def graph(self) -> PoseGraph: ...
    @property
    def summary(self) -> dict: ...
    @property
    def chi2(self) -> float: ...
    @property
    def f_chordal(self) -> float: ...
    @property
    def certified(self) -> Optional[bool]: ...

def optimize(graph: PoseGraph | str, *, init: Literal["auto", "file", "odometry", "chordal"] = "auto",
             solver: Literal["lm", "gn", "dogleg"] = "lm", objective: Literal["geodesic", "chordal"] = "geodesic",
             robust: Literal["none", "huber", "cauchy", "geman-mcclure", "gnc"] = "none", robust_scale: float = 1.0,
             max_iterations: int = 100, threads: int = 0, certify: bool = False, polish_geodesic: bool = False,
             covariance: Sequence[int] = (), progress: Optional[Callable[[dict], None]] = None) -> OptimizeResult: ...

# --- Evaluation (python/src/eval.cpp): evo's APE/RPE, the KITTI devkit's metric, alignment ---
# Trajectory is the class bound in io.cpp, defined elsewhere in this file.

class Alignment:
    """How an estimate was moved onto its reference: p_reference = scale * R @ p_estimate + t (Umeyama 1991 as evo's umeyama_alignment, or evo's align_origin)."""

    @property
    def method(self) -> typing.Literal["none", "se3", "sim3", "se2", "origin"]:
        """'se3' (evo -a), 'sim3' (-as), 'se2' (cairn's planar variant), 'origin' (--align_origin) or 'none'."""
    @property
    def R(self) -> numpy.typing.NDArray[numpy.float64]:
        """Rotation, 3 x 3 float64 (an exact rotation)."""
    @property
    def t(self) -> numpy.typing.NDArray[numpy.float64]:
        """Translation, shape (3,), metres."""
    @property
    def scale(self) -> float:
        """Scale factor; 1.0 unless 'sim3'."""
    @property
    def matrix(self) -> numpy.typing.NDArray[numpy.float64]:
        """[[scale * R, t], [0, 0, 0, 1]], 4 x 4 float64: evo's alignment_transformation (lie_algebra.sim3)."""
    @property
    def pairs_used(self) -> int:
        """Pose pairs the alignment was estimated from."""
    def apply(self, poses: numpy.typing.ArrayLike) -> numpy.typing.NDArray[numpy.float64]:
        """The poses (N x 4 x 4, or one 4 x 4) moved into the reference frame: rotation R @ R_pose, position scale * R @ p + t (evo's scale() then transform(); the rotation block is not scaled)."""

class Association:
    """Which reference pose pairs with which estimated pose (evo's sync.associate_trajectories, or by index without timestamps)."""

    @property
    def reference_indices(self) -> numpy.typing.NDArray[numpy.int64]:
        """Index into the reference of each pair, int64 array."""
    @property
    def estimate_indices(self) -> numpy.typing.NDArray[numpy.int64]:
        """Index into the estimate of each pair, int64 array."""
    @property
    def by_time(self) -> bool:
        """True when paired by timestamps, False when by index."""
    @property
    def max_pairs(self) -> int:
        """Poses of the shorter trajectory: the most pairs possible."""
    @property
    def size(self) -> int:
        """Number of pairs."""
    def __len__(self) -> int: ...

class _Statistics(typing.TypedDict):
    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    sse: float
    count: int

class ApeResult:
    """Absolute pose error per pose pair, as evo's APE metric (evo_ape)."""

    @property
    def errors(self) -> numpy.typing.NDArray[numpy.float64]:
        """Error of each pair, float64 array."""
    @property
    def statistics(self) -> _Statistics:
        """evo's statistics of errors: dict with rmse, mean, median, std (population), min, max, sse, and count."""
    @property
    def reference(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired reference poses, N x 4 x 4 float64."""
    @property
    def estimate(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired estimated poses after the alignment, N x 4 x 4 float64."""
    @property
    def alignment(self) -> Alignment:
        """The Alignment applied to the estimate (method 'none' if none)."""
    @property
    def association(self) -> Association:
        """How the poses were paired."""
    @property
    def pose_relation(self) -> str:
        """What was measured, evo's -r name: 'trans_part', 'angle_rad', 'angle_deg', 'rot_part' or 'full'."""
    @property
    def unit(self) -> str:
        """Unit of the errors: 'm', 'rad', 'deg', or '' (dimensionless)."""
    @property
    def times(self) -> numpy.typing.NDArray[numpy.float64]:
        """Time of each pair, seconds since the first paired reference stamp (the pair index without stamps)."""

class RpeResult:
    """Relative pose error per index pair, as evo's RPE metric (evo_rpe)."""

    @property
    def errors(self) -> numpy.typing.NDArray[numpy.float64]:
        """Error of each pair, float64 array."""
    @property
    def statistics(self) -> _Statistics:
        """evo's statistics of errors: dict with rmse, mean, median, std (population), min, max, sse, and count."""
    @property
    def reference(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired reference poses, N x 4 x 4 float64."""
    @property
    def estimate(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired estimated poses after the alignment, N x 4 x 4 float64."""
    @property
    def alignment(self) -> Alignment:
        """The Alignment applied to the estimate (method 'none' if none)."""
    @property
    def association(self) -> Association:
        """How the poses were paired."""
    @property
    def pose_relation(self) -> str:
        """What was measured, evo's -r name: 'trans_part', 'angle_rad', 'angle_deg', 'rot_part' or 'full'."""
    @property
    def unit(self) -> str:
        """Unit of the errors: 'm', 'rad', 'deg', or '' (dimensionless)."""
    @property
    def pairs(self) -> numpy.typing.NDArray[numpy.int64]:
        """Index pairs (i, j) into reference/estimate, N x 2 int64; errors[k] belongs to pairs[k]."""
    @property
    def times(self) -> numpy.typing.NDArray[numpy.float64]:
        """Time of each pair's second pose j (evo's delta_ids), seconds since the first paired reference stamp (the pose index without stamps)."""
    @property
    def pose_times(self) -> numpy.typing.NDArray[numpy.float64]:
        """Time of every paired pose (reference/estimate rows), as times."""

class _KittiSegments(typing.TypedDict):
    first_frame: numpy.typing.NDArray[numpy.int64]
    last_frame: numpy.typing.NDArray[numpy.int64]
    length_m: numpy.typing.NDArray[numpy.float64]
    rotation_error_rad_per_m: numpy.typing.NDArray[numpy.float64]
    translation_error_m_per_m: numpy.typing.NDArray[numpy.float64]
    speed_m_per_s: numpy.typing.NDArray[numpy.float64]

class _KittiPerLength(typing.TypedDict):
    length_m: numpy.typing.NDArray[numpy.float64]
    segments: numpy.typing.NDArray[numpy.int64]
    translation_error_m_per_m: numpy.typing.NDArray[numpy.float64]
    rotation_error_rad_per_m: numpy.typing.NDArray[numpy.float64]
    reported_by_devkit: numpy.typing.NDArray[numpy.bool_]

class KittiResult:
    """The KITTI odometry metric exactly as the official devkit (evaluate_odometry.cpp) computes it: segments of 100..800 m, errors per metre."""

    @property
    def segments(self) -> _KittiSegments:
        """The devkit's errors/NN.txt as a dict of arrays: first_frame, last_frame (int64), length_m, rotation_error_rad_per_m, translation_error_m_per_m, speed_m_per_s."""
    @property
    def per_length(self) -> _KittiPerLength:
        """Mean errors per nominal length (the devkit's NN_tl.txt / NN_rl.txt) as a dict of arrays: length_m, segments, translation_error_m_per_m, rotation_error_rad_per_m, reported_by_devkit (>= 3 segments)."""
    @property
    def translation_error_m_per_m(self) -> float:
        """t_err of the devkit's stats.txt: mean over all segments, m/m."""
    @property
    def rotation_error_rad_per_m(self) -> float:
        """r_err of the devkit's stats.txt: mean over all segments, rad/m."""
    @property
    def translation_error_percent(self) -> float:
        """t_err in %, as the KITTI benchmark table."""
    @property
    def rotation_error_deg_per_m(self) -> float:
        """r_err in deg/m, as the KITTI benchmark table."""
    @property
    def rotation_error_deg_per_100m(self) -> float:
        """r_err in deg/100 m."""
    @property
    def path_length_m(self) -> numpy.typing.NDArray[numpy.float64]:
        """Ground-truth path length at each paired frame, metres (accumulated in float, as the devkit)."""
    @property
    def reference(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired ground-truth poses, N x 4 x 4 float64."""
    @property
    def estimate(self) -> numpy.typing.NDArray[numpy.float64]:
        """The paired result poses, N x 4 x 4 float64 (never aligned: the metric is relative)."""
    @property
    def association(self) -> Association:
        """How the poses were paired."""

def ape(
    reference: Trajectory,
    estimate: Trajectory,
    *,
    pose_relation: typing.Literal["trans_part", "angle_rad", "angle_deg", "rot_part", "full"] = "trans_part",
    align: bool = False,
    correct_scale: bool = False,
    align_origin: bool = False,
    n_to_align: int = -1,
    t_max_diff: float = 0.01,
    t_offset: float = 0.0,
    by_index: bool = False,
) -> ApeResult:
    """Absolute pose error of estimate against reference, as evo_ape / evo.main_ape.ape: associate (by time, or by index without stamps), align, then the error of each pair under pose_relation, and evo's statistics.

    pose_relation: evo's -r: 'trans_part' (m, the ATE), 'angle_rad', 'angle_deg', 'rot_part', 'full'.
    align: SE(3) Umeyama alignment (evo -a); with correct_scale, Sim(3) (evo -as).
    align_origin: move the first estimated pose onto the first reference pose (evo --align_origin).
    n_to_align: align on the first n pairs only; -1 = all (evo --n_to_align).
    t_max_diff, t_offset: association tolerance and estimate time offset, seconds (evo --t_max_diff, --t_offset).
    by_index: pair by index even with timestamps (equal lengths needed; no evo flag).

    Raises ValueError (with cairn's message) for no common stamps, mismatched lengths, NaN, unsorted stamps, a degenerate alignment or an unknown name. Runs without the GIL.
    """

def rpe(
    reference: Trajectory,
    estimate: Trajectory,
    *,
    pose_relation: typing.Literal["trans_part", "angle_rad", "angle_deg", "rot_part", "full"] = "trans_part",
    delta: float = 1.0,
    delta_unit: typing.Literal["f", "m", "frames", "meters", "metres"] = "f",
    all_pairs: bool = False,
    rel_delta_tol: float = 0.1,
    pairs_from_reference: bool = False,
    align: bool = False,
    correct_scale: bool = False,
    align_origin: bool = False,
    n_to_align: int = -1,
    t_max_diff: float = 0.01,
    t_offset: float = 0.0,
    by_index: bool = False,
) -> RpeResult:
    """Relative pose error, as evo_rpe / evo.main_rpe.rpe: after association and optional alignment, index pairs (i, j) delta apart on the estimate, and the error of (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) under pose_relation.

    delta, delta_unit: pair distance in 'f' frames (a whole number) or 'm' metres of path (evo -d, -u).
    all_pairs: every overlapping pair instead of consecutive ones (evo --all_pairs).
    rel_delta_tol: with metres and all_pairs, accept |path - delta| <= delta * rel_delta_tol (evo's rel_delta_tol).
    pairs_from_reference: choose the pairs on the reference's path (evo --pairs_from_reference).
    The other keywords are those of ape(). Raises ValueError as ape() does, and when delta selects no pair.
    """

def kitti_metric(
    ground_truth: Trajectory,
    result: Trajectory,
    *,
    lengths_m: numpy.typing.ArrayLike = ...,
    step_frames: int = 10,
    frame_period_s: float = 0.1,
    t_max_diff: float = 0.01,
    t_offset: float = 0.0,
    by_index: bool = False,
) -> KittiResult:
    """The KITTI odometry metric as the official devkit computes it (evaluate_odometry.cpp): from every step_frames-th frame, segments of each length in lengths_m (default 100, 200, ..., 800) along the ground-truth path; errors per metre of nominal length. Poses pair by index (equal lengths), or by time when both trajectories have stamps (t_max_diff, t_offset, by_index as for ape()). frame_period_s only enters the speeds. Raises ValueError for bad options, mismatched lengths, or a ground truth shorter than the shortest length. Runs without the GIL."""

def align(
    reference: numpy.typing.ArrayLike,
    estimate: numpy.typing.ArrayLike,
    method: typing.Literal["se3", "sim3", "se2", "origin", "none"] = "se3",
    n: int = -1,
) -> Alignment:
    """The alignment of estimate onto reference (N x 4 x 4 arrays paired by index): 'se3' Umeyama (evo -a), 'sim3' with scale (evo -as), 'se2' rotation about z and x-y translation, 'origin' first pose onto first pose (evo --align_origin). n: estimate from the first n pairs, -1 = all (evo's n). Returns an Alignment; Alignment.apply(poses) moves poses. Raises ValueError for wrong shapes, unequal lengths or degenerate positions."""

def umeyama(
    x: numpy.typing.ArrayLike,
    y: numpy.typing.ArrayLike,
    with_scale: bool = False,
) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64], float]:
    """Umeyama's least-squares similarity (IEEE PAMI 1991), as evo.core.geometry.umeyama_alignment: x and y are m x n arrays of n points (m = 2 or 3, columns are points); returns (R, t, c) with y ~ c R x + t (c = 1.0 without with_scale). Raises ValueError for wrong shapes or degenerate (coincident, collinear) points."""

# --- The pipelines (python/src/lidar3d.cpp, slam2d.cpp, vslam.cpp) ---


_Path = str | os.PathLike[str]
_Setting = bool | int | float | str | Sequence[float]

# ---- 3D LiDAR SLAM ------------------------------------------------------------------------------

class LidarScanResult:
    """What LidarSlam.add_scan says about one scan (lidar3d::SlamScanResult)."""
    @property
    def time(self) -> float: ...
    @property
    def health(self) -> str:
        """'ok', 'degraded' or 'lost'."""
    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """T_world_scan, 4 x 4, as the odometry placed it."""
    @property
    def keyframe(self) -> bool: ...
    @property
    def degenerate_axis(self) -> str: ...
    @property
    def segment(self) -> int: ...
    @property
    def points_read(self) -> int: ...
    @property
    def points_in_range(self) -> int: ...
    @property
    def correspondences(self) -> int: ...
    @property
    def rms_m(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def iterations(self) -> int: ...
    @property
    def threshold_sigma_m(self) -> float: ...
    @property
    def point_times_unusable(self) -> bool: ...
    @property
    def local_map_points(self) -> int: ...
    @property
    def timings(self) -> dict[str, float]:
        """preprocess_s, register_s, map_s, total_s."""

class LidarSlam:
    """3D LiDAR SLAM as `cairn slam3d` runs it (lidar3d::LidarSlam with its SlamRun)."""
    def __init__(self, config: _Path | None = None, set: Mapping[str, _Setting] | None = None, *,
                 preset: str = "default", map_voxel_m: float = 0.25, imu: _Path | None = None,
                 imu_topic: str = "", imu_calibration: _Path = "", lidar_extrinsic: _Path = "",
                 imu_time_offset: float = 0.0) -> None: ...
    @property
    def has_imu(self) -> bool: ...
    @overload
    def add_scan(self, cloud: PointCloud, time: float) -> LidarScanResult: ...
    @overload
    def add_scan(self, points: npt.ArrayLike, time: float, point_times: npt.ArrayLike | None = None,
                 intensity: npt.ArrayLike | None = None, ring: npt.ArrayLike | None = None) -> LidarScanResult: ...
    def finish(self) -> None: ...
    def trajectory(self) -> npt.NDArray[np.float64]:
        """N x 4 x 4."""
    def times(self) -> npt.NDArray[np.float64]: ...
    def health(self) -> list[str]: ...
    def keyframe_poses(self) -> npt.NDArray[np.float64]: ...
    def keyframe_scans(self) -> npt.NDArray[np.int64]: ...
    def map_points(self) -> npt.NDArray[np.float32]:
        """M x 3, after finish(): map.ply of `cairn slam3d`."""
    @property
    def summary(self) -> dict[str, Any]: ...
    def report(self) -> dict[str, Any]: ...
    def config(self) -> dict[str, dict[str, Any]]: ...
    def save_map(self, path: _Path) -> None:
        """After finish(): the map for Localizer3d and `cairn localize3d --map` (`cairn slam3d --save-map`)."""
    @property
    def front_end(self) -> str: ...
    @property
    def finished(self) -> bool: ...
    @property
    def map_voxel_m(self) -> float: ...
    def __len__(self) -> int: ...

class Localizer3d:
    """Localisation in a saved 3D map, as `cairn localize3d` runs it; the map is never changed."""
    def __init__(self, map: _Path, *, confirmations: int = 2, threads: int = 0,
                 odometry_while_tracking: bool = False) -> None: ...
    @overload
    def add_scan(self, cloud: PointCloud, time: float) -> dict[str, Any]:
        """state, health, localised, pose (4 x 4 or None), relocalised, dead_reckoning, fitness, inlier_rmse_m,
        degenerate_axis, reason, total_s."""
    @overload
    def add_scan(self, points: ArrayLike, time: float, point_times: ArrayLike | None = None,
                 intensity: ArrayLike | None = None, ring: ArrayLike | None = None) -> dict[str, Any]: ...
    def report(self) -> dict[str, Any]: ...
    def trajectory(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """(K x 4 x 4 map-frame poses of the localised scans, K times): trajectory.tum."""
    def __len__(self) -> int: ...

class ScanSequence:
    """Scan files and their times, in the order `cairn slam3d` reads them."""
    @property
    def files(self) -> list[str]: ...
    @property
    def times(self) -> npt.NDArray[np.float64]: ...
    @property
    def times_from_file(self) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[tuple[str, float]]: ...

def scan_sequence(scans: _Path | Sequence[_Path], times: _Path | None = None, times_column: int = 1,
                  max_scans: int = 0) -> ScanSequence: ...

# ---- 2D LiDAR SLAM ------------------------------------------------------------------------------

class LaserScan:
    """One 2D laser record (io::LaserScan)."""
    def __init__(self, ranges: npt.ArrayLike, angle_min: float, angle_increment: float, time: float,
                 odometry: Sequence[float] | npt.ArrayLike | None = None, max_range: float | None = None) -> None: ...
    @property
    def tag(self) -> str: ...
    @property
    def time(self) -> float: ...
    @property
    def time_ns(self) -> int: ...
    @property
    def ranges(self) -> npt.NDArray[np.float32]: ...
    @property
    def angle_min(self) -> float: ...
    @property
    def angle_increment(self) -> float: ...
    @property
    def max_range(self) -> float | None: ...
    @property
    def odometry(self) -> npt.NDArray[np.float64]:
        """(x, y, theta) of the laser in the odometry frame."""
    @property
    def robot_odometry(self) -> npt.NDArray[np.float64]: ...
    @property
    def line(self) -> int: ...
    def __len__(self) -> int: ...

def read_carmen_log(path: _Path, lenient: bool = False, max_scans: int = 0) -> list[LaserScan]: ...

class Slam2dScanResult:
    @property
    def time(self) -> float: ...
    @property
    def time_ns(self) -> int: ...
    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """(x, y, theta)."""
    @property
    def health(self) -> str: ...
    @property
    def inlier_fraction(self) -> float: ...
    @property
    def degeneracy(self) -> float: ...
    @property
    def covariance(self) -> npt.NDArray[np.float64]: ...
    @property
    def keyframe(self) -> bool: ...
    @property
    def segment(self) -> int: ...

class OccupancyGrid:
    @property
    def probability(self) -> npt.NDArray[np.float64]:
        """H x W, row 0 at the lowest y; NaN where unobserved."""
    @property
    def origin(self) -> tuple[float, float]: ...
    @property
    def resolution_m(self) -> float: ...

class Slam2d:
    """2D LiDAR SLAM as `cairn slam2d` runs it (slam2d::Slam2d)."""
    def __init__(self, config: _Path | None = None, set: Mapping[str, _Setting] | None = None, *,
                 preset: str = "default") -> None: ...
    @overload
    def add_scan(self, scan: LaserScan) -> Slam2dScanResult: ...
    @overload
    def add_scan(self, ranges: npt.ArrayLike, angle_min: float, angle_increment: float, time: float,
                 odometry: Sequence[float] | npt.ArrayLike | None = None, max_range: float | None = None) -> Slam2dScanResult: ...
    def finish(self) -> None: ...
    def trajectory(self) -> npt.NDArray[np.float64]:
        """N x 3: x, y, theta."""
    def times(self) -> npt.NDArray[np.float64]: ...
    def health(self) -> list[str]: ...
    @property
    def current_health(self) -> str: ...
    def occupancy_grid(self, resolution_m: float | None = None) -> OccupancyGrid: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    def report(self) -> dict[str, Any]: ...
    def config(self) -> dict[str, dict[str, Any]]: ...

# ---- Visual SLAM --------------------------------------------------------------------------------

class CameraCalibration:
    fx: float
    fy: float
    cx: float
    cy: float
    k1: float
    k2: float
    p1: float
    p2: float
    k3: float
    width: int
    height: int
    baseline_m: float
    depth_units_per_m: float
    virtual_baseline_m: float
    def __init__(self, fx: float, fy: float, cx: float, cy: float, *, k1: float = 0.0, k2: float = 0.0,
                 p1: float = 0.0, p2: float = 0.0, k3: float = 0.0, width: int = 0, height: int = 0,
                 baseline_m: float = 0.0, depth_units_per_m: float = 0.0, virtual_baseline_m: float = 0.0) -> None: ...
    def problems(self) -> str: ...
    def implausibilities(self, width: int, height: int, stereo: bool) -> str: ...

def read_calibration_yaml(path: _Path) -> CameraCalibration: ...
def read_kitti_calibration(path: _Path) -> CameraCalibration: ...
def tum_calibration(name: str) -> CameraCalibration: ...

class ImageSequence:
    @property
    def kind(self) -> str: ...
    @property
    def layout(self) -> str: ...
    @property
    def folder(self) -> str: ...
    @property
    def calibration(self) -> CameraCalibration: ...
    @property
    def calibration_from_dataset(self) -> bool: ...
    @property
    def times(self) -> npt.NDArray[np.float64]: ...
    @property
    def images(self) -> list[str]: ...
    @property
    def right_images(self) -> list[str]: ...
    @property
    def depth_images(self) -> list[str]: ...
    @property
    def ground_truth_path(self) -> str: ...
    @property
    def notes(self) -> list[str]: ...
    def __len__(self) -> int: ...

def read_image_sequence(folder: _Path) -> ImageSequence: ...
def read_gray_image(path: _Path) -> npt.NDArray[np.uint8]: ...
def read_depth_image(path: _Path) -> npt.NDArray[np.uint16]: ...

class VisualFrameResult:
    @property
    def frame(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def tracked(self) -> bool: ...
    @property
    def health(self) -> str: ...
    @property
    def pose(self) -> npt.NDArray[np.float64]: ...
    @property
    def features(self) -> int: ...
    @property
    def stereo_points(self) -> int: ...
    @property
    def inliers(self) -> int: ...
    @property
    def inlier_ratio(self) -> float: ...
    @property
    def keyframe(self) -> bool: ...
    @property
    def relocalised(self) -> bool: ...
    @property
    def relocalisation_refused(self) -> bool:
        """A relocalisation candidate was refused (ambiguous, or too few inliers); the reason is in note."""
    @property
    def loop_closed(self) -> bool: ...
    @property
    def new_map(self) -> bool: ...
    @property
    def segment(self) -> int: ...
    @property
    def sigma_position_m(self) -> float: ...
    @property
    def note(self) -> str: ...
    @property
    def keypoints(self) -> npt.NDArray[np.float32]: ...
    @property
    def keypoint_states(self) -> npt.NDArray[np.int8]: ...
    @property
    def timings(self) -> dict[str, float]: ...

class VisualSlam:
    """Stereo, RGB-D or monocular visual SLAM as `cairn vslam` runs it (vslam::VisualSlam)."""
    def __init__(self, calibration: CameraCalibration, kind: str = "stereo", config: _Path | None = None,
                 set: Mapping[str, _Setting] | None = None, *, dataset: str = "folder",
                 vocabulary: _Path | None = None, imu: bool = False, T_imu_camera: ArrayLike | None = None,
                 imu_calibration: _Path | None = None) -> None: ...
    @staticmethod
    def localize_in(map: _Path, config: _Path | None = None, set: Mapping[str, _Setting] | None = None, *,
                    dataset: str = "folder", vocabulary: _Path | None = None) -> VisualSlam:
        """Localisation in a saved map (`cairn vslam --localize-in`): tracks, never adds to the map."""
        ...
    def save_map(self, path: _Path) -> None:
        """Writes the main map for localize_in (`cairn vslam --save-map`)."""
        ...
    @property
    def localization_only(self) -> bool: ...
    @overload
    def add_frame(self, image: npt.NDArray[np.uint8], time: float,
                  depth: npt.NDArray[np.uint16] | npt.NDArray[np.floating[Any]] | None = None) -> VisualFrameResult: ...
    @overload
    def add_frame(self, left: npt.NDArray[np.uint8], right: npt.NDArray[np.uint8], time: float) -> VisualFrameResult: ...
    def trajectory(self) -> npt.NDArray[np.float64]: ...
    def times(self) -> npt.NDArray[np.float64]: ...
    def keyframe_poses(self) -> npt.NDArray[np.float64]: ...
    def keyframe_frames(self) -> npt.NDArray[np.int64]: ...
    def frame_segments(self) -> list[int]: ...
    @property
    def main_segment(self) -> int: ...
    def map_points(self) -> npt.NDArray[np.float64]: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    def add_imu(self, time: float | ArrayLike, gyro: ArrayLike, accel: ArrayLike) -> None:
        """IMU readings (IMU frame, rad/s, m/s^2): one or N, in time order, before the frames they span."""
        ...
    @property
    def inertial(self) -> dict[str, Any]: ...
    def config(self) -> dict[str, dict[str, Any]]: ...
    @property
    def calibration(self) -> CameraCalibration: ...
    @property
    def kind(self) -> str: ...

def register(source: PointCloud, target: PointCloud, guess: Optional[ArrayLike] = None, *, global_: bool = False,
             method: Literal["gicp", "icp"] = "gicp", max_distance: float = 1.0) -> dict:
    """Registers source onto target as `cairn register` does; returns its --json dict."""
