"""Penumbra from Python: factors on arrays, scenes as dicts, renders as arrays.

A thin layer over Penumbra's C++ libraries (the compiled ``_penumbra``):
every check, factor, pixel and metric comes from the code the ``penumbra``
command runs, so the numbers are the command line's to the bit. Units:
directions are unit vectors in any one frame; radiance is W m^-2 sr^-1;
factors are dimensionless, in [0, 1] unless a method's row says otherwise.
See docs/python.md for a worked session.
"""

import json
import os
import tempfile

import numpy as np

from . import _build
from ._errors import SceneError
from ._tables import load_metrics, load_report

# The harness scripts, scenes and image-format module lie beside the
# penumbra binary (util/data_files.h), not beside the Python interpreter.
os.environ.setdefault("PENUMBRA_EXECUTABLE_DIR", _build.BINARY_DIR)
os.environ.setdefault("PENUMBRA_DATA_DIR", _build.DATA_DIR)

from . import _penumbra  # noqa: E402  (after PENUMBRA_DATA_DIR)

__all__ = ["SceneError", "methods", "factor", "load_scene", "render", "read_exr", "write_exr",
           "compare", "run", "load_metrics", "load_report"]


def methods():
    """The method registry, as ``penumbra methods --json`` prints it.

    Returns a list of dicts, one per terminator method, normal adjustment,
    shadow-ray offset and roughness filter: ``id``, ``kind``, ``source``,
    ``summary`` and, where there are any, ``parameters`` (each with
    ``name``, ``unit``, ``min``, ``max``, ``default``, ``description``).
    """
    return json.loads(_penumbra.methods_json())


