"""Penumbra from Python: factors on arrays, scenes as dicts, renders as arrays.

A thin layer over Penumbra's C++ libraries (the compiled ``_penumbra``):
every check, factor, pixel and metric comes from the code the ``penumbra``
command runs, so the numbers are the command line's to the bit. Units:
directions are unit vectors in any one frame; radiance is W m^-2 sr^-1;
factors are dimensionless, in [0, 1] unless a method's row says otherwise.
See docs/python.md for a worked session.
"""

import hashlib
import inspect
import json
import marshal
import math
import os
import re
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

UserMethodError = _penumbra.UserMethodError

__all__ = ["SceneError", "UserMethodError", "method", "user_methods", "methods", "factor",
           "offset", "export", "load_scene", "render", "read_exr", "write_exr",
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


def factor(method, ng, ns, wi, wo=None, visibility=1.0, material=None, lobes=None,
           adjustment=None, **parameters):
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
    material    a scene's /material as a dict (``{"albedo": 0.8, "specular":
                {"weight": 0.5, "roughness": 0.3}}``); default a white
                Lambertian base. A plain factor does not depend on it; the
                effective factor of an adjustment or a microfacet model does
    lobes       "diffuse" (default) or "all": the scene's /terminator/lobes,
                the lobes a plain factor scales
    adjustment  a normal adjustment id (``pn.methods()``, kind
                "normal_adjustment"), the scene's
                /terminator/normal_adjustment, on top of ``method`` (which
                may be "none"): G is then the effective factor
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
    terminator = {"method": _method_id(method)}
    if parameters:
        terminator["parameters"] = parameters
    if lobes is not None:
        terminator["lobes"] = lobes
    if adjustment is not None:
        terminator["normal_adjustment"] = adjustment
    if terminator["method"] in _penumbra.user_methods():
        return _penumbra.user_factor(json.dumps(terminator), ng, ns, wi, wo)
    return _penumbra.factor(json.dumps(terminator), ng, ns, wi, wo, vis,
                            "" if material is None else json.dumps(material))


