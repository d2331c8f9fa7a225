"""Render one Penumbra Blender job with Cycles (CPU) into a linear OpenEXR.

Supported: Blender 3.4 to 4.4 (BLENDER_SUPPORTED); tested with 3.4 (Debian
12).  Any other version is refused before anything is rendered, with one line
on stderr and exit status 1.

Usage:

    blender -b -t 1 --factory-startup -noaudio --python-exit-code 1 \\
        --python harness/blender_render.py -- JOB.json OUTPUT.exr [--threads N]
    blender -b -t 1 --factory-startup -noaudio --python-exit-code 1 \\
        --python harness/blender_render.py -- --serve

-t 1 makes all of Blender run on one thread, Cycles included (it overrides
--threads).  Penumbra always starts Blender so and renders several jobs at
once instead.  A displaced surface (mode "mesh", below) needs it: without
it, Blender sums the mesh's vertex normals on several threads in an order
that varies from run to run (Blender 3.4 mesh_normals.cc,
normals_calc_poly_vert with add_v3_v3_atomic), Cycles' bump shadowing term
reads them, and the same job renders one float ulp apart in a pixel or
two (measured: 5 of 24 renders).  Such a job is refused on more than one
thread (single_threaded).

With --serve, one Blender renders job after job, so that its start-up (about
1 s) is paid once: each line on stdin is a request, a JSON object
{"job": "/abs/JOB.json", "output": "/abs/OUT.exr", "threads": N}; the
answer is OUT.exr (renamed into place when done) or OUT.exr.error (one line:
why), and a log line on stdout.  A bad job does not end the server; end of
input does.  A served job that differs from the last one only in its light
and material keeps the last one's mesh object (and its material, when that
is the same too; see KEPT); any other job starts from Blender's factory
settings with an empty scene.  Either way a job's
pixels do not depend on what the same process rendered before.

JOB.json ("penumbra-blender-job" version 2, see SCHEMA) gives a camera, a sun,
a triangle mesh in three raw little-endian files beside it (float32 positions,
float32 unit vertex normals, uint32 triangles) with smooth faces (shaded with
those normals) or flat faces (shaded with the triangle's normal), a Diffuse
albedo, a sum or product of sines h(P) or an image map beside the job (a
height map or a tangent-space normal map, sampled at per-corner UVs from a
fourth raw file, float32 u v per triangle corner), a shading mode: "smooth",
"bump-displacement", "bump-node" or "mesh", and the object's shading and
geometry ("shadow terminator") offsets.  Smooth normals become custom split
normals, except in mode "mesh" with both offsets 0 (a displaced surface),
where only the Diffuse BSDF reads them: there they reach its Normal input
through a point attribute, which shades alike and builds in a fraction of
the time (exact_normals_as_attribute).

The job is data only: it is validated strictly (unknown keys, wrong types and
out-of-range values are errors naming the JSON path) and only its numbers and
fixed enum strings are used.  Nothing from the job is ever executed or
evaluated, and no string from it becomes Python code or a Blender name.

The render is direct light only, unclamped, undenoised, box-filtered one pixel
wide, with a fixed seed.  The EXR holds scene-linear premultiplied RGBA (alpha
= coverage, first row = image top); it is written to a temporary name and
renamed into place only on success.  On failure one line starting with
"blender_render.py: " goes to stderr and the exit status is 1.
"""

import functools
import hashlib
import json
import math
import os
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector

PROG = "blender_render.py"
MAX_TERMS = 32
# First and last Blender release (major, minor) this script accepts.  3.4 is
# the release the calibration bounds were measured with and the oldest it has
# run on.  4.5 is refused: its Cycles replaced Chiang et al.'s term in
# bump_shadowing_term with Conty Estevez et al.'s (Blender commit 11e282522)
# and added a hemisphere test for every closure (commit 3b1e329ac), so the
# Bump node would no longer render "chiang2019".  Releases in between are
# accepted on the strength of Blender's API change logs (the
# version-dependent paths below cite them); a property one of them lacks
# still fails the job with a line naming it (configure).
BLENDER_SUPPORTED = ((3, 4), (4, 4))
BLENDER_TESTED = "3.4"
INT32 = 2**31 - 1


class JobError(Exception):
    """Invalid job, input data or Blender; the message names the cause."""


def blender_version_problem(version):
    """Why this script refuses Blender `version` (bpy.app.version), or None.

    Pure, so that it can be tested without Blender.
    """
    first, last = BLENDER_SUPPORTED
    if first <= tuple(version[:2]) <= last:
        return None
    return (f"Blender {'.'.join(map(str, version))} is not supported: this "
            f"script supports Blender {first[0]}.{first[1]} to "
            f"{last[0]}.{last[1]} (tested with {BLENDER_TESTED}); set "
            "PENUMBRA_BLENDER to a supported blender executable")


# --------------------------------------------------------------- validation

POSITIVE = ("num", 0.0, None, True)
UNIT = ("num", 0.0, 1.0)
CAMERA = {"projection": ("enum", "orthographic", "perspective"),
          "matrix_world": ("matrix",), "width": ("int", 1, 65536),
          "height": ("int", 1, 65536)}
LIGHTS = {
    "sun": {"type": ("enum", "sun"), "direction": ("unit",),
            "strength": ("num", 0.0, None)},
    "sphere": {"type": ("enum", "sphere"), "center": ("vec", 3),
               "radius": POSITIVE, "radiance": ("num", 0.0, None)},
    "quad": {"type": ("enum", "quad"),
             "vertices": ("list", 4, ("vec", 3)), "normal": ("unit",),
             "radiance": ("num", 0.0, None)},
    "environment": {"type": ("enum", "environment"), "file": ("file",),
                    "rotation_deg": ("num", -360.0, 360.0),
                    "strength": ("num", 0.0, None)}}
