"""armsim: a musculoskeletal arm simulator with Virtual Muscle force elements.

Models, steady states, muscle and arm trials, simulations stepped on request (Simulation), protocols,
identification with its reports, validation, experiment design, population studies and rendering on
the C++ core, with numpy arrays out. Units are SI; keyword names are those of the YAML files, and for the command's options their long
names with underscores (--max-iterations: max_iterations; --speed is playback_speed). Errors carry
the command line's messages: ValueError for bad input, FileNotFoundError for a missing file,
RuntimeError for a simulation that cannot go on. Long calls release the GIL, so threads can run
trials in parallel, and Ctrl-C raises KeyboardInterrupt in them. Models and protocols are found in the
assets folder: ARMSIM_ASSETS if set, else the installed one (cmake --install) or the source tree's.

    import armsim
    model = armsim.Model.load("twin")
    series, summary = armsim.arm_trial(model, angle_deg=90, activation=1.0)
    sim = armsim.Simulation(model, angle_deg=120, excitation={"BRA": 0.3}); sim.advance_to(0.5)
    series, summary = armsim.isometric_trial("arm26", coordinate="r_elbow_flex", angle_deg=80)  # OpenSim
    report = armsim.identify(armsim.Model.load("thesis"), "measured/thesis_measured.csv")
    armsim.render_video(model, series, "mvc.mp4")
"""
import os as _os


def _use_installed_assets():
    """An installed package (cmake --install) reads its models from the prefix's assets folder, unless
    ARMSIM_ASSETS says otherwise; a package in the build tree finds the source tree's."""
    paths = _os.path.join(_os.path.dirname(__file__), "_install_paths.txt")
    if _os.environ.get("ARMSIM_ASSETS") or not _os.path.exists(paths):
        return
    with open(paths, encoding="utf-8") as f:
        for line in f:
            key, _, value = line.strip().partition("=")
            if key == "assets" and _os.path.isdir(value):
                _os.environ["ARMSIM_ASSETS"] = value


_use_installed_assets()

from ._armsim import (Model, arm_trial, design_protocol, forward, free_movement, identify, identify_torque, isometric_trial, muscle_trial,
                      read_torque_data, run_protocol, run_study, Simulation, steady_state, validate, validate_elbow, __version__)


def render_video(model, series, path, fps=30.0, width=1280, height=720, playback_speed=1.0, overlay=True,
                 codec="h264", supersample=2, color_by="activation"):
    """Renders a recorded trial (the series dict arm_trial returns; with an OpenSim model's name or
    .osim path as model, the series isometric_trial or free_movement returns) to an .mp4 (h264) or .avi (mjpg).

    Offscreen (OSMesa, no display). fps: video frames per second; playback_speed: trial seconds per
    video second; width, height: even, in [16, 4096]; color_by: 'activation' or 'force'. Written
    whole or not at all. Returns {'path', 'frames'}. Releases the GIL.
    """
    from . import _render  # the render stack loads on first use only
    path = _os.fspath(path) if isinstance(path, _os.PathLike) else path
    if isinstance(model, (str, _os.PathLike)):   # an OpenSim model (.osim path or shipped name): its trial's series
        if color_by != "activation":
            raise ValueError(f"color_by = {color_by!r}: an OpenSim model's muscles are coloured by activation")
        return _render.render_osim_video(model, series, path, fps, width, height, playback_speed, overlay, codec,
                                         supersample)
    return _render.render_video(model, series, path, fps, width, height, playback_speed, overlay, codec,
                                supersample, color_by)


def render_frame(model, series, time, width=640, height=360, overlay=True, supersample=2, color_by="activation"):
    """One frame of a recorded trial at the sample nearest to `time` [s] as an (H, W, 3) uint8 RGB array.

    The same pixels as the video's frame at that sample; show it with matplotlib's imshow.
    """
    from . import _render
    if isinstance(model, (str, _os.PathLike)):
        if color_by != "activation":
            raise ValueError(f"color_by = {color_by!r}: an OpenSim model's muscles are coloured by activation")
        return _render.render_osim_frame(model, series, time, width, height, overlay, supersample)
    return _render.render_frame(model, series, time, width, height, overlay, supersample, color_by)


__all__ = ["__version__", "Model", "arm_trial", "design_protocol", "forward", "free_movement", "identify", "identify_torque", "isometric_trial",
           "muscle_trial", "read_torque_data", "render_frame",
           "render_video", "run_protocol", "run_study", "Simulation", "steady_state", "validate", "validate_elbow"]
