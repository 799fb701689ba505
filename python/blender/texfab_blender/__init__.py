# SPDX-License-Identifier: GPL-3.0-or-later
# texfab for Blender: texture a mesh from an exemplar, fracture it with textured interiors, export
# coloured slices for full-colour 3D printing, through texfab's Python module. A legacy add-on
# (bl_info, Blender 3.4+) and a Blender 4.2+ extension (blender_manifest.toml).
import bpy

from . import operators, props, ui

bl_info = {
    "name": "texfab",
    "author": "texfab developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > texfab",
    "description": "Texture synthesis from an exemplar, fracture with textured interiors, colored slices",
    "category": "Material",
}

classes = props.classes + operators.classes + ui.classes


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.texfab = bpy.props.PointerProperty(type=props.TexfabSettings)


def unregister():
    del bpy.types.Scene.texfab
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
