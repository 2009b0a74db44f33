"""Type stubs of the armsim package (python/armsim/__init__.py)."""
import os
from typing import Any, Dict, Union

import numpy as np
import numpy.typing as npt

from ._armsim import (Model, arm_trial, design_protocol, forward, free_movement, identify, identify_torque, isometric_trial, muscle_trial,
                      read_torque_data, run_protocol, run_study, Simulation, steady_state, validate, validate_elbow, __version__)

def render_video(model: Union[Model, str, "os.PathLike[str]"], series: Dict[str, npt.NDArray[np.float64]],
                 path: Union[str, "os.PathLike[str]"], fps: float = 30.0,
                 width: int = 1280, height: int = 720, playback_speed: float = 1.0, overlay: bool = True,
                 codec: str = "h264", supersample: int = 2, color_by: str = "activation") -> Dict[str, Any]: ...
def render_frame(model: Union[Model, str, "os.PathLike[str]"], series: Dict[str, npt.NDArray[np.float64]], time: float, width: int = 640,
                 height: int = 360, overlay: bool = True, supersample: int = 2,
                 color_by: str = "activation") -> npt.NDArray[np.uint8]: ...
