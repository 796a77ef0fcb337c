# Type stub of the errfield extension module (src/python). Units: coordinates mm (task space) or
# deg (joint space), values mm, semivariances and variances mm^2, joints deg.
import os
from typing import Any, Literal, Sequence, overload

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]

class Error(RuntimeError): ...
class ArgumentError(Error, ValueError): ...
class InputError(Error, ValueError):
    file: str | None
    row: int | None
    column: str | None
class OutsideGridError(InputError): ...
class ResourceError(Error): ...

class EmpiricalVariogram:
    lag_lo: F64
    lag_hi: F64
    lag_mean: F64
    gamma: F64
    pairs: npt.NDArray[np.uint64]
    component_gamma: F64
    estimator: str
    convention: str
    pair_fraction: float
    def __len__(self) -> int: ...

def variogram(
    coords: ArrayLike,
    values: ArrayLike,
    bins: ArrayLike,
    estimator: Literal["matheron", "cressie", "dowd"] = "matheron",
    *,
    convention: Literal["paper", "gstat"] = "paper",
    pair_fraction: float = 1.0,
    seed: int = 0,
    threads: int = 0,
    covariates: ArrayLike | None = None,
) -> EmpiricalVariogram: ...

def variogram_cloud(
    coords: ArrayLike,
    values: ArrayLike,
    *,
    cutoff: float,
    max_pairs: int = 1000000,
) -> dict[str, Any]: ...
def variogram_map(
    coords: ArrayLike,
    values: ArrayLike,
    *,
    cutoff: float,
    width: tuple[float, float],
) -> dict[str, Any]: ...
def indicator_kriging(
    coords: ArrayLike,
    values: ArrayLike,
    targets: ArrayLike,
    thresholds: Sequence[float],
    models: VariogramModel | str | Sequence[VariogramModel | str],
    *,
    kind: str = "ordinary",
    backend: str | None = None,
    neighbors: int | None = None,
    radius: float | None = None,
    order_correction: bool = True,
) -> dict[str, Any]: ...
def cross_variogram(
    coords: ArrayLike,
    values: ArrayLike,
    bins: ArrayLike,
    *,
    convention: Literal["paper", "gstat"] = "paper",
    pair_fraction: float = 1.0,
    seed: int = 0,
    threads: int = 0,
) -> dict[str, Any]: ...
def fit_lmc(
    variogram: Any,
    model: str,
    *,
    method: Literal["goulard-voltz", "gstat"] = "goulard-voltz",
    weights: Literal["nj_h2", "nj", "unweighted"] = "nj_h2",
    nu: float | None = None,
    names: list[str] | None = None,
) -> dict[str, Any]: ...

class VariogramModel:
    def __init__(self, text: str) -> None: ...
    @staticmethod
    def parse(text: str) -> VariogramModel: ...
    @overload
    def gamma(self, h: float) -> float: ...
    @overload
    def gamma(self, h: ArrayLike) -> F64: ...
    @overload
    def __call__(self, h: float) -> float: ...
    @overload
    def __call__(self, h: ArrayLike) -> F64: ...
    @overload
    def covariance(self, h: float) -> float: ...
    @overload
    def covariance(self, h: ArrayLike) -> F64: ...
    @property
    def sill(self) -> float: ...
    @property
    def nugget(self) -> float: ...
    @property
    def bounded(self) -> bool: ...
    @property
    def compact(self) -> bool: ...
    @property
    def support(self) -> float: ...
    @property
    def components(self) -> list[dict[str, Any]]: ...

def fit_variogram(
    variogram: Any,
    model: str,
    *,
    weights: Literal["nj_h2", "nj", "cressie"] = "nj_h2",
    nugget: Literal["free", "none"] | float | None = "free",
    nu: float | None = None,
    range_max: float = 0.0,
    starts: int = 6,
) -> dict[str, Any]: ...
def fit_likelihood(
    coords: ArrayLike,
    values: ArrayLike,
    model: str,
    *,
    method: Literal["reml", "ml"] = "reml",
    kind: str = "ordinary",
    drift_order: int = 1,
    mean: float = 0.0,
    nugget: bool = True,
    nu: float | None = None,
    anisotropy: Literal["none", "ard", "rotated", "anis"] = "none",
    covariates: ArrayLike | None = None,
    likelihood: Literal["auto", "exact", "vecchia"] = "auto",
    vecchia_neighbours: int = 30,
    vecchia_ordering: Literal["maxmin", "random", "coordinate"] = "maxmin",
) -> dict[str, Any]: ...
def negative_log_likelihood(
    coords: ArrayLike,
    values: ArrayLike,
    model: VariogramModel,
    *,
    method: Literal["reml", "ml"] = "reml",
    kind: str = "ordinary",
    drift_order: int = 1,
    mean: float = 0.0,
    covariates: ArrayLike | None = None,
) -> float: ...

