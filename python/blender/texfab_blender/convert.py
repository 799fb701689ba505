# SPDX-License-Identifier: GPL-3.0-or-later
# Between Blender's data and texfab's arrays: meshes, images, materials. Main thread only.
import math

import bpy
import numpy as np


def read(collection, attribute, dtype, width=1):
    """A per-item attribute of a Blender collection as a numpy array (N, width), or (N,) for width 1."""
    array = np.empty(len(collection) * width, dtype)
    collection.foreach_get(attribute, array)
    return array.reshape(-1, width) if width > 1 else array


def object_triangles(context, obj):
    """The object's evaluated mesh (modifiers applied), triangulated, in the object's own frame:
    float32 vertices (N, 3), uint32 triangles (M, 3), and whether most of its faces are smooth."""
    if obj.mode == 'EDIT':
        obj.update_from_editmode()
    evaluated = obj.evaluated_get(context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        vertices = read(mesh.vertices, "co", np.float32, 3)
        triangles = read(mesh.loop_triangles, "vertices", np.int32, 3).astype(np.uint32)
        smooth = bool(len(mesh.polygons)) and read(mesh.polygons, "use_smooth", bool).mean() > 0.5
    finally:
        evaluated.to_mesh_clear()
    return vertices, triangles, smooth


def new_mesh(name, source, smooth, offset=(0.0, 0.0, 0.0)):
    """A Blender mesh of a texfab.Mesh, its vertices moved by -offset: UV map "texfab" from its
    per-corner UVs, face material indices from face_materials; cut faces (face_tags 1) are flat,
    the others smooth if `smooth`. Materials are left to the caller."""
    vertices = np.asarray(source.vertices, np.float32) - np.asarray(offset, np.float32)
    triangles = np.asarray(source.triangles, np.int32)
    count = len(triangles)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.loops.add(3 * count)
    mesh.polygons.add(count)
    mesh.vertices.foreach_set("co", vertices.ravel())
    mesh.loops.foreach_set("vertex_index", triangles.ravel())
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * count, 3, dtype=np.int32))
    if not bpy.types.MeshPolygon.bl_rna.properties["loop_total"].is_readonly:  # Blender < 3.6
        mesh.polygons.foreach_set("loop_total", np.full(count, 3, np.int32))
    mesh.polygons.foreach_set("material_index", np.asarray(source.face_materials, np.int32))
    cut = np.asarray(source.face_tags) == 1
    mesh.polygons.foreach_set("use_smooth", smooth & ~cut)
    if smooth and cut.any() and hasattr(mesh, "use_auto_smooth"):
        # Before Blender 4.1, flat faces bound smooth ones' normals only with auto smooth.
        mesh.use_auto_smooth = True
        mesh.auto_smooth_angle = math.pi
    mesh.update(calc_edges=True)
    if source.uvs is not None:
        mesh.uv_layers.new(name="texfab").data.foreach_set("uv", np.asarray(source.uvs, np.float32).ravel())
    return mesh


def new_image(name, pixels, colorspace):
    """A Blender image of a texfab image (H, W, C), top row first, packed into the .blend file.
    8 bits per channel: texfab's 8-bit values come back exactly."""
    array = np.asarray(pixels, np.float32)
    array = array[:, :, None] if array.ndim == 2 else array
    height, width, channels = array.shape
    rgba = np.ones((height, width, 4), np.float32)
    rgba[:, :, :3] = array[:, :, :3] if channels >= 3 else array[:, :, :1]
    if channels in (2, 4):
        rgba[:, :, 3] = array[:, :, -1]
    image = bpy.data.images.new(name, width, height, alpha=channels in (2, 4))
    image.colorspace_settings.name = colorspace
    image.pixels.foreach_set(rgba[::-1].ravel())  # Blender's rows go bottom up
    image.pack()
    return image


def image_node(tree, image, y):
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    node.location = (-700, y)
    return node


def new_material(name, base_color=None, normal=None, metallic_roughness=None, factors=None):
    """A material whose Principled BSDF reads the given texfab images: base colour (sRGB), normal map
    (tangent space, through a Normal Map node), roughness (the metallic-roughness image's G, as
    glTF's); `factors`, a texfab.Material, gives the values no image gives (metallic: its factor)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    bsdf = next(node for node in tree.nodes if node.type == 'BSDF_PRINCIPLED')
    if factors is not None:
        bsdf.inputs["Base Color"].default_value = [float(v) for v in factors.base_color_factor]
        bsdf.inputs["Roughness"].default_value = factors.roughness_factor
        bsdf.inputs["Metallic"].default_value = factors.metallic_factor
    if base_color is not None:
        texture = image_node(tree, new_image(name + " base color", base_color, 'sRGB'), 300)
        tree.links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    if metallic_roughness is not None:
        texture = image_node(tree, new_image(name + " metallic-roughness", metallic_roughness, 'Non-Color'), 0)
        separate = tree.nodes.new("ShaderNodeSeparateColor")
        separate.location = (-400, 0)
        tree.links.new(texture.outputs["Color"], separate.inputs["Color"])
        tree.links.new(separate.outputs["Green"], bsdf.inputs["Roughness"])
    if normal is not None:
        texture = image_node(tree, new_image(name + " normal", normal, 'Non-Color'), -300)
        normal_map = tree.nodes.new("ShaderNodeNormalMap")
        normal_map.location = (-400, -300)
        tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
        tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    return material


def texfab_material(name, source):
    """A Blender material of a texfab.Material."""
    return new_material(name, source.base_color, source.normal, source.metallic_roughness, source)
