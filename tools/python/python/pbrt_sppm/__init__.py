"""pbrt-sppm from Python: load pbrt-v3/v4 scenes, check them, trace rays against them,
render them with SPPM, VCM or BDPT, and compare images, with NumPy arrays throughout.

    import pbrt_sppm
    scene = pbrt_sppm.load("scene.pbrt")
    image = scene.render(spp=16, seed=1)            # float32, (height, width, 3)
    ref = pbrt_sppm.read_image("reference.exr")
    print(pbrt_sppm.relmse(image, ref))

Everything here is the command line's work (`pbrt-sppm render`, `check --json`,
`trace`, `pbrt-imgtool diff` and `tiles`) without processes or files in between.
"""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _native

__all__ = [
    "SceneError",
    "Scene",
    "load",
    "read_image",
    "read_buckets",
    "write_image",
    "diff",
    "relmse",
    "tiles",
    "__version__",
]
__version__ = _native.__version__


class SceneError(ValueError):
    """A scene that cannot be loaded: ``str(e)`` is ``file:line:col: error: message``,
    as ``pbrt-sppm`` prints it; ``file``, ``line`` and ``column`` locate it (``line``
    and ``column`` are None for a problem with a whole file, such as a missing one)."""

    def __init__(self, message: str, file: str, line: Optional[int], column: Optional[int]):
        self.message, self.file, self.line, self.column = message, file, line, column
        at = file if line is None else f"{file}:{line}:{column}"
        super().__init__(f"{at}: error: {message}")


PathOrText = Union[str, "os.PathLike[str]"]


def load(
    source: PathOrText,
    syntax: Optional[str] = None,
    *,
    fix: Union[None, str, Sequence[str]] = None,
    limits: Optional[dict] = None,
    colour: Optional[str] = None,
) -> "Scene":
    """Loads a scene from a file path (a str naming an existing file, or any
    os.PathLike) or from the scene's text (a str that is not a file name).

    syntax: "v3" or "v4" to override detection. fix: pbrt bugs to fix (names, or
    "all"), as ``--fix``. limits: {"pixels": N, ...} as ``--limit NAME=N``.
    colour: "spectral" or "rgb" for what paths carry, as ``--colour``.
    Raises SceneError with the file, line and column of the problem."""
    if isinstance(source, os.PathLike):
        path, text = os.fspath(source), False
    elif isinstance(source, str):
        # A name of a file that does not exist stays a name (and its error says so);
        # text has a line break, a space or a quote where a name has none.
        text = "\n" in source or (not os.path.exists(source) and any(c in source for c in ' \t"['))
        path = source
    else:
        raise TypeError(f"load() takes a path or the scene's text, not {type(source).__name__}")
    fixes = fix if fix is None or isinstance(fix, str) else ",".join(fix)
    specs = [f"{k}={v}" for k, v in (limits or {}).items()]
    return Scene(_native.load(path, text, syntax, fixes, specs, colour))