class CrossValidation:
    fold: npt.NDArray[np.int64]
    prediction: F64
    residual: F64
    variance: F64 | None
    samples: int
    predicted: int
    mean_error: F64
    mean_abs_error: float
    max_abs_error: float
    max_abs_index: int
    rms_error: float
    mean_z: float | None
    mean_squared_z: float | None

class Cokriging:
    def __init__(
        self,
        coords: ArrayLike,
        values: ArrayLike,
        model: str | dict[str, Any],
        *,
        kind: Literal["simple", "ordinary", "universal", "universal1", "universal2"] = "ordinary",
        backend: Literal["dense", "local"] | None = None,
        mean: float | Sequence[float] | None = None,
        drift_order: int | None = None,
        nugget: Literal["micro", "error"] = "micro",
        neighbors: int | None = None,
        radius: float | None = None,
        threads: int = 0,
        neighbour_metric: Literal["model", "euclidean"] | None = None,
        min_neighbours: int | None = None,
        octant_max: int | None = None,
    ) -> None: ...
    def predict(self, targets: ArrayLike) -> tuple[F64, F64, F64]: ...
    def cross_validate(self) -> tuple[F64, F64, F64]: ...
    @property
    def report(self) -> dict[str, Any]: ...

class Kriging:
    def __init__(
        self,
        coords: ArrayLike,
        values: ArrayLike,
        model: VariogramModel | str,
        *,
        kind: Literal["simple", "ordinary", "universal", "universal1", "universal2"] = "ordinary",
        backend: Literal["dense", "local", "sparse"] | None = None,
        mean: float | Sequence[float] | None = None,
        drift_order: int | None = None,
        nugget: Literal["micro", "error"] = "micro",
        neighbors: int | None = None,
        radius: float | None = None,
        measurement_variance: ArrayLike | None = None,
        duplicates: Literal["error", "average"] = "error",
        duplicate_distance: float = 0.0,
        threads: int = 0,
        neighbour_metric: Literal["model", "euclidean"] | None = None,
        covariates: ArrayLike | None = None,
        covariate_names: Sequence[str] | None = None,
        min_neighbours: int | None = None,
        octant_max: int | None = None,
    ) -> None: ...
    def predict(
        self,
        targets: ArrayLike,
        covariates: ArrayLike | None = None,
        *,
        block: ArrayLike | None = None,
        block_points: int = 4,
        block_rule: Literal["gauss", "regular"] = "gauss",
    ) -> tuple[F64, F64]: ...
    def cross_validate(self, folds: int | Literal["loo"] = "loo", seed: int = 1) -> CrossValidation: ...
    def simulate(
        self,
        targets: ArrayLike,
        n: int,
        *,
        seed: int = 1,
        method: Literal["auto", "cholesky", "sequential"] = "auto",
        neighbours: int = 60,
        draws_per_path: int = 100,
        covariates: ArrayLike | None = None,
    ) -> F64: ...
    @property
    def report(self) -> dict[str, Any]: ...
    @property
    def model(self) -> VariogramModel: ...

class ScatteredIdw:
    def __init__(
        self,
        coords: ArrayLike,
        values: ArrayLike,
        *,
        power: float | None = None,
        neighbors: int | None = None,
        radius: float | None = None,
        exact_distance: float = 0.0,
        threads: int = 0,
    ) -> None: ...
    def predict(self, targets: ArrayLike) -> F64: ...
    def cross_validate(self, folds: int | Literal["loo"] = "loo", seed: int = 1) -> CrossValidation: ...

class GridIdw:
    def __init__(self, coords: ArrayLike, values: ArrayLike, *, power: float = 1.0, clamp: bool = False,
                 threads: int = 0) -> None: ...
    def predict(self, targets: ArrayLike) -> F64: ...
    @property
    def grid(self) -> dict[str, Any]: ...

class IkSolution:
    q: F64
    ok: npt.NDArray[np.bool_]
    status: list[str]
    residual_mm: F64
    residual_deg: F64
    iterations: npt.NDArray[np.int64]

