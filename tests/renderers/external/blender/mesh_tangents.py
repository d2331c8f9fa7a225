"""Blender's own MikkTSpace tangents of an OBJ file, per triangle corner.

A fixed test script, run by Penumbra's test MeshTangents.MatchBlendersOnARealAsset:
    blender -b --factory-startup --python mesh_tangents.py -- IN.obj OUT.json
It imports IN.obj without converting axes, triangulates every mesh, lets
Blender compute its tangents (Mesh.calc_tangents, MikkTSpace over the loop
normals Blender shades with) and writes, per triangle and corner, the
position, loop normal, UV, tangent and bitangent sign Blender used, so the
test computes its tangents from exactly the same inputs.
"""

import json
import sys

import bmesh
import bpy


def corners(mesh):
    uv_layer = mesh.uv_layers.active.data
    out = []
    for polygon in mesh.polygons:
        triangle = []
        for index in polygon.loop_indices:
            loop = mesh.loops[index]
            triangle.append({
                "position": list(mesh.vertices[loop.vertex_index].co),
                "normal": list(loop.normal),
                "uv": list(uv_layer[index].uv),
                "tangent": list(loop.tangent),
                "sign": loop.bitangent_sign,
            })
        out.append(triangle)
    return out


def main():
    source, target = sys.argv[sys.argv.index("--") + 1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)  # no default cube
    bpy.ops.wm.obj_import(filepath=source, forward_axis="Y", up_axis="Z")
    triangles = []
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or not obj.data.uv_layers:
            continue
        mesh = obj.data
        bm = bmesh.new()
        bm.from_mesh(mesh)
        bmesh.ops.triangulate(bm, faces=bm.faces[:])
        bm.to_mesh(mesh)
        bm.free()
        mesh.calc_tangents()
        triangles.extend(corners(mesh))
    with open(target, "w", encoding="utf-8") as out:
        json.dump({"blender": bpy.app.version_string, "triangles": triangles}, out)


main()