SCHEMA = {
    "format": ("enum", "penumbra-blender-job"),
    "version": ("int", 2, 2),
    "camera": ("switch", "projection", {
        "orthographic": dict(CAMERA, ortho_scale=POSITIVE,
                             **{"sensor_width?": POSITIVE}),
        "perspective": dict(CAMERA, sensor_width=POSITIVE, lens=POSITIVE)}),
    "render": {"samples": ("int", 1, 1 << 24), "seed": ("int", 0, INT32)},
    "light": ("switch", "type", dict(
        LIGHTS, group={"type": ("enum", "group"),
                       "lights": ("list", 8, ("switch", "type", LIGHTS))})),
    "mesh": {"positions": ("file",), "normals": ("file",),
             "triangles": ("file",), "vertex_count": ("int", 3, INT32),
             "triangle_count": ("int", 1, INT32 // 3),
             "faces": ("enum", "smooth", "flat"), "uvs?": ("file",)},
    "material": {"albedo": UNIT},
    "height": {"amplitude": ("num", 0.0, None),
               "combine": ("enum", "sum", "product"),
               "terms": ("list", MAX_TERMS,
                         {"k": ("vec", 3), "phase": ("num",),
                          "weight": ("num",)}),
               "image?": {"file": ("file",),
                          "kind": ("enum", "height", "normal"),
                          "extension": ("enum", "REPEAT", "EXTEND")}},
    "shading": {"mode": ("enum", "smooth", "bump-displacement",
                         "bump-node", "mesh"),
                "shading_offset": UNIT, "geometry_offset": UNIT},
}


def _is_num(v):
    return (isinstance(v, (int, float)) and not isinstance(v, bool)
            and math.isfinite(v))


def _vec(v, path, n):
    if not (isinstance(v, list) and len(v) == n and all(map(_is_num, v))):
        raise JobError(f"{path}: expected an array of {n} numbers")
    return v


def check(v, spec, path=""):
    """Check v against a SCHEMA entry; raises JobError naming the path."""
    if isinstance(spec, dict):
        if not isinstance(v, dict):
            raise JobError(f"{path or '/'}: expected an object")
        names = {k.rstrip("?"): k for k in spec}
        for key in v:
            if key not in names:
                raise JobError(f"{path}/{key}: unknown key")
        for name, key in names.items():
            if name in v:
                check(v[name], spec[key], f"{path}/{name}")
            elif not key.endswith("?"):
                raise JobError(f"{path}/{name}: missing key")
        return
    kind, args = spec[0], spec[1:]
    if kind == "switch":  # an object whose keys depend on v[key]
        key, cases = args
        if not isinstance(v, dict) or key not in v:
            raise JobError(f"{path}: expected an object with \"{key}\"")
        check(v[key], ("enum", *cases), f"{path}/{key}")
        check(v, cases[v[key]], path)
    elif kind == "num":
        lo, hi, positive = (args + (None, None, False))[:3]
        if lo is not None and hi is not None:
            what = f"a number in [{lo:g}, {hi:g}]"
        elif positive:
            what = "a positive number"
        else:
            what = "a number" if lo is None else f"a number >= {lo:g}"
        if (not _is_num(v) or (positive and v <= lo)
                or (lo is not None and v < lo) or (hi is not None and v > hi)):
            raise JobError(f"{path}: expected {what}, "
                           f"got {json.dumps(v)[:60]}")
    elif kind == "int":
        if (not isinstance(v, int) or isinstance(v, bool)
                or not args[0] <= v <= args[1]):
            raise JobError(f"{path}: expected an integer in [{args[0]}, "
                           f"{args[1]}], got {json.dumps(v)[:60]}")
    elif kind == "enum":
        if not isinstance(v, str) or v not in args:
            raise JobError(f"{path}: expected one of "
                           f"{', '.join(map(json.dumps, args))}")
    elif kind == "vec":
        _vec(v, path, args[0])
    elif kind == "unit":
        if abs(math.sqrt(sum(x * x for x in _vec(v, path, 3))) - 1) > 1e-3:
            raise JobError(f"{path}: expected a unit vector")
    elif kind == "path":
        if not isinstance(v, str) or not os.path.isabs(v) or "\0" in v:
            raise JobError(f"{path}: expected an absolute path")
    elif kind == "file":
        if (not isinstance(v, str) or v in ("", ".", "..")
                or any(c in v for c in "/\\\0")):
            raise JobError(f"{path}: expected a plain file name "
                           "(no '/', '\\' or '..')")
    elif kind == "list":
        if not isinstance(v, list) or len(v) > args[0]:
            raise JobError(f"{path}: expected an array of at most "
                           f"{args[0]} items")
        for i, item in enumerate(v):
            check(item, args[1], f"{path}/{i}")
    elif kind == "matrix":
        if not isinstance(v, list) or len(v) != 4:
            raise JobError(f"{path}: expected 4 rows of 4 numbers")
        m = Matrix([_vec(r, f"{path}/{i}", 4) for i, r in enumerate(v)])
        rot = m.to_3x3()
        err = rot @ rot.transposed() - Matrix.Identity(3)
        if (list(m[3]) != [0, 0, 0, 1] or rot.determinant() <= 0
                or max(abs(x) for row in err for x in row) > 1e-4):
            raise JobError(f"{path}: expected a rigid transform (orthonormal "
                           "right-handed rotation, last row [0,0,0,1])")


# ------------------------------------------------------------------- scene

def configure(owner, what, **settings):
    """Set properties, failing clearly if this Blender lacks one. A property
    that already has its value is left alone: setting it would still tag
    the scene for Cycles to sync again (a color-management setting makes a
    served render on a kept mesh resync everything)."""
    for key, value in settings.items():
        if not hasattr(owner, key):
            raise JobError(f"Blender {bpy.app.version_string} has no "
                           f"{what}.{key}")
        if getattr(owner, key) != value:
            setattr(owner, key, value)


def read_raw(folder, name, dtype, count, path):
    fn = os.path.join(folder, name)
    size = np.dtype(dtype).itemsize * count
    try:
        actual = os.path.getsize(fn)
    except OSError as e:
        raise JobError(f"{path}: cannot read {fn}: {e.strerror}") from None
    if actual != size:
        raise JobError(f"{path}: {fn} has {actual} bytes, expected {size}")
    return np.fromfile(fn, dtype=dtype, count=count)


# The point attribute that carries a "mesh" job's vertex normals.
NORMALS_ATTRIBUTE = "penumbra_normal"


def exact_normals_as_attribute(job):
    """Whether the job's smooth normals reach the shading through an
    attribute rather than as custom split normals: in mode "mesh" (the
    displaced surface itself) with both offsets 0, nothing but the Diffuse
    BSDF reads them, and its Normal input can take them.  Custom normals
    make Blender compute split normals, and Cycles split the mesh by them
    (object sync), which took 4.3 s of a 1.1 M-triangle render."""
    sh = job["shading"]
    return (sh["mode"] == "mesh" and job["mesh"]["faces"] == "smooth"
            and sh["shading_offset"] == 0.0 and sh["geometry_offset"] == 0.0)


@functools.lru_cache(maxsize=None)
def single_threaded():
    """Whether Blender runs on one thread: started with -t 1, or on a
    one-core machine.  In mode AUTO, RenderSettings.threads reports
    Blender's thread count, -t first; it is fixed for the process."""
    r = bpy.context.scene.render
    mode = r.threads_mode
    r.threads_mode = "AUTO"
    threads = r.threads
    r.threads_mode = mode
    return threads == 1


def build_mesh(job, folder):
    jm = job["mesh"]
    n, m = jm["vertex_count"], jm["triangle_count"]
    pos = read_raw(folder, jm["positions"], "<f4", 3 * n, "/mesh/positions")
    nrm = read_raw(folder, jm["normals"], "<f4", 3 * n, "/mesh/normals")
    tri = read_raw(folder, jm["triangles"], "<u4", 3 * m, "/mesh/triangles")
    if not (np.isfinite(pos).all() and np.isfinite(nrm).all()):
        raise JobError("/mesh: positions or normals hold NaN or infinity")
    nrm = nrm.reshape(n, 3)
    if np.abs(np.linalg.norm(nrm.astype(np.float64), axis=1) - 1).max() > 1e-3:
        raise JobError("/mesh/normals: expected unit vectors")
    if tri.max() >= n:
        raise JobError(f"/mesh/triangles: index {int(tri.max())} out of "
                       f"range (vertex_count {n})")
    t3 = tri.reshape(m, 3)
    if ((t3[:, 0] == t3[:, 1]) | (t3[:, 1] == t3[:, 2])
            | (t3[:, 0] == t3[:, 2])).any():
        raise JobError("/mesh/triangles: a triangle repeats a vertex")

    me = bpy.data.meshes.new("penumbra_mesh")
    me.vertices.add(n)
    me.vertices.foreach_set("co", pos)
    me.loops.add(3 * m)
    # Unsigned 32-bit arrays: Blender 3.4 declares these properties
    # unsigned, and foreach_set copies a buffer of that exact type in one
    # go but converts any other item by item (int32: 0.15 s against 0.01 s
    # for the 3.4 M corners of a 1.1 M-triangle mesh).
    me.loops.foreach_set("vertex_index", tri)
    me.polygons.add(m)
    me.polygons.foreach_set("loop_start",
                            np.arange(0, 3 * m, 3, dtype=np.uint32))
    me.polygons.foreach_set("loop_total", np.full(m, 3, dtype=np.uint32))
    # Cycles applies the geometry offset to smooth faces only
    # (SHADER_SMOOTH_NORMAL): smooth faces must really be marked smooth.
    smooth = jm["faces"] == "smooth"
    me.polygons.foreach_set("use_smooth", np.full(m, smooth, dtype=bool))
    me.update(calc_edges=True)
    if len(me.vertices) != n or len(me.polygons) != m:
        raise JobError("/mesh: Blender changed the mesh while building it")
    if "uvs" in jm:
        # Per corner, so that a seam needs no split vertices; the exporter
        # has already multiplied in the map's tiling.
        uvs = read_raw(folder, jm["uvs"], "<f4", 6 * m, "/mesh/uvs")
        if not np.isfinite(uvs).all():
            raise JobError("/mesh/uvs: NaN or infinity")
        layer = me.uv_layers.new(name="penumbra_uv")
        layer.data.foreach_set("uv", uvs)
    if smooth and exact_normals_as_attribute(job):
        # The displaced surface's normals, for the material to shade with
        # (build_material): custom split normals would cost most of the
        # render (README, Speed), and the shading is the same (tested).
        layer = me.attributes.new(NORMALS_ATTRIBUTE, "FLOAT_VECTOR", "POINT")
        layer.data.foreach_set("vector", nrm.ravel())
    elif smooth:
        # Custom split normals: Cycles then shades with these vertex normals.
        # Up to 4.0 they count only with auto smooth on (an angle of pi marks
        # no edge sharp); 4.1 removed the option (4.1 API change log,
        # bpy.types.Mesh) and uses custom normals whenever they are set, with
        # no edge sharp unless marked so (Blender PR #108014, "Mesh: Replace
        # auto smooth with node group"): the same normals either way.
        if hasattr(me, "use_auto_smooth"):
            configure(me, "Mesh", use_auto_smooth=True,
                      auto_smooth_angle=math.pi)
        me.normals_split_custom_set_from_vertices(nrm)
    kept = np.empty(m, dtype=bool)
    me.polygons.foreach_get("use_smooth", kept)
    if (kept != smooth).any():
        raise JobError("/mesh/faces: Blender did not keep the face shading")
    ob = bpy.data.objects.new("penumbra_object", me)
    sh = job["shading"]
    configure(ob.cycles, "Object.cycles",
              shadow_terminator_offset=sh["shading_offset"],
              shadow_terminator_geometry_offset=sh["geometry_offset"])
    return ob


def digest(parts, folder, files):
    """A digest of JSON `parts` and the bytes of `files` (pointer, name)."""
    h = hashlib.sha256(json.dumps(parts, sort_keys=True).encode("utf-8"))
    for pointer, name in files:
        try:
            with open(os.path.join(folder, name), "rb") as f:
                h.update(f.read())
        except OSError as e:
            raise JobError(f"{pointer}: cannot read: {e.strerror}") from None
    return h.hexdigest()


def mesh_digest(job, folder):
    """What a kept mesh object must share with the job: all of the job (the
    mesh's raw files included) but the light and what build_material builds
    from. Cycles does not see a change of a kept object's own settings (its
    shading and geometry offsets) under persistent data, so those count
    here too."""
    jm = job["mesh"]
    parts = {k: v for k, v in job.items()
             if k not in ("light", "height", "material", "shading")}
    parts["shading"] = {k: v for k, v in job["shading"].items()
                        if k != "mode"}
    parts["normals_as_attribute"] = exact_normals_as_attribute(job)
    return digest(parts, folder, [(f"/mesh/{k}", jm[k]) for k in
                                  ("positions", "normals", "triangles", "uvs")
                                  if k in jm])


def material_digest(job, folder):
    """What build_material builds from: the mode, /height (and its image
    file), /material, where the normals come from."""
    image = job["height"].get("image")
    return digest([job["shading"]["mode"], job["height"], job["material"],
                   exact_normals_as_attribute(job)],
                  folder, [("/height/image/file", image["file"])] if image
                  else [])


def height_socket(nt, hgt):
    """Build h(P) from world-space Position with Math nodes; return output."""
    nodes, links = nt.nodes, nt.links
    product = hgt["combine"] == "product"
    if not hgt["terms"]:
        val = nodes.new("ShaderNodeValue")
        val.outputs[0].default_value = 1.0 if product else 0.0
        return val.outputs[0]
    position = nodes.new("ShaderNodeNewGeometry").outputs["Position"]

    def math_node(op, a, b=None):
        node = nodes.new("ShaderNodeMath")
        node.operation = op
        for socket, x in zip(node.inputs, (a, b)):
            if isinstance(x, float):
                socket.default_value = x
            elif x is not None:
                links.new(x, socket)
        return node.outputs[0]

    acc = None
    for t in hgt["terms"]:
        dot = nodes.new("ShaderNodeVectorMath")
        dot.operation = "DOT_PRODUCT"
        links.new(position, dot.inputs[0])
        dot.inputs[1].default_value = [2 * math.pi * k for k in t["k"]]
        arg = math_node("ADD", dot.outputs["Value"], float(t["phase"]))
        term = math_node("SINE", arg)
        if not product:
            term = math_node("MULTIPLY", term, float(t["weight"]))
        acc = term if acc is None else math_node(
            "MULTIPLY" if product else "ADD", acc, term)
    return acc


def image_node(nt, job, folder):
    """The job's image map at the mesh's UVs, with Cycles' "Cubic"
    interpolation: the uniform cubic B-spline the evaluator samples."""
    im = job["height"]["image"]
    if "uvs" not in job["mesh"]:
        raise JobError("/mesh/uvs: an image map needs the mesh's UVs")
    path = os.path.join(folder, im["file"])
    try:
        img = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as e:
        raise JobError(f"/height/image/file: Blender cannot read it ({e})")
    img.colorspace_settings.name = "Non-Color"
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = img
    configure(tex, "ShaderNodeTexImage", interpolation="Cubic",
              extension=im["extension"])
    uv = nt.nodes.new("ShaderNodeUVMap")
    uv.uv_map = "penumbra_uv"
    nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
    return tex


def map_height_socket(nt, job, folder):
    """h from a height map: its first channel (a one-channel EXR reads as
    grey, every channel the same)."""
    sep = nt.nodes.new("ShaderNodeSeparateColor")
    nt.links.new(image_node(nt, job, folder).outputs["Color"], sep.inputs[0])
    return sep.outputs[0]


def attribute_normal(nt):
    """The normals attribute, interpolated, normalised and turned to the
    viewer's side as Cycles turns its smooth normal (N = -N on a back face);
    returns the output socket."""
    nodes, links = nt.nodes, nt.links
    attr = nodes.new("ShaderNodeAttribute")
    configure(attr, "ShaderNodeAttribute", attribute_type="GEOMETRY",
              attribute_name=NORMALS_ATTRIBUTE)
    geometry = nodes.new("ShaderNodeNewGeometry")
    sign = nodes.new("ShaderNodeMath")  # 1 - 2 * backfacing
    configure(sign, "ShaderNodeMath", operation="MULTIPLY_ADD",
              use_clamp=False)
    links.new(geometry.outputs["Backfacing"], sign.inputs[0])
    sign.inputs[1].default_value = -2.0
    sign.inputs[2].default_value = 1.0
    turned = nodes.new("ShaderNodeVectorMath")
    configure(turned, "ShaderNodeVectorMath", operation="SCALE")
    links.new(attr.outputs["Vector"], turned.inputs[0])
    links.new(sign.outputs["Value"], turned.inputs["Scale"])
    unit = nodes.new("ShaderNodeVectorMath")
    configure(unit, "ShaderNodeVectorMath", operation="NORMALIZE")
    links.new(turned.outputs["Vector"], unit.inputs[0])
    return unit.outputs["Vector"]


def cycles_material(name):
    """(material, node tree, output node): an empty node material for Cycles."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    return mat, nt, out


def build_material(job, ob, folder):
    mat, nt, out = cycles_material("penumbra_material")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    a = job["material"]["albedo"]
    bsdf.inputs["Color"].default_value = (a, a, a, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    # 4.1 moved the displacement method from the Cycles settings to the
    # material (4.1 API change log: CyclesMaterialSettings.displacement_method
    # removed; bpy.types.Material.displacement_method in the 4.2 reference).
    if hasattr(mat.cycles, "displacement_method"):
        configure(mat.cycles, "Material.cycles", displacement_method="BUMP")
    else:
        configure(mat, "Material", displacement_method="BUMP")
    mode, amp = job["shading"]["mode"], job["height"]["amplitude"]
    if exact_normals_as_attribute(job):
        nt.links.new(attribute_normal(nt), bsdf.inputs["Normal"])
    image = job["height"].get("image")
    if image and image["kind"] == "normal":
        if mode != "bump-node":
            raise JobError("/shading/mode: a normal map shades through the "
                           "Normal Map node (\"bump-node\")")
        nmap = nt.nodes.new("ShaderNodeNormalMap")
        configure(nmap, "ShaderNodeNormalMap", space="TANGENT",
                  uv_map="penumbra_uv")
        nmap.inputs["Strength"].default_value = 1.0
        nt.links.new(image_node(nt, job, folder).outputs["Color"],
                     nmap.inputs["Color"])
        nt.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
        ob.data.materials.append(mat)
        return

    def height():
        return (map_height_socket(nt, job, folder) if image
                else height_socket(nt, job["height"]))

    if mode == "bump-displacement":
        disp = nt.nodes.new("ShaderNodeDisplacement")
        disp.space = "OBJECT"  # the object transform is the identity
        nt.links.new(height(), disp.inputs["Height"])
        disp.inputs["Midlevel"].default_value = 0.0
        disp.inputs["Scale"].default_value = amp
        nt.links.new(disp.outputs["Displacement"],
                     out.inputs["Displacement"])
    elif mode == "bump-node":
        bump = nt.nodes.new("ShaderNodeBump")
        bump.invert = False
        bump.inputs["Strength"].default_value = 1.0
        bump.inputs["Distance"].default_value = amp
        nt.links.new(height(), bump.inputs["Height"])
        nt.links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    ob.data.materials.append(mat)


def reset_blender():
    """Factory settings and an empty scene: no state from an earlier job."""
    result = bpy.ops.wm.read_factory_settings(use_empty=True)
    if "FINISHED" not in result:
        raise JobError("Blender could not reset to factory settings")


def clear_all_but(ob, keep_material):
    """Everything an earlier job built but the mesh object `ob` (and, with
    `keep_material`, its material): what the next job builds again
    (build_scene sets every setting it uses)."""
    for o in list(bpy.data.objects):
        if o != ob:
            bpy.data.objects.remove(o, do_unlink=True)
    kinds = [bpy.data.cameras, bpy.data.lights, bpy.data.worlds]
    for blocks in (bpy.data.meshes, bpy.data.materials, bpy.data.images):
        for block in list(blocks):
            if block.name.startswith(LIGHT_PREFIX):
                blocks.remove(block)
    if not keep_material:
        kinds += [bpy.data.materials, bpy.data.images, bpy.data.node_groups]
        ob.data.materials.clear()
    for blocks in kinds:
        for block in list(blocks):
            blocks.remove(block)


def build_sun(lj):
    """The distant light: a sun of the job's strength, shining along
    -direction, with sharp shadows; returns its (unlinked) object."""
    ld = bpy.data.lights.new("penumbra_sun", type="SUN")
    configure(ld, "SunLight", energy=lj["strength"], angle=0.0,
              color=(1.0, 1.0, 1.0), use_shadow=True)
    # 4.2 removed Light.cycles.cast_shadow (4.2 API change log,
    # bpy.types.CyclesLightSettings); use_shadow above is then the light's
    # only shadow switch.
    if hasattr(ld.cycles, "cast_shadow"):
        configure(ld.cycles, "Light.cycles", cast_shadow=True)
    lo = bpy.data.objects.new("penumbra_sun", ld)
    d = Vector(lj["direction"]).normalized()
    lo.rotation_mode = "QUATERNION"
    lo.rotation_quaternion = d.to_track_quat("Z", "Y")  # local +Z -> d
    if (lo.rotation_quaternion.to_matrix().col[2] - d).length > 1e-5:
        raise JobError("internal: sun orientation check failed")
    return lo


LIGHT_PREFIX = "penumbra_light"
# The emitting sphere's segments round and from pole to pole: its outline,
# an inscribed 256-gon, spans 1 - (2 pi / 256)^2 / 6 = 1 - 1.0e-4 of the
# sphere's solid angle, far below the noise of any test.
SPHERE_SEGMENTS, SPHERE_RINGS = 256, 128


def emission_material(radiance):
    """Emission of the given radiance (a strength S shows the camera S,
    Emission node), on front faces only: backfacing, it emits nothing."""
    mat, nt, out = cycles_material(LIGHT_PREFIX + "_material")
    front = nt.nodes.new("ShaderNodeEmission")
    front.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    front.inputs["Strength"].default_value = radiance
    back = nt.nodes.new("ShaderNodeEmission")
    back.inputs["Strength"].default_value = 0.0
    mix = nt.nodes.new("ShaderNodeMixShader")
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    nt.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(front.outputs["Emission"], mix.inputs[1])
    nt.links.new(back.outputs["Emission"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    # 3.4 names the switch sample_as_light; 3.5 replaced it by
    # emission_sampling (3.5 API change log, CyclesMaterialSettings).
    if hasattr(mat.cycles, "emission_sampling"):
        configure(mat.cycles, "Material.cycles", emission_sampling="FRONT")
    else:
        configure(mat.cycles, "Material.cycles", sample_as_light=True)
    return mat


def light_mesh(lj):
    """(vertices, faces) of an area light, faces turned so that their
    normals point where it emits (outwards for a sphere)."""
    if lj["type"] == "quad":
        v = [Vector(p) for p in lj["vertices"]]
        if (v[1] - v[0]).cross(v[3] - v[0]).dot(Vector(lj["normal"])) < 0:
            v.reverse()
        return [tuple(p) for p in v], [(0, 1, 2, 3)]
    c, r = Vector(lj["center"]), lj["radius"]
    verts = [tuple(c + Vector((0, 0, r)))]
    for i in range(1, SPHERE_RINGS):
        theta = math.pi * i / SPHERE_RINGS
        for j in range(SPHERE_SEGMENTS):
            phi = 2 * math.pi * j / SPHERE_SEGMENTS
            verts.append(tuple(c + r * Vector((math.sin(theta) * math.cos(phi),
                                               math.sin(theta) * math.sin(phi),
                                               math.cos(theta)))))
    verts.append(tuple(c - Vector((0, 0, r))))
    last, n = len(verts) - 1, SPHERE_SEGMENTS

    def ring(i, j):  # vertex j of ring i (1-based rings)
        return 1 + (i - 1) * n + j % n
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(n)]
    for i in range(1, SPHERE_RINGS - 1):
        faces += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1))
                  for j in range(n)]
    faces += [(last, ring(SPHERE_RINGS - 1, j + 1), ring(SPHERE_RINGS - 1, j))
              for j in range(n)]
    return verts, faces


def build_area_light(lj):
    """An area light as an emissive mesh that only shadow rays and light
    sampling see (Cycles 3.4's point light of a radius is a disk facing
    the shading point, not a sphere); returns its (unlinked) object."""
    verts, faces = light_mesh(lj)
    me = bpy.data.meshes.new(LIGHT_PREFIX)
    me.from_pydata(verts, [], faces)
    me.update()
    if lj["type"] == "sphere":  # outward normals, checked at the first face
        f = me.polygons[0]
        if f.normal.dot(f.center - Vector(lj["center"])) < 0:
            me.flip_normals()
    me.materials.append(emission_material(lj["radiance"]))
    lo = bpy.data.objects.new(LIGHT_PREFIX, me)
    # Cycles samples an emissive object as a light only if diffuse or
    # glossy rays can see it (scene/light.cpp, object_usable_as_light); no
    # such ray is traced (no bounces), so only the camera must not see it.
    configure(lo, "Object", visible_camera=False, visible_diffuse=True,
              visible_glossy=True, visible_transmission=False,
              visible_volume_scatter=False, visible_shadow=False)
    return lo


def build_environment(world, lj, folder):
    """The world as the job's environment map: the ray's direction turned by
    a Mapping node's Z rotation, then the map read per texel ("Closest",
    as the evaluator reads it), times the strength. The camera does not see
    it (the film is transparent)."""
    path = os.path.join(folder, lj["file"])
    try:
        img = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as e:
        raise JobError(f"/light/file: Blender cannot read it ({e})")
    img.name = LIGHT_PREFIX + "_environment"
    img.colorspace_settings.name = "Non-Color"
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    coord = nt.nodes.new("ShaderNodeTexCoord")
    mapping = nt.nodes.new("ShaderNodeMapping")
    configure(mapping, "ShaderNodeMapping", vector_type="POINT")
    mapping.inputs["Rotation"].default_value = (
        0.0, 0.0, math.radians(lj["rotation_deg"]))
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = img
    configure(env, "ShaderNodeTexEnvironment", interpolation="Closest",
              projection="EQUIRECTANGULAR")
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = lj["strength"]
    out = nt.nodes.new("ShaderNodeOutputWorld")
    nt.links.new(coord.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])


def build_light(lj, world, folder):
    """The job's lights as objects to link: none for an environment (it is
    the world), one per light of a group."""
    if lj["type"] == "group":
        return [o for m in lj["lights"] for o in build_light(m, world, folder)]
    if lj["type"] == "environment":
        build_environment(world, lj, folder)
        return []
    return [build_sun(lj) if lj["type"] == "sun" else build_area_light(lj)]


def build_scene(job, folder, threads, keep=None, keep_material=False):
    """The job's scene; with `keep`, the mesh object of the last job (built
    from the same mesh) stays, with `keep_material` its material too, and
    the rest is built again."""
    if keep is None:
        reset_blender()
        for o in list(bpy.data.objects):
            bpy.data.objects.remove(o, do_unlink=True)
    else:
        clear_all_but(keep, keep_material)
    scene = bpy.context.scene

    scene.world = bpy.data.worlds.new("penumbra_world")  # no nodes: black
    scene.world.use_nodes = False
    scene.world.color = (0.0, 0.0, 0.0)

    cam, r = job["camera"], scene.render
    configure(r, "RenderSettings", engine="CYCLES", film_transparent=True,
              resolution_x=cam["width"], resolution_y=cam["height"],
              resolution_percentage=100, pixel_aspect_x=1.0,
              pixel_aspect_y=1.0, use_border=False, use_motion_blur=False,
              use_compositing=False, use_sequencer=False,
              dither_intensity=0.0, use_file_extension=False,
              threads_mode="FIXED" if threads else "AUTO")
    if threads:
        r.threads = threads
    for attr in dir(r):  # no stamp in pixels or header
        if attr.startswith("use_stamp") and getattr(r, attr):
            setattr(r, attr, False)
    configure(scene.cycles, "Scene.cycles", device="CPU",
              feature_set="SUPPORTED", samples=job["render"]["samples"],
              seed=job["render"]["seed"], use_animated_seed=False,
              use_adaptive_sampling=False, use_denoising=False,
              sample_clamp_direct=0.0, sample_clamp_indirect=0.0,
              blur_glossy=0.0, pixel_filter_type="BOX", filter_width=1.0,
              max_bounces=0, diffuse_bounces=0, glossy_bounces=0,
              transmission_bounces=0, volume_bounces=0,
              transparent_max_bounces=0, min_light_bounces=0,
              min_transparent_bounces=0, caustics_reflective=False,
              caustics_refractive=False, light_sampling_threshold=0.0,
              sample_offset=0, time_limit=0.0, film_exposure=1.0,
              use_fast_gi=False, use_layer_samples="IGNORE")
    if scene.view_layers[0].samples != 0:
        scene.view_layers[0].samples = 0
    configure(r.image_settings, "ImageFormatSettings",
              file_format="OPEN_EXR", color_mode="RGBA", color_depth="32",
              exr_codec="ZIP", use_zbuffer=False, use_preview=False,
              color_management="FOLLOW_SCENE")
    if scene.display_settings.display_device != "sRGB":
        scene.display_settings.display_device = "sRGB"
    configure(scene.view_settings, "ColorManagedViewSettings",
              view_transform="Standard", look="None", exposure=0.0,
              gamma=1.0, use_curve_mapping=False)

    cd = bpy.data.cameras.new("penumbra_camera")
    if cam["projection"] == "orthographic":  # ortho_scale: larger side
        configure(cd, "Camera", type="ORTHO", ortho_scale=cam["ortho_scale"],
                  sensor_fit="AUTO")
    else:  # horizontal field of view from sensor width and focal length
        configure(cd, "Camera", type="PERSP", lens_unit="MILLIMETERS",
                  sensor_width=cam["sensor_width"], lens=cam["lens"],
                  sensor_fit="HORIZONTAL")
    configure(cd, "Camera", shift_x=0.0, shift_y=0.0, clip_start=1e-4,
              clip_end=1e4)
    cd.dof.use_dof = False
    co = bpy.data.objects.new("penumbra_camera", cd)
    co.matrix_world = Matrix(cam["matrix_world"])
    scene.camera = co

    lights = build_light(job["light"], scene.world, folder)
    ob = build_mesh(job, folder) if keep is None else keep
    if not (keep is not None and keep_material):
        build_material(job, ob, folder)
    for o in [co, *lights] + ([] if keep is not None else [ob]):
        scene.collection.objects.link(o)
    return ob


# A serving process keeps the mesh object of its last job, and its material,
# with the digests of what they were built from (mesh_digest,
# material_digest). A job that differs only in its light and material (a
# variant's methods, variants that differ in light) builds the rest again,
# and Cycles keeps what it synced (persistent data): the mesh build is saved,
# and with the same material also the shader compilation and the BVH. The
# pixels are those of a fresh process (tested against one process per job:
# Renderers.ServedBlenderJobsAreBitIdenticalToOne...).
KEPT = {"mesh": None, "material": None, "object": None}


# -------------------------------------------------------------------- main

def write_exr(scene, raw, tmp):
    """Save the render result without Cycles' timing metadata.

    Cycles stamps render and sync times into the EXR header, so identical
    renders would differ in bytes; the pixels are copied (bit-exact) into a
    plain float image, which is saved with the same settings.
    """
    bpy.data.images["Render Result"].save_render(raw, scene=scene)
    src = bpy.data.images.load(raw)
    w, h = src.size
    if (w, h) != (scene.render.resolution_x, scene.render.resolution_y):
        raise JobError(f"render result is {w}x{h}, expected "
                       f"{scene.render.resolution_x}x"
                       f"{scene.render.resolution_y}")
    px = np.empty(w * h * 4, dtype=np.float32)
    src.pixels.foreach_get(px)
    dst = bpy.data.images.new("penumbra_result", w, h, alpha=True,
                              float_buffer=True)
    dst.alpha_mode = "PREMUL"
    dst.pixels.foreach_set(px)
    dst.save_render(tmp, scene=scene)
    if not os.path.isfile(tmp):
        raise JobError(f"{tmp}: EXR was not written")


USAGE = ("usage: blender -b -t 1 --factory-startup -noaudio --python-exit-code 1 "
         "--python blender_render.py -- (JOB.json OUTPUT.exr [--threads N] "
         "| --serve)")
REQUEST = {"job": ("path",), "output": ("path",), "threads": ("int", 1, 1024)}


def parse_args(argv):
    """(job, output, threads) for one job; None for --serve."""
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    if args == ["--serve"]:
        return None
    threads = 0
    if len(args) == 4 and args[2] == "--threads":
        threads = int(args[3]) if args[3].isdigit() else -1
        if not 1 <= threads <= 1024:
            raise JobError(f"--threads: expected an integer in [1, 1024], "
                           f"got {args[3]!r}")
        args = args[:2]
    if len(args) != 2:
        raise JobError(USAGE)
    return args[0], args[1], threads


def kept_what(keep, keep_material):
    if keep is None:
        return ""
    return "mesh and material kept, " if keep_material else "mesh kept, "


def render_job(job_path, out_path, threads, serving=False):
    """Render one job file into out_path (atomically); one log line."""
    try:
        with open(job_path, "rb") as f:
            job = json.loads(f.read().decode("utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise JobError(f"{job_path}: cannot read JSON job: {e}") from None
    out_path = os.path.abspath(out_path)
    if not os.path.isdir(os.path.dirname(out_path)):
        raise JobError(f"{out_path}: output folder does not exist")
    t0 = time.monotonic()
    folder = os.path.dirname(os.path.abspath(job_path))
    kept, KEPT["object"] = KEPT["object"], None  # a failure keeps nothing
    try:
        check(job, SCHEMA)
        if exact_normals_as_attribute(job) and not single_threaded():
            raise JobError(
                "/shading/mode: \"mesh\" renders the same pixels run after "
                "run only on one thread: start Blender with -t 1 (see the "
                "usage at the top of blender_render.py)")
        digests = ((mesh_digest(job, folder), material_digest(job, folder))
                   if serving else (None, None))
        keep = (kept if digests[0] is not None and digests[0] == KEPT["mesh"]
                else None)
        keep_material = keep is not None and digests[1] == KEPT["material"]
        ob = build_scene(job, folder, threads, keep, keep_material)
    except JobError as e:
        raise JobError(f"{job_path}: {e}") from None
    t1 = time.monotonic()
    tmp = f"{out_path}.tmp-{os.getpid()}.exr"
    raw = f"{out_path}.raw-{os.getpid()}.exr"
    scene = bpy.context.scene
    scene.render.use_persistent_data = serving
    try:
        result = bpy.ops.render.render(write_still=False)
        t2 = time.monotonic()
        if "FINISHED" not in result:
            raise JobError(f"render failed ({', '.join(sorted(result))})")
        write_exr(scene, raw, tmp)
        # The line goes out before the image appears: a serving process's
        # caller copies the job's log lines as soon as it sees the image.
        print(f"{PROG}: {summary(job, ob, scene)}, "
              f"{kept_what(keep, keep_material)}setup {t1 - t0:.2f} s, "
              f"render {t2 - t1:.2f} s -> {out_path}", flush=True)
        os.replace(tmp, out_path)
        if serving:
            KEPT.update(mesh=digests[0], material=digests[1], object=ob)
    finally:
        for name in (raw, tmp):
            if os.path.exists(name):
                os.remove(name)


def normals_note(job):
    if job["mesh"]["faces"] != "smooth":
        return ""
    return (" (normals as an attribute)" if exact_normals_as_attribute(job)
            else " (custom normals)")


def summary(job, ob, scene):
    """What was rendered, for the job's log."""
    return (f"{len(ob.data.vertices)} vertices, "
            f"{len(ob.data.polygons)} {job['mesh']['faces']} triangles"
            f"{normals_note(job)}, mode {job['shading']['mode']}, geometry offset "
            f"{ob.cycles.shadow_terminator_geometry_offset:g}, "
            f"{scene.cycles.samples} samples, "
            f"{scene.render.resolution_x}x{scene.render.resolution_y}, "
            f"{scene.render.threads} threads")