class Scene:
    """A loaded scene. Rendering does not change it: render it as often as you like.
    After a render, ``last_render`` holds its width, height, seconds, iterations,
    photons (light paths), integrator and whether it was interrupted."""

    def __init__(self, native: Any):
        self._native = native

    @property
    def warnings(self) -> list:
        """The warnings loading gave, each ``file:line:col: warning: ...``."""
        return self._native.warnings()

    @property
    def size(self) -> tuple:
        """(width, height) of the rendered window (the Film's crop of its resolution)."""
        return self._native.size()

    def check(self, shapes: bool = False) -> dict:
        """The ``pbrt-sppm check --json`` object (``shapes=True``: with ``--shapes``)."""
        return json.loads(self._native.check_json(shapes))

    def summary(self) -> str:
        """The text ``pbrt-sppm check`` prints."""
        return self._native.summary()

    def trace(self, origins, directions, tmax=None) -> dict:
        """Intersects rays with the scene, as ``pbrt-sppm trace`` does.

        origins, directions: (N, 3) arrays (directions need not be unit length; t is
        in their units); tmax: None or (N,). Returns a dict of arrays with one row per
        ray: ``hit`` (bool), ``t``, ``p``, ``p_error``, ``n`` (pbrt's geometric
        normal), ``ns``, ``uv``, ``dpdu``, ``dpdv`` (float32, NaN where missed),
        ``shape`` (names, "" where missed), ``shape_index``, ``triangle``, ``patch``
        (int64, -1 where missed or not a mesh)."""
        o = _rows(origins, 3, "origins")
        d = _rows(directions, 3, "directions")
        if len(o) != len(d):
            raise ValueError(f"{len(o)} origins but {len(d)} directions")
        t = None if tmax is None else np.ascontiguousarray(tmax, dtype="<f4").reshape(-1)
        cols = self._native.trace(o.tobytes(), d.tobytes(), None if t is None else t.tobytes())
        n = len(o)
        out = {"hit": np.array(cols["hit"], dtype=bool).reshape(n), "shape": np.array(cols["shape"], dtype=object)}
        for k, width in [("t", 1), ("p", 3), ("p_error", 3), ("n", 3), ("ns", 3), ("uv", 2), ("dpdu", 3), ("dpdv", 3)]:
            a = np.frombuffer(cols[k], dtype="<f4")
            out[k] = a.reshape(n) if width == 1 else a.reshape(n, width)
        for k in ["shape_index", "triangle", "patch"]:
            out[k] = np.frombuffer(cols[k], dtype="<i8").reshape(n)
        return out

    def render(
        self,
        spp: Optional[int] = None,
        integrator: Optional[str] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: Optional[Callable[[int, int, float], Optional[bool]]] = None,
        **options,
    ) -> np.ndarray:
        """Renders and returns the image as float32, (height, width, 3), linear RGB.

        spp: iterations (pixel samples), default the scene's. integrator: "sppm",
        "vcm", "bdpt" or "direct" (default: what the file asks for, as the command
        line).
        seed: default the Integrator's. threads: default every core.
        progress(done, planned, seconds) is called after every iteration; returning
        False stops the render after it (the image so far is returned).
        More options, as on the command line: photons, radius, time_limit,
        sampler ("sobol"/"random"), passes ("classic"/"independent"), alpha,
        volume_gather ("points"/"beams": how SPPM gathers photons in media).

        The GIL is released while rendering. Ctrl-C (or an exception raised by
        progress) stops the render after the iteration under way and is then raised."""
        return self._render(spp, integrator, seed, threads, progress, None, options)[0]

    def render_with_errors(self, reference, **kwargs) -> tuple:
        """render(), measuring the error against ``reference`` (an array, or an image
        file name) after every iteration: returns (image, errors), errors being a dict
        of arrays with ERRORS.csv's columns (iteration, seconds, photons, mse, rmse,
        relmse). The reference may be the full image or the Film's crop of it."""
        ref = read_image(reference) if isinstance(reference, (str, os.PathLike)) else _image(reference, "reference")
        args = [kwargs.pop(k, None) for k in ["spp", "integrator", "seed", "threads", "progress"]]
        image, out = self._render(*args, ref, kwargs)
        rows = out["errors"]
        cols = ["iteration", "seconds", "photons", "mse", "rmse", "relmse"]
        types = [np.int64, np.float64, np.int64, np.float64, np.float64, np.float64]
        return image, {c: np.array([r[i] for r in rows], dtype=t) for i, (c, t) in enumerate(zip(cols, types))}

    def _render(self, spp, integrator, seed, threads, progress, reference, options):
        known = {"photons", "radius", "time_limit", "sampler", "passes", "alpha", "volume_gather"}
        unknown = set(options) - known
        if unknown:
            raise TypeError(f"render() got unknown options {sorted(unknown)}; the options are {sorted(known)}")
        settings = {k: options.get(k) for k in known}
        settings.update(spp=spp, integrator=integrator, seed=seed)
        ref = None
        if reference is not None:
            ref = (reference.tobytes(), reference.shape[1], reference.shape[0])
        out = self._native.render(settings, progress, ref, threads)
        image = np.frombuffer(out["image"], dtype="<f4").reshape(out["height"], out["width"], 3).copy()
        self.last_render = {k: v for k, v in out.items() if k not in ("image", "errors")}
        return image, out


