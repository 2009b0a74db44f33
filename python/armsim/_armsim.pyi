"""Type stubs of armsim's C++ core (python/armsim_module.cpp)."""
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

__version__: str

class Model:
    """An arm with its muscles (a model file of assets/models/ or your own)."""
    @staticmethod
    def load(name_or_file: Union[str, "os.PathLike[str]"]) -> Model: ...
    def __copy__(self) -> Model: ...
    def __deepcopy__(self, memo: Dict[int, Any]) -> Model: ...
    @property
    def name(self) -> str: ...
    @property
    def muscles(self) -> List[str]: ...
    @property
    def primary(self) -> str: ...
    def parameters(self, muscle: Optional[str] = None) -> Dict[str, Any]: ...
    def with_muscle(self, muscle: Optional[str] = None, **parameters: float) -> Model: ...
    def geometry(self, flexion_deg: List[float]) -> Dict[str, Array]: ...

def steady_state(model: Model, path_length: float, activation: float = 1.0,
                 muscle: Optional[str] = None) -> Dict[str, float]: ...
def muscle_trial(model: Model, path_length: float = 0.375, activation: float = 1.0, onset: float = 0.0,
                 rise: float = 0.0, duration: float = 3.0, rate: float = 1000.0, steady_start: bool = False,
                 muscle: Optional[str] = None) -> Dict[str, Array]: ...
def arm_trial(model: Model, angle_deg: float = 90.0, activation: float = 1.0, effort: str = "flexion",
              antagonist_activation: float = 0.0, rest: float = 0.5, rise: float = 0.0, hold: float = 3.0,
              rate: float = 1000.0, averaging_window: Optional[float] = None,
              rotation_deg: Optional[float] = None) -> Tuple[Dict[str, Array], Dict[str, Any]]: ...
def run_study(study_file: str, threads: int = 0, out: str = "", restart: bool = False) -> Dict[str, Any]: ...

def identify(model: Model, data: Union[str, "os.PathLike[str]", Mapping[str, Any]], method: str = "lm",
             free: Sequence[str] = ("mass", "optimal_tendon_length"),
             bounds: Optional[Mapping[str, Tuple[float, float]]] = None, start: Optional[Mapping[str, float]] = None,
             forward: str = "steady", estimate: str = "moment-arm", hold: float = 3.0, rate: float = 200.0,
             warm_start: bool = True, jobs: int = 2, force_sd: Optional[float] = None, noise: str = "absolute",
             multistart: int = 1, seed: int = 1, max_iterations: int = 200, tolerance: float = 0.1,
             subject: int = -1, out: Optional[Union[str, "os.PathLike[str]"]] = None) -> Dict[str, Any]: ...
def identify_torque(data: Union[str, "os.PathLike[str]", Mapping[str, Any]],
                    population: Optional[Union[str, "os.PathLike[str]"]] = None, noise_level: Optional[float] = None,
                    activation: Optional[float] = None, activation_sd: float = 0.02,
                    channels: Optional[Union[str, "os.PathLike[str]"]] = None, emg_crosstalk: float = 0.10,
                    free_slow_fraction: bool = False) -> List[Dict[str, Any]]: ...
def read_torque_data(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Array]: ...
def validate(model: Model, seeds: int = 1, seed: int = 1, noise: Sequence[float] = (0, 0.01, 0.02, 0.05),
             methods: Sequence[str] = (), forward: str = "corrected", estimate: str = "moment-arm",
             jobs: int = 2) -> Dict[str, Any]: ...
def validate_elbow(population: Optional[Union[str, "os.PathLike[str]"]] = None, subjects: int = 200, seed: int = 1,
                   noise: Optional[Sequence[float]] = None, activation_sd: float = 0.02,
                   angles: Optional[Sequence[float]] = None, repetitions: Optional[int] = None,
                   protocol: Optional[Union[str, "os.PathLike[str]"]] = None, free_slow_fraction: bool = False,
                   jobs: int = 2, truth_population: Optional[Union[str, "os.PathLike[str]"]] = None,
                   prior: Optional[Union[str, "os.PathLike[str]"]] = None) -> Tuple[Dict[str, Any], List[Dict[str, Any]]]: ...
def design_protocol(population: Optional[Union[str, "os.PathLike[str]"]] = None,
                    angles: Sequence[float] = (15, 30, 45, 60, 75, 90, 105, 120, 135),
                    levels: Optional[Sequence[float]] = None, extension: bool = True, trials: int = 15,
                    repetitions: int = 3, draws: int = 32, seed: int = 1, activation_sd: float = 0.02,
                    free_slow_fraction: bool = False, jobs: int = 2) -> Dict[str, Any]: ...
def run_protocol(file: Union[str, "os.PathLike[str]"], out: Optional[Union[str, "os.PathLike[str]"]] = None,
                 jobs: int = 2) -> Dict[str, Any]: ...