def answer_error(out_path, message):
    """OUT.exr.error, renamed into place: the server's answer to a failure."""
    tmp = f"{out_path}.error.tmp-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(message.replace("\n", " ") + "\n")
    os.replace(tmp, f"{out_path}.error")


def serve_request(line):
    """One request line; failures of the job become its .error answer."""
    try:
        request = json.loads(line)
        check(request, REQUEST)
    except (ValueError, JobError) as e:  # no output to answer on: fatal
        raise JobError(f"bad request on stdin: {e}") from None
    out_path = request["output"]
    try:
        render_job(request["job"], out_path, request["threads"], serving=True)
    except (JobError, OSError) as e:
        message = f"{PROG}: {e}"
    except Exception as e:  # noqa: BLE001 - answer, then serve on
        message = f"{PROG}: internal error: {type(e).__name__}: {e}"
    else:
        return
    print(message, file=sys.stderr, flush=True)
    answer_error(out_path, message)


def main():
    problem = blender_version_problem(bpy.app.version)
    if problem:
        raise JobError(problem)
    args = parse_args(sys.argv)
    if args is not None:
        render_job(*args)
        return
    print(f"{PROG}: serving (Blender {bpy.app.version_string})", flush=True)
    for line in sys.stdin:
        if line.strip():
            serve_request(line)


if __name__ == "__main__":
    try:
        main()
    except (JobError, OSError) as e:
        print(f"{PROG}: {e}", file=sys.stderr, flush=True)
        sys.exit(1)
    except Exception as e:  # noqa: BLE001 - any failure must be one line
        print(f"{PROG}: internal error: {type(e).__name__}: {e}",
              file=sys.stderr, flush=True)
        sys.exit(1)
