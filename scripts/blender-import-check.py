# SPDX-License-Identifier: GPL-3.0-or-later
# Imports models into Blender (headless) and checks what a user would see: a material whose base
# colour comes from an image texture, a normal map connected through a Normal Map node, and as
# many UV islands as the atlas has charts. Run through scripts/blender-import-check.sh:
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS -- MODEL[:CHARTS] ...
# MODEL is a .glb/.gltf or .obj; CHARTS (optional) the atlas's chart count; ":normal" after it
# requires the normal map. Prints one line per model and raises (exit code 1) on any failure.
import sys

import bpy

# Debian 12's Blender 3.4 glTF importer uses numpy's `np.bool`, which Debian 12's numpy 1.24 no
# longer has: every glTF import fails (KhronosGroup/glTF-Blender-IO#1844, fixed in Blender 3.5).
# The alias restores it for this process.
try:
    import numpy
    if not hasattr(numpy, "bool"):
        numpy.bool = bool
except ImportError:
    pass


def upstream_nodes(socket, seen=None):
    """Every node that feeds `socket`, through any chain of links."""
    seen = set() if seen is None else seen
    nodes = []
    for link in socket.links:
        node = link.from_node
        if node.name in seen:
            continue
        seen.add(node.name)
        nodes.append(node)
        for inp in node.inputs:
            nodes.extend(upstream_nodes(inp, seen))
    return nodes


def image_feeding(socket):
    for node in upstream_nodes(socket):
        if node.type == "TEX_IMAGE" and node.image is not None and node.image.size[0] > 0:
            return node.image
    return None


def uv_islands(mesh):
    """Faces connected through corners that share a position and a UV, as Blender's UV tools do."""
    uv = mesh.uv_layers.active.data
    parent = list(range(len(mesh.polygons)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner = {}
    for poly in mesh.polygons:
        for li in poly.loop_indices:
            co = mesh.vertices[mesh.loops[li].vertex_index].co
            key = (round(co.x, 5), round(co.y, 5), round(co.z, 5), round(uv[li].uv.x, 6), round(uv[li].uv.y, 6))
            if key in owner:
                a, b = find(owner[key]), find(poly.index)
                if a != b:
                    parent[a] = b
            else:
                owner[key] = poly.index
    return len({find(i) for i in range(len(mesh.polygons))})


def check(path, charts, normal):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.lower().endswith((".glb", ".gltf")):
        bpy.ops.import_scene.gltf(filepath=path)
    elif path.lower().endswith(".obj"):
        bpy.ops.wm.obj_import(filepath=path)
    else:
        raise RuntimeError(path + ": not a glTF or OBJ file")
    objects = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if not objects:
        raise RuntimeError(path + ": no mesh imported")
    problems, islands, faces = [], 0, 0
    for obj in objects:
        mesh = obj.data
        faces += len(mesh.polygons)
        if not mesh.uv_layers:
            problems.append("no UVs")
            continue
        islands += uv_islands(mesh)
        materials = [m for m in mesh.materials if m is not None]
        if not materials:
            problems.append("no material")
        for m in materials:
            bsdf = next((n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if m.use_nodes else None
            if bsdf is None:
                problems.append(m.name + ": no Principled BSDF")
                continue
            if image_feeding(bsdf.inputs["Base Color"]) is None:
                problems.append(m.name + ": base colour is not an image texture")
            normal_map = next((n for n in upstream_nodes(bsdf.inputs["Normal"]) if n.type == "NORMAL_MAP"), None)
            if normal and (normal_map is None or image_feeding(normal_map.inputs["Color"]) is None):
                problems.append(m.name + ": no normal map (Normal Map node fed by an image) on the BSDF's Normal")
    if charts is not None and islands != charts:
        problems.append("%d UV islands, the atlas has %d charts" % (islands, charts))
    print("blender-import-check: %s: %d faces, %d UV islands%s%s" % (
        path, faces, islands, "" if charts is None else " (atlas: %d charts)" % charts,
        ": OK" if not problems else ": FAILED: " + "; ".join(problems)))
    return not problems


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ok = True
    for arg in args:
        parts = arg.split(":")
        path = parts[0]
        charts = int(parts[1]) if len(parts) > 1 and parts[1] else None
        ok = check(path, charts, "normal" in parts[2:]) and ok
    if not args or not ok:
        raise SystemExit(1)


main()