def read_image(path: PathOrText) -> np.ndarray:
    """An EXR (or PNG, decoded from sRGB) as float32 (height, width, 3)."""
    data, w, h = _native.read_image(os.fspath(path))
    return np.frombuffer(data, dtype="<f4").reshape(h, w, 3).copy()


def read_buckets(path: PathOrText) -> Optional[dict]:
    """A spectral film's wavelength buckets (pbrt-v4's ``Film "spectral"``, written by
    pbrt-v4 or by us): ``{"wavelengths": float64 (n,) bucket centres in nm, "names":
    the n channel names, "values": float32 (height, width, n)}``; None when the EXR
    holds only R, G and B."""
    found = _native.read_buckets(os.fspath(path))
    if found is None:
        return None
    names, data, w, h = found
    centres = [float(n[len("S0.") : -len("nm")].replace(",", ".")) for n in names]
    values = np.frombuffer(data, dtype="<f4").reshape(h, w, len(names)).copy()
    return {"wavelengths": np.array(centres), "names": list(names), "values": values}


def write_image(path: PathOrText, image) -> None:
    """Writes an .exr (float32) or .png (8-bit sRGB); the file appears whole or not at all."""
    a = _image(image, "image")
    _native.write_image(os.fspath(path), a.tobytes(), a.shape[1], a.shape[0])


def diff(image, reference, pixel_threshold: float = 0.01) -> dict:
    """``pbrt-imgtool diff``: mse, rmse, relmse (mean((a-b)^2/(b^2+0.01))), mae,
    max_abs and share_above (pixels with a channel off by more than pixel_threshold)."""
    a, b = _pair(image, reference)
    return _native.diff(a.tobytes(), b.tobytes(), a.shape[1], a.shape[0], pixel_threshold)


def relmse(image, reference) -> float:
    """Relative MSE, mean((a-b)^2/(b^2+0.01)) over pixels and channels, as ERRORS.csv."""
    return diff(image, reference)["relmse"]


def tiles(image, reference, grid: int = 4, floor: float = 0.05) -> dict:
    """``pbrt-imgtool tiles``: channel means of both images over the whole image
    (``image_means``, ``reference_means``: (3,)) and each tile of a grid×grid split
    (``tile_means``, ``reference_tile_means``: (grid, grid, 3), row 0 at the top), and
    ``worst``: the largest relative deviation of a mean, with ``at`` ("image" or
    "tile (x, y)") and ``channel``. A mean below ``floor`` × the reference's image mean
    is compared against that floor instead of itself."""
    a, b = _pair(image, reference)
    t = _native.tiles(a.tobytes(), b.tobytes(), a.shape[1], a.shape[0], grid, floor)
    ma, mb = np.array(t["a"]), np.array(t["b"])
    return {
        "image_means": ma[0],
        "reference_means": mb[0],
        "tile_means": ma[1:].reshape(grid, grid, 3),
        "reference_tile_means": mb[1:].reshape(grid, grid, 3),
        "worst": t["worst"],
        "at": t["at"],
        "channel": t["channel"],
    }


def _rows(x, width: int, name: str) -> np.ndarray:
    a = np.ascontiguousarray(x, dtype="<f4")
    if a.ndim == 1 and a.shape[0] == width:
        a = a.reshape(1, width)
    if a.ndim != 2 or a.shape[1] != width:
        raise ValueError(f"{name} must be an (N, {width}) array, not {a.shape}")
    return a


def _image(x, name: str) -> np.ndarray:
    a = np.ascontiguousarray(x, dtype="<f4")
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"{name} must be a (height, width, 3) array, not {a.shape}")
    return a


def _pair(image, reference):
    a, b = _image(image, "image"), _image(reference, "reference")
    if a.shape != b.shape:
        raise ValueError(f"the images differ in size: {a.shape} and {b.shape}")
    return a, b