def offset(method, vertices, normals, barycentrics, wi, ns=None, backfacing=False,
           **parameters):
    """The shadow ray's origin a low-poly offset method picks at N hits.

    The evaluator's own computation (core/shadow_origin.cpp,
    shadow_ray_origin), as the low-poly section renders it.

    method        an offset id (``pn.methods()``, kind "offset")
    vertices      (N, 3, 3): each hit's triangle, vertex by vertex, in scene
                  units; the triangle's normal is taken from its winding,
                  (v1 - v0) x (v2 - v0), which must face the shaded side
    normals       (N, 3, 3): the vertex normals (unit), on the shaded side
    barycentrics  (N, 3): the hit's weights of the three vertices (sum 1)
    wi            (N, 3): unit vectors towards the light
    ns            (N, 3): the shading normal; default the interpolated
                  vertex normal
    backfacing    the triangles were hit from their backs (normals flipped)
    parameters    the method's parameters by name (``distance=0.01`` for
                  epsilon, ``cutoff=0.1`` for cycles-geometry-offset, ...)

    Returns (origins, skip_self): (N, 3) float64 points in scene units, and
    (N,) bool, whether the shadow ray ignores its own triangle.
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    m = np.ascontiguousarray(normals, dtype=np.float64)
    b = _directions("barycentrics", barycentrics)
    n = b.shape[0]
    if v.shape != (n, 3, 3) or m.shape != (n, 3, 3):
        raise ValueError(f"vertices, normals: expected ({n}, 3, 3) arrays, got {v.shape} "
                         f"and {m.shape}")
    ng = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)
    if ns is None:
        ns = np.einsum("ij,ijk->ik", b, m)
        ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    settings = {"method": method, **parameters}  # a scene's /offset
    return _penumbra.offset(json.dumps(settings), v, m, b, ng, _directions("ns", ns, n),
                            _directions("wi", wi, n), bool(backfacing))


_DOMAIN = re.compile(r"\[\s*([-+]?(?:inf|[0-9.]+(?:e[-+]?[0-9]+)?))\s*,"
                     r"\s*([-+]?(?:inf|[0-9.]+(?:e[-+]?[0-9]+)?))\s*\]", re.IGNORECASE)


def _parameter(name, spec):
    """(name, default, min, max, description) from (default, "unit, [lo, hi]")."""
    if isinstance(spec, (int, float)):
        spec = (spec, "")
    if not (isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[1], str)):
        raise TypeError(f"parameter {name!r}: expected (default, \"unit, [min, max]\"), "
                        f"got {spec!r}")
    default, description = float(spec[0]), spec[1]
    domain = _DOMAIN.search(description)
    low, high = (float(domain[1]), float(domain[2])) if domain else (-math.inf, math.inf)
    if not low <= default <= high:
        raise ValueError(f"parameter {name!r}: default {default} outside [{low}, {high}]")
    return (name, default, max(low, -1e300), min(high, 1e300), description)


def _definition_digest(function, id, parameters, value_range, vectors):
    """SHA-256 of what defines a user method: its source file's bytes (the
    function's own source where there is no file, its compiled code where
    there is no source), its name and its
    declaration. A render's cache key includes it, so editing the file
    renders again."""
    h = hashlib.sha256()
    try:
        path = inspect.getsourcefile(function)
    except TypeError:  # a built-in or C function: no source file
        path = None
    if path and os.path.isfile(path):
        with open(path, "rb") as f:
            h.update(f.read())
    else:
        try:
            h.update(inspect.getsource(function).encode())
        except (OSError, TypeError):  # defined by exec or in a REPL: its compiled code
            h.update(marshal.dumps(function.__code__))
    h.update(json.dumps([id, function.__qualname__, parameters, list(value_range),
                         vectors]).encode())
    return h.hexdigest()


def method(id, parameters=None, range=(0.0, 1.0), vectors=False):
    """Decorator: a Python function becomes a terminator method ``id``.

    The function takes NumPy (N,) arrays of the four cosines a factor may
    use, as the evaluator computes them at each shading sample (ng is the
    reference normal: Ng, or Ni where the scene says so):

        cos_light      <ng, wi>    cos_deviation  <ng, ns>
        cos_shading    <ns, wi>    cos_view       <ng, wo>

    and each declared parameter as a keyword (a float), plus ``ng, ns, wi,
    wo`` as (N, 3) arrays when ``vectors=True``. It returns G, an (N,)
    array, dimensionless, finite and within ``range`` ([0, 1] by default).
    The arrays are read-only views, valid during the call only.

    The method then works wherever a built-in one does, by its id: in
    ``pn.render(..., method=id)``, ``pn.factor(id, ...)``, a scene's
    /terminator/method, a study's "methods" and ``pn.run(...,
    extra_methods=[id])``. G multiplies raw bump's light on the scene's
    /terminator/lobes (diffuse by default), as a built-in factor does. The
    evaluator calls the function once per block of samples (about 5e5),
    never per sample; a render that calls it runs its shading on one
    sample path (no SIMD packets) and records the samples in between.

    id          lower-case letters, digits and '-'; not a built-in id
    parameters  {name: (default, "unit, [min, max]")}; the domain in
                brackets is parsed and enforced, e.g. (0.125,
                "dimensionless, [0, 1]")
    range       (min, max) of G: a value outside it, NaN or infinite fails
                the render with UserMethodError
    vectors     also pass the unit vectors (more memory per sample)

    Registering an id again replaces the function. A failing function
    (an exception, a wrong shape, a value outside ``range``) fails the
    render with UserMethodError naming the method; in a study, that render
    fails, the study exits 1 and nothing of it is cached.
    """
    declared = [_parameter(name, spec) for name, spec in (parameters or {}).items()]
    low, high = float(range[0]), float(range[1])
    if not low <= high:
        raise ValueError(f"range: expected (min, max) with min <= max, got {range!r}")

    def register(function):
        digest = _definition_digest(function, id, declared, (low, high), bool(vectors))
        code = getattr(function, "__code__", None)
        path = code.co_filename if code else "<unknown>"
        source = f"{os.path.basename(path)}:{function.__qualname__}"
        _penumbra.register_method(id, function, source, digest, declared, low, high,
                                  bool(vectors))
        function.penumbra_id = id
        return function

    return register


def user_methods():
    """The ids of the user methods registered in this process."""
    return list(_penumbra.user_methods())


def _method_id(m):
    """A method id, or a function that penumbra.method registered."""
    return getattr(m, "penumbra_id", m)


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
    method = None if method is None else _method_id(method)
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


def export(scene, to, out, *, method=None, width=None, height=None, spp=None,
           representation=None, set=None):
    """Write a scene for POV-Ray or Blender, as ``penumbra export --to TO
    SCENE -o OUT`` does, from a file or a dict.

    to      "povray" (a .pov file) or "blender" (a job and its mesh)
    out     the output folder, made if missing
    method, ..., set  as ``load_scene``

    Returns what the command prints (the files written). Raises SceneError
    for bad input, RuntimeError for a method or offset the renderer does not
    ship.
    """
    path, document = _scene_source(scene)
    options = _scene_options(method, width, height, spp, representation, set)
    return _penumbra.export(path, document, options, to, os.fspath(out))


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
    extra_methods  method ids (or functions registered with penumbra.method)
                   measured in the study's bump section besides its own, as
                   ``--add-method`` adds them: ranked and reported like the
                   built-in methods

    Raises RuntimeError with the command's message when it exits non-zero
    (a user method that fails makes its renders fail: exit 1).
    """
    added = []
    for m in extra_methods or ():
        added += ["--add-method", _method_id(m)]
    status, stdout, err = cli("run", study, "-o", out, *options, *added)
    if status != 0:
        raise RuntimeError(f"penumbra run exited {status}: {err.strip()}")
    return stdout