def _directions(name, value, n=None):
    a = np.ascontiguousarray(value, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3 or (n is not None and a.shape[0] != n):
        want = "(N, 3)" if n is None else f"({n}, 3)"
        raise ValueError(f"{name}: expected a {want} array of unit vectors, got shape {a.shape}")
    return a


def factor(method, ng, ns, wi, wo=None, visibility=1.0, **parameters):
    """The factor G a terminator method applies at each of N shading points.

    The evaluator's own per-sample computation (core/shading.cpp, shade()),
    the value its ``analysis.G`` channel averages: for a plain factor the
    method's formula; for a method with a normal adjustment or a microfacet
    model the effective factor, its radiance over raw bump's on a white
    Lambertian base (NaN where raw bump receives no light), as
    ``penumbra contour`` plots it.

    method      a terminator method id (``pn.methods()``, kind "terminator")
    ng, ns, wi  (N, 3) float arrays of unit vectors: the reference (base)
                normal, the bumped shading normal, towards the light
    wo          (N, 3) towards the viewer; default ng (viewer along the base
                normal, as ``penumbra contour``); only view-dependent
                methods and adjustments read it
    visibility  the height field's ambient visibility, [0, 1], scalar or
                (N,); only the micro-shadowing methods read it
    parameters  the method's parameters by name (e.g. ``s=0.3`` for
                shading-offset), checked against their domains as a scene's
                /terminator/parameters are; ``table="table.json"`` for fitted

    Returns an (N,) float64 array. Raises SceneError for an unknown method
    or a parameter outside its domain (file "pn.factor", pointer under
    /terminator).
    """
    ng = _directions("ng", ng)
    n = ng.shape[0]
    ns = _directions("ns", ns, n)
    wi = _directions("wi", wi, n)
    wo = ng if wo is None else _directions("wo", wo, n)
    vis = np.ascontiguousarray(np.broadcast_to(np.asarray(visibility, dtype=np.float64), (n,)))
    terminator = {"method": method}
    if parameters:
        terminator["parameters"] = parameters
    return _penumbra.factor(json.dumps(terminator), ng, ns, wi, wo, vis)


def _scene_source(scene):
    """(path, document JSON text) for the C++ reader: a path reads the file."""
    if isinstance(scene, (str, os.PathLike)):
        return os.fspath(scene), ""
    if isinstance(scene, dict):
        # Relative map files resolve from the working directory, as they
        # would for a scene file written there.
        return os.path.join(os.getcwd(), "<dict>"), json.dumps(scene)
    raise TypeError(f"scene: expected a file path or a dict, got {type(scene).__name__}")


def _scene_options(method, width, height, spp, representation, set):
    options = {}
    for key, value in (("method", method), ("width", width), ("height", height), ("spp", spp),
                       ("representation", representation)):
        if value is not None:
            options[key] = value
    if set:
        items = set.items() if isinstance(set, dict) else set
        options["sets"] = [s if isinstance(s, str) else f"{s[0]}={json.dumps(s[1])}"
                           for s in items]
    return options


def load_scene(scene, *, method=None, width=None, height=None, spp=None, representation=None,
               set=None):
    """A scene read and validated by the command line's reader, as a dict.

    scene   a scene file path, or a dict (then checked as if it were a file in
            the working directory)
    method, width, height, spp, representation, set
            the shortcuts of ``penumbra render``: each sets one pointer
            (/terminator/method, /camera/width in pixels, /camera/height in
            pixels, /camera/spp in samples per pixel, /representation);
            ``set`` is ``{"/json/pointer": value}`` or a list of
            ``"POINTER=VALUE"`` strings, as ``--set``

    Returns the document with the overrides applied and relative map files
    made absolute. Raises SceneError (file, pointer, reason; the same message
    as the command line's exit-2 line).
    """
    path, document = _scene_source(scene)
    options = _scene_options(method, width, height, spp, representation, set)
    return json.loads(_penumbra.load_scene(path, document, options))


class Render(dict):
    """A render: channel name -> (height, width) float32 array.

    ``R``, ``G``, ``B``: radiance in W m^-2 sr^-1; ``A``: coverage in [0, 1];
    ``analysis.theta``, ``analysis.deviation``, ``analysis.view`` in degrees
    and ``analysis.G`` (the factor, dimensionless), means over the samples
    that hit (evaluator/evaluator.h). ``attributes`` holds the EXR header
    ``penumbra render`` writes (scene, method, renderer, version).
    """

    def __init__(self, channels, pixels, attributes):
        # Views of one interleaved buffer, as the evaluator wrote it: no copy.
        super().__init__((name, pixels[:, :, k]) for k, name in enumerate(channels))
        self.channels = list(channels)
        self.pixels = pixels
        self.attributes = dict(attributes)


def render(scene, *, method=None, width=None, height=None, spp=None, representation=None,
           set=None, renderer="evaluator", threads=0):
    """Render a scene and return its image as arrays (a ``Render`` dict).

    The same reader, renderer call and bits as
    ``penumbra render SCENE -o out.exr`` with the same options; the image is
    the same whatever ``threads`` (0: all cores).

    scene           a scene file path or a dict (see ``load_scene``)
    method          terminator method id (``pn.methods()``), /terminator/method
    width, height   image size in pixels, integers >= 1 (/camera/width, /camera/height)
    spp             samples per pixel, integer >= 1 (/camera/spp)
    representation  "smooth", "bump" or "displacement" (the ground truth)
    set             ``{"/json/pointer": value}`` or ``["POINTER=VALUE", ...]``, as --set
    renderer        "evaluator" (default), "povray" or "blender"
    threads         worker threads, 0 for all cores; the GIL is released meanwhile

    Returns a ``Render``: ``img["R"]`` etc., (height, width) float32 arrays;
    R, G, B radiance in W m^-2 sr^-1, A coverage in [0, 1], analysis.theta,
    analysis.deviation, analysis.view in degrees, analysis.G the factor
    (dimensionless). Raises SceneError for a bad scene (the CLI's exit-2
    message), RuntimeError when the renderer fails.
    """
    path, document = _scene_source(scene)
    options = _scene_options(method, width, height, spp, representation, set)
    return Render(*_penumbra.render(path, document, options, renderer, int(threads)))


def read_exr(path):
    """An OpenEXR file (e.g. from ``penumbra render``) as a ``Render``."""
    return Render(*_penumbra.read_exr(os.fspath(path)))


def write_exr(image, path):
    """Write a ``Render`` (channels and attributes) as ``penumbra render`` does."""
    pixels = np.stack([np.asarray(image[c], dtype=np.float32) for c in image], axis=-1)
    attributes = sorted(getattr(image, "attributes", {}).items())
    _penumbra.write_exr(list(image), pixels, os.fspath(path), attributes)


def cli(*args):
    """Run ``penumbra ARGS...`` in this process: (exit status, stdout, stderr)."""
    return _penumbra.cli([os.fspath(a) for a in args])


def compare(truth, img, *options):
    """Every metric of ``img`` against ``truth``, as ``penumbra compare --json``.

    truth, img  EXR paths or ``Render`` dicts (written to a temporary folder
                with their attributes, which hold the scene the radiance
                scale comes from)
    options     further ``penumbra compare`` options, e.g. "--no-mask"

    Returns the JSON document as a dict ("reference" and "test" are the
    paths, None for an image given as a dict): the profile, image and view metrics,
    each with its 95 % interval (``*_ci``: [low, high]) and units as
    docs/reading-numbers.md describes. Raises SceneError or RuntimeError with
    the command's message when it exits non-zero.
    """
    with tempfile.TemporaryDirectory(prefix="penumbra-compare-") as folder:
        paths = {}
        for key, image in (("reference", truth), ("test", img)):
            if isinstance(image, dict):
                paths[key] = os.path.join(folder, key + ".exr")
                write_exr(image, paths[key])
            else:
                paths[key] = os.fspath(image)
        status, out, err = cli("compare", paths["reference"], paths["test"], "--json", *options)
    if status != 0:
        raise RuntimeError(err.strip())
    result = json.loads(out)
    for key, image in (("reference", truth), ("test", img)):
        if isinstance(image, dict):
            result[key] = None  # no file: the temporary one is gone
    return result


def run(study, out, *options, extra_methods=None):
    """Run a study as ``penumbra run STUDY -o OUT`` does; returns stdout.

    options        further ``penumbra run`` options, e.g. "--jobs", "2"
    extra_methods  not supported yet (user methods in Python: see docs/python.md)

    Raises RuntimeError with the command's message when it exits non-zero.
    """
    if extra_methods:
        raise NotImplementedError("extra_methods: user methods in Python are not implemented; "
                                  "see docs/python.md, 'What is not there yet'")
    status, stdout, err = cli("run", study, "-o", out, *options)
    if status != 0:
        raise RuntimeError(f"penumbra run exited {status}: {err.strip()}")
    return stdout
