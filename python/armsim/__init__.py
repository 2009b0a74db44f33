"""armsim: a musculoskeletal arm simulator with Virtual Muscle force elements.

Models, steady states, muscle and arm trials and population studies on the C++ core, with numpy
arrays out. Units are SI; parameter names are those of the YAML files. Errors carry the command
line's messages: ValueError for bad input, FileNotFoundError for a missing file, RuntimeError for a
simulation that cannot go on. Long calls release the GIL, so threads can run trials in parallel.

    import armsim
    model = armsim.Model.load("elbow")
    series, summary = armsim.arm_trial(model, angle_deg=90, activation=1.0)
"""
from ._armsim import Model, arm_trial, muscle_trial, run_study, steady_state

__all__ = ["Model", "arm_trial", "muscle_trial", "run_study", "steady_state"]
