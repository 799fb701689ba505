# SPDX-License-Identifier: GPL-3.0-or-later
# The texfab tab of the 3D viewport's sidebar (N).
import bpy


class VIEW3D_PT_texfab(bpy.types.Panel):
    bl_label = "texfab"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "texfab"

    def draw(self, context):
        s = context.scene.texfab
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        section(layout, "Material", s, ("exemplar", "interior", "normal_map", "roughness_map"))
        section(layout, "Synthesis", s, ("mode", "resolution", "texture_scale", "seed", "solid_method"))
        layout.operator("texfab.texture", icon='TEXTURE')
        section(layout, "Fracture", s, ("pieces", "rigid_bodies"))
        layout.operator("texfab.fracture", icon='MOD_EXPLODE')
        section(layout, "Slices", s, ("slice_folder", "slice_height", "slice_dpi", "slice_layer", "slice_replace"))
        layout.operator("texfab.slices", icon='RENDERLAYERS')


def section(layout, title, settings, names):
    box = layout.box()
    box.label(text=title)
    for name in names:
        box.prop(settings, name)


classes = (VIEW3D_PT_texfab,)
