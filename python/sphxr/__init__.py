"""sphxr: SPH water runs from Python (docs/user/python.md).

    import sphxr
    run = sphxr.Run("dam_break", set={"spacing": 0.005, "method": "dfsph"})
    run.run_to(0.1)                      # or run.step(100), run.run_scene()
    p = run.positions()                  # (N, 3) float32, in particle-id order
    print(run.summary()["mean_density_error"])

A run is built as `sphxr --headless` builds it: the same scene loader, the same --set overrides, the same
state files, the same app::Simulation; errors are sphxr.Error carrying the program's one-line message.
Sweeps over a grid of parameters on Dask distributed: `python3 -m sphxr.sweep --help`.
"""
import json
import numbers
import os

import numpy as np

from . import _sphxr
from ._sphxr import Error, set_log_level

__all__ = ["Run", "Error", "read_state", "set_log_level", "find_scene", "scene_dirs", "parameter_names", "scene_info",
           "data_dir", "show_text"]

_HERE = os.path.dirname(os.path.abspath(__file__))
# Installed, the package is PREFIX/lib/python3/dist-packages/sphxr and the scenes PREFIX/share/sphxr/scenes;
# in the build tree neither exists and the build's scenes (the source tree's) are found instead.
_PREFIX = os.path.normpath(os.path.join(_HERE, "..", "..", "..", ".."))
_INSTALLED_SCENES = os.path.join(_PREFIX, "share", "sphxr", "scenes")
_INSTALL_DIR = _INSTALLED_SCENES if os.path.isdir(_INSTALLED_SCENES) else ""


def data_dir():
    """The measured data the sweeps compare with (Martin & Moyce 1952, Buchner 2002): the installed copy,
    else the source tree's tests/data."""
    installed = os.path.join(_PREFIX, "share", "sphxr", "data")
    if os.path.isdir(installed):
        return installed
    return os.path.normpath(os.path.join(_sphxr.build_scenes_dir, "..", "tests", "data"))


def _path(name, path):
    """A file name given to the module as a str (os.fspath); sphxr.Error when it is none."""
    try:
        path = os.fspath(path)
    except TypeError:
        raise Error("%s: a file name is a str or a path, not %s" % (name, type(path).__name__)) from None
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    return path


def _number(name, value, integer=False):
    """`value` checked by the command line's bounds for `name` (app/run_arguments.h): a float, or an int
    where a whole number is wanted; sphxr.Error (one line) for anything else, NaN and infinities included."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise Error("%s %s: not a number" % (name, show_text(repr(value))))
    try:
        number = float(value)
    except OverflowError:  # an int past the largest float
        number = float("inf") if value > 0 else float("-inf")
    _sphxr.check_argument(name, number)
    return int(value) if integer else number


def show_text(text, max_bytes=80):
    """`text` as sphxr prints what a user wrote: control, bidi and other hidden characters escaped
    (\\x1B, \\u202E), cut after max_bytes with its length."""
    return _sphxr.show_text(str(text), max_bytes)


def read_state(path):
    """A state file's contents (sphxr --save-state, Run.save_state) without running it: path, scene,
    method, time, step, spacing, fluid, boundary, and the fluid's positions, velocities, densities,
    pressures and ids as NumPy arrays (in the file's order; `ids` gives each row's particle)."""
    return _sphxr.read_state(_path("read_state", path))


def find_scene(name):
    """The file a scene name stands for: NAME or NAME.json in the current directory, the installed scenes,
    then the build's (a path is returned as it is)."""
    return _sphxr.find_scene(_path("find_scene", name), _INSTALL_DIR)


def scene_info(scene, set=None):
    """A scene file read (not run): path, name, run_time, run_steps, run_settle, probe_columns (the
    --probes header, or None), dam_break_column_width (or None), parameters (with the overrides)."""
    return _sphxr.scene_info(_path("scene_info", scene), _INSTALL_DIR, _assignments(set))


