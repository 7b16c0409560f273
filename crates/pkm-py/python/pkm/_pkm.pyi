"""Type stubs of pkm's extension module. Arrays: float64, mm and rad (s for time)."""

import os
from typing import Any, Iterator, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]

class Error(Exception):
    """Base of every pkm error; `details` holds its structured fields."""
    details: dict[str, Any]

class MachineFileError(Error):
    """A machine file or dict that is not a valid machine."""
    file: str
    line: Optional[int]
    column: Optional[int]
    field: str
    reason: str

class InvalidInputError(Error):
    """A value that is not acceptable (shape, finiteness, range)."""
    what: str
    reason: str

class UnreachableError(Error):
    """A pose beyond the machine's limits."""
    violations: list[dict[str, Any]]

class NotAttainableError(Error):
    """A pose the mechanism cannot produce at all."""
    reason: str

class NotConvergedError(Error):
    """An iterative solver that did not converge."""
    solver: str
    iterations: int
    residual: float

class NotIdentifiableError(Error):
    """Measurements that cannot determine a parameter combination."""
    combination: str
    relative_singular_value: float

class SingularError(Error):
    """A singular configuration."""
    what: str
    rcond: float

class UnsupportedError(Error):
    """An analysis the machine type cannot run."""
    machine: str
    kind: str
    analysis: str
    reason: str

class IkBatch:
    """Inverse kinematics of N poses; unpacks as (actuators, reachable, limit)."""
    @property
    def actuators(self) -> F64: ...
    """(N, A) mm or rad; NaN rows without solution."""
    @property
    def reachable(self) -> npt.NDArray[np.bool_]: ...
    @property
    def limit(self) -> npt.NDArray[np.int32]: ...
    """Index into limit_names of the first violated limit; -1 where reachable."""
    @property
    def limit_names(self) -> list[str]: ...
    @property
    def limit_units(self) -> list[str]: ...
    @property
    def excess(self) -> F64: ...
    """By how much the first violated limit is crossed, in its unit (mm, deg)."""
    def messages(self) -> list[Optional[str]]: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[Any]: ...

class FkBatch:
    """Forward kinematics of N actuator sets; unpacks as (poses, solved, reachable)."""
    @property
    def poses(self) -> F64: ...
    @property
    def solved(self) -> npt.NDArray[np.bool_]: ...
    @property
    def reachable(self) -> npt.NDArray[np.bool_]: ...
    @property
    def iterations(self) -> npt.NDArray[np.uint32]: ...
    @property
    def residual(self) -> F64: ...
    @property
    def limit(self) -> npt.NDArray[np.int32]: ...
    @property
    def limit_names(self) -> list[str]: ...
    def messages(self) -> list[Optional[str]]: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[Any]: ...

class Machine:
    """A machine (immutable). Arrays in and out: mm and rad."""
    @staticmethod
    def from_toml(text: str, name: str = "<string>") -> Machine: ...
    @staticmethod
    def from_dict(d: dict[str, Any], name: str = "<dict>") -> Machine: ...
    @property
    def toml(self) -> Optional[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def pose_space(self) -> str: ...
    @property
    def coordinates(self) -> list[dict[str, str]]: ...
    @property
    def actuators(self) -> list[dict[str, Any]]: ...
    @property
    def driven(self) -> list[int]: ...
    @property
    def home(self) -> F64: ...
    @property
    def characteristic_length(self) -> float: ...
    @property
    def capabilities(self) -> dict[str, bool]: ...
    @property
    def parameters(self) -> list[dict[str, Any]]: ...
    def ik(
        self, poses: ArrayLike, check: bool = True, continuous: bool = False
    ) -> Union[tuple[F64, bool, Optional[str]], IkBatch]: ...
    """(P,) -> (actuators, reachable, message); (N, P) -> IkBatch."""
    def fk(
        self, q: ArrayLike, start: Optional[ArrayLike] = None
    ) -> Union[tuple[F64, dict[str, Any]], FkBatch]: ...
    """(A,) -> (pose, info); (N, A) -> FkBatch."""
    def jacobian(self, pose: ArrayLike) -> F64: ...
    """(A, P): actuator rates per pose-coordinate rates."""
    def condition(self, poses: ArrayLike) -> Union[float, F64]: ...
    def tool_pose(self, pose: ArrayLike) -> F64: ...
    """(P,) -> (4, 4) homogeneous transform (mm); (N, P) -> (N, 4, 4), NaN where none."""
    def check_limits(
        self, pose: ArrayLike, actuators: Optional[ArrayLike] = None
    ) -> list[dict[str, Any]]: ...
    def workspace(
        self,
        bounds: Optional[ArrayLike] = None,
        step: Optional[float] = None,
        orientation: Optional[ArrayLike] = None,
        tilt: Optional[float] = None,
    ) -> dict[str, Any]: ...
    def motion(
        self,
        gcode: Union[str, os.PathLike[str], None] = None,
        path: Optional[ArrayLike] = None,
        *,
        feed: Optional[float] = None,
        profile: str = "constant",
        acceleration: Optional[float] = None,
        jerk: Optional[float] = None,
        rapid: Optional[float] = None,
        rate: Optional[float] = None,
        points: Optional[int] = None,
        start: Optional[ArrayLike] = None,
        tool_length: Optional[float] = None,
        max_samples: int = 2_000_000,
        samples: bool = True,
    ) -> dict[str, Any]: ...
    def __reduce__(self) -> tuple[Any, tuple[str, str]]: ...
    def errors(
        self,
        pose: Optional[ArrayLike] = None,
        *,
        tolerances: Union[None, str, dict[str, Any]] = None,
        deviations: Optional[dict[str, float]] = None,
        monte_carlo: Optional[int] = None,
        seed: int = 1,
    ) -> dict[str, Any]: ...

def load(path: Union[str, os.PathLike[str]]) -> Machine: ...
def machine_types() -> list[tuple[str, str]]: ...
def simulate_measurements(
    machine: Machine,
    *,
    states: Optional[int] = None,
    holdout: int = 0,
    deviation: Optional[float] = None,
    point_noise: Optional[float] = None,
    length_noise: Optional[float] = None,
    design: str = "random",
    translation: Optional[float] = None,
    rotation: Optional[float] = None,
    condition_ratio: Optional[float] = None,
    step: Optional[float] = None,
    fixture_radius: Optional[float] = None,
    seed: int = 1,
) -> dict[str, Any]: ...
def calibrate(
    machine: Machine,
    measurements: Union[str, os.PathLike[str]],
    *,
    validation: Union[str, os.PathLike[str], None] = None,
    model: str = "pose",
    fix: Sequence[str] = ...,
    seed_procedure: bool = False,
) -> dict[str, Any]: ...