class Robot:
    @staticmethod
    def builtin(name: str = "er20_c10") -> Robot: ...
    @staticmethod
    def load(path: str | os.PathLike[str]) -> Robot: ...
    @staticmethod
    def from_json(text: str, source: str = "robot JSON") -> Robot: ...
    def to_json(self) -> str: ...
    def save(self, path: str | os.PathLike[str]) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def mdh(self) -> F64: ...
    @property
    def q_min(self) -> F64: ...
    @property
    def q_max(self) -> F64: ...
    @property
    def base(self) -> F64: ...
    @property
    def tool(self) -> F64: ...
    def with_tool(self, tool: ArrayLike) -> Robot: ...
    def with_base(self, base: ArrayLike) -> Robot: ...
    def within_limits(self, q: ArrayLike, slack_deg: float = 0.0) -> npt.NDArray[np.bool_]: ...
    def fk(self, q: ArrayLike, frame: Literal["tool", "flange"] = "tool") -> F64: ...
    def position(self, q: ArrayLike, frame: Literal["tool", "flange"] = "tool") -> F64: ...
    def jacobian(self, q: ArrayLike, frame: Literal["tool", "flange"] = "tool") -> F64: ...
    def identification_jacobian(self, q: ArrayLike) -> F64: ...
    @staticmethod
    def parameter_names() -> list[str]: ...
    def apply_parameter_increment(self, delta: ArrayLike) -> Robot: ...
    def ik(
        self,
        targets: ArrayLike,
        *,
        seed: ArrayLike | None = None,
        frame: Literal["tool", "flange"] = "tool",
        position_only: bool = False,
        max_iterations: int = 100,
    ) -> IkSolution: ...

def calibrate_positions(
    robot: Robot,
    q: ArrayLike,
    measured: ArrayLike,
    *,
    robust: bool = False,
    k0: float = 1.5,
    k1: float = 3.0,
    max_condition: float = 1e3,
) -> dict[str, Any]: ...
def calibrate_distances(
    robot: Robot | str | os.PathLike[str] | None,
    data: dict[str, Any],
    *,
    base_points: ArrayLike | None = None,
    robust: bool = False,
    k0: float = 1.5,
    k1: float = 3.0,
    max_condition: float = 1e3,
) -> dict[str, Any]: ...

# Robot pipeline (the CLI's fit / predict / compensate / validate). Columns: a dict of 1-D arrays
# named as the CLI's CSV columns (point, kind, q1..q6 deg, x,y,z mm, mx,my,mz mm, dist_bK mm);
# a pandas DataFrame works too. Results: dicts of NumPy arrays with the CLI's output column names.
Columns = dict[str, Any]
RobotLike = Robot | str | os.PathLike[str] | None

class CompensationModel:
    @staticmethod
    def load(path: str | os.PathLike[str]) -> CompensationModel: ...
    def save(self, path: str | os.PathLike[str]) -> None: ...
    def to_json(self) -> str: ...
    @property
    def method(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def is_robot_json(self) -> bool: ...
    fit_report: dict[str, Any] | None

def fit(
    data: Columns,
    *,
    robot: RobotLike = None,
    method: Literal["auto", "distance-idw", "position-idw", "distance-kriging", "vector-kriging", "kinematic",
                    "kinematic+kriging"] = "auto",
    space: Literal["auto", "task", "joint"] = "auto",
    power: float = 1.0,
    model: str | None = None,
    kind: Literal["ordinary", "universal1", "universal2"] = "ordinary",
    base: int = 0,
    base_points: ArrayLike | None = None,
    region_margin: float | None = None,
    calibration: Literal["position", "distance"] | None = None,
    robust: Literal["none", "igg3"] | None = None,
    max_condition: float = 1e3,
    max_registration_rms: float = 5.0,
    outlier_limit: float = 5.0,
    reflector_far_ok: bool = False,
    variance_calibration: Literal["auto", "loo", "none"] = "auto",
    joint_functions: int = -1,
) -> CompensationModel: ...
def predict(
    model: CompensationModel,
    joints: ArrayLike | Columns,
    *,
    tool: ArrayLike | None = None,
    joints_are_degrees: bool = False,
) -> dict[str, Any]: ...
def locate_tool(
    model: CompensationModel,
    data: Columns,
    *,
    min_orientations: int = ...,
    distinct_orientation: float = ...,
    not_rigid_factor: float = ...,
) -> tuple[CompensationModel, dict[str, Any]]: ...
def compensate(
    model: CompensationModel,
    targets: ArrayLike | Columns,
    *,
    robot: RobotLike = None,
    tolerance: float = 0.25,
    seed: ArrayLike | None = None,
    max_correction: float = 0.0,
    tool: ArrayLike | None = None,
    frame: Literal["robot", "tracker"] = "robot",
    joints_are_degrees: bool = False,
) -> dict[str, Any]: ...
def plan(
    candidates: ArrayLike | Columns,
    *,
    count: int,
    model: CompensationModel | None = None,
    measured: ArrayLike | Columns | None = None,
    target_rms: float | None = None,
    local_scale: bool = True,
    spacing_floor: float = 0.7,
) -> dict[str, Any]: ...
def validate(
    model: CompensationModel,
    data: Columns,
    *,
    robot: RobotLike = None,
    base_points: ArrayLike | None = None,
    targets: bool = False,
) -> dict[str, Any]: ...