def scene_dirs():
    """The folders find_scene looks in, in order."""
    return _sphxr.scene_dirs(_INSTALL_DIR)


def parameter_names():
    """The keys `set` takes (those of a scene's "solver" section, and reuse.*)."""
    return _sphxr.parameter_names()


def _assignments(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, (str, bytes)):  # one "key=value", as one --set (never its characters)
        overrides = [overrides]
    if isinstance(overrides, dict):
        items = overrides.items()
    else:  # "key=value" strings, as --set
        try:
            overrides = list(overrides)
        except TypeError:
            raise Error("set: a dict, a list of \"key=value\" or one \"key=value\", not %s"
                        % type(overrides).__name__) from None
        items = []
        for o in overrides:
            if isinstance(o, bytes):
                o = os.fsdecode(o)
            if not isinstance(o, str):
                raise Error("set: %s: an item is a \"key=value\" str" % show_text(repr(o)))
            items.append(o.split("=", 1) if "=" in o else (o, ""))
    out = []
    for key, value in items:
        if isinstance(value, bool):
            value = int(value)
        out.append("%s=%s" % (key, repr(value) if isinstance(value, float) else value))
    return out


def _scene_text(scene):
    """A dict scene as the JSON text the scene loader reads; nesting past the loader's limit is refused
    before json.dumps would recurse into it (the walk here is a loop)."""
    limit = _sphxr.max_scene_depth
    stack = [(scene, 1)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            raise Error("scene: a dict nested more than %d levels deep: not a scene" % limit)
        children = item.values() if isinstance(item, dict) else item if isinstance(item, (list, tuple)) else ()
        for child in children:
            if isinstance(child, (dict, list, tuple)):
                stack.append((child, depth + 1))
    try:
        return json.dumps(scene)
    except (TypeError, ValueError) as e:
        raise Error("scene: not a JSON scene: %s" % show_text(str(e))) from None


class Run:
    """One run of a scene.

    scene       a scene file's path, a scene's name ("stir": found as `sphxr --scene stir` finds it), or a
                dict in the scene file's format (docs/user/scenes.md), read by the same loader
    set         overrides as --set: {"spacing": 0.01, "method": "dfsph", "reuse.threshold": 0.8} or
                ["spacing=0.01", ...]; applied in order, after the scene
    device      "auto", "cpu", "cuda" or "cpu-reference"; threads: CPU threads (0: all cores)
    settle      seconds of settling before t = 0; None: the scene's run.settle, as `sphxr --headless`
    load_state  a state file to start from (sphxr --save-state, Run.save_state); its spacing is the run's
    probes_csv  the file the probe rows go to, as --probes (default: a temporary file, read by probes())
    base_dir    for a dict scene: the folder its relative paths (paddle trajectories) are read from
    record_dam_break  the surge front and column height after every step (default: for a dam-break scene)
    """

    def __init__(self, scene, set=None, device="cpu", threads=0, settle=None, load_state=None,
                 probes_csv=None, validate=False, base_dir=None, record_dam_break=None):
        o = _sphxr.RunOptions()
        if isinstance(scene, dict):
            o.scene_json = _scene_text(scene)
            name = scene.get("name", "scene") if isinstance(scene.get("name"), str) else "scene"
            folder = os.path.abspath(_path("base_dir", base_dir) if base_dir else os.getcwd())
            o.origin = os.path.join(folder, "<dict %s>" % show_text(name, 40))
        else:
            o.scene = _path("scene", scene)
        o.install_dir = _INSTALL_DIR
        o.sets = _assignments(set)
        if not isinstance(device, str):
            raise Error("device %s: must be auto, cpu or cuda (or cpu-reference)" % show_text(repr(device)))
        o.device = device
        o.threads = _number("threads", threads, integer=True)
        o.validate = bool(validate)
        o.settle = -1.0 if settle is None else _number("settle", settle)
        o.load_state = _path("load_state", load_state) if load_state else ""
        o.probes_csv = _path("probes_csv", probes_csv) if probes_csv else ""
        o.record_dam_break = -1 if record_dam_break is None else int(bool(record_dam_break))
        self._run = _sphxr.Run(o)

    # ---- stepping (the GIL is released; Ctrl-C stops after the step in progress: KeyboardInterrupt) ----
    def step(self, n=1):
        """n solver steps (0 to 2^40)."""
        self._run.step(_number("step", n, integer=True))
        return self

    def run_to(self, time):
        """Steps until the simulated clock reaches `time` (s, 0 to 1e6)."""
        self._run.run_to(_number("run_to", time))
        return self

    def advance(self, seconds):
        """Steps for `seconds` of simulated time from now (the clock stays within 1e6 s)."""
        seconds = _number("advance", seconds)
        target = self.time + seconds
        if target > _sphxr.max_run_time:
            raise Error("advance %r: the clock would pass %g s (it is at %.9g s)" % (seconds, _sphxr.max_run_time, self.time))
        return self.run_to(target)

    def run_scene(self):
        """The scene's own run: to its run.time (or run.steps), as `sphxr --headless` without --time."""
        self._run.run_scene()
        return self

    # ---- state ----
    def save_state(self, path):
        """Writes a state file (as --save-state): Run(scene, load_state=path) continues from it."""
        self._run.save_state(_path("save_state", path))

    @property
    def time(self):
        return self._run.time

    @property
    def steps(self):
        """Steps of the whole run (a state file's included), as the CSV files number them."""
        return self._run.steps

    @property
    def fluid_count(self):
        return self._run.fluid_count

    @property
    def boundary_count(self):
        return self._run.boundary_count

    @property
    def device(self):
        return self._run.device

    @property
    def scene_name(self):
        return self._run.scene_name

    @property
    def scene_path(self):
        return self._run.scene_path

    def parameters(self):
        """The solver's parameters as the run uses them (the scene's with the overrides)."""
        return self._run.parameters()

    # ---- fields (copies, in particle-id order) ----
    def particles(self):
        """All fields at once: positions (N, 3), velocities (N, 3), densities, pressures, ids."""
        return self._run.particles()

    def positions(self):
        return self._run.particles()["positions"]

    def velocities(self):
        return self._run.particles()["velocities"]

    def densities(self):
        return self._run.particles()["densities"]

    def pressures(self):
        return self._run.particles()["pressures"]

    # ---- measures ----
    def probes(self):
        """The scene's probes as --probes writes them: {"time": ..., "step": ..., "P1_p": ..., ...}, a row
        every probes.every s up to now (NaN where a sensor is dry). Raises sphxr.Error without probes."""
        columns, rows = self._run.probe_table()
        return {c: rows[:, k] for k, c in enumerate(columns)}

    def stats(self):
        """Per step: time, dt, max_speed, mean_density_error, max_density_error, active_fraction,
        density_iterations (NumPy arrays)."""
        return self._run.step_table()

    def dam_break(self):
        """For a dam-break scene: {"time", "T" = t sqrt(2g/a), "Z" = front / a, "H" = height / 2a} from the
        start (the Martin & Moyce units); None for other scenes or without record_dam_break."""
        a = self._run.dam_break_column_width
        table = self._run.dam_break_table()
        if a is None or len(table) == 0:
            return None
        g = float(np.linalg.norm(self._run.gravity))
        return {"time": table[:, 0], "T": table[:, 0] * np.sqrt(2.0 * g / a), "Z": table[:, 1], "H": table[:, 2]}

    def summary(self):
        """The summary's figures (as `sphxr --headless` prints them) as NumPy scalars."""
        return {k: np.float64(v) for k, v in self._run.summary().items()}

    def __repr__(self):
        return "<sphxr.Run %s: %d fluid particles, t = %.6g s, step %d, %s>" % (
            self.scene_name, self.fluid_count, self.time, self.steps, self.device)
