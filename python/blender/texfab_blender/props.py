# SPDX-License-Identifier: GPL-3.0-or-later
# The add-on's options: per scene (scene.texfab), and preferences (where texfab is, its backend).
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, StringProperty

RESOLUTIONS = [(str(1 << n), str(1 << n), "%d x %d texels" % (1 << n, 1 << n)) for n in range(6, 14)]


class TexfabSettings(bpy.types.PropertyGroup):
    exemplar: StringProperty(name="Exemplar", subtype='FILE_PATH',
                             description="Image of the material to synthesize (PNG, JPEG, TIFF, EXR)")
    interior: StringProperty(name="Interior", subtype='FILE_PATH',
                             description="Exemplar of the fracture's cut faces (default: the exemplar)")
    normal_map: StringProperty(name="Normal Map", subtype='FILE_PATH',
                               description="The exemplar's normal map, synthesized with it (optional)")
    roughness_map: StringProperty(name="Roughness Map", subtype='FILE_PATH',
                                  description="The exemplar's roughness map, synthesized with it (optional)")
    mode: EnumProperty(name="Mode", default='surface', items=[
        ('surface', "Surface", "Synthesis over the surface"),
        ('solid', "Solid", "A 3-D material: the object is carved from it, seamless")])
    resolution: EnumProperty(name="Resolution", items=RESOLUTIONS, default='2048',
                             description="Texture atlas size")
    texture_scale: FloatProperty(name="Texture Scale", min=0.0, default=0.0,
                                 description="Exemplar pixels per object unit (0: automatic)")
    seed: IntProperty(name="Seed", min=0, default=1, description="Random seed: the only source of variation")
    solid_method: EnumProperty(name="Solid Method", default='lazy', items=[
        ('lazy', "Lazy", "Each voxel synthesized with its dependency chain"),
        ('tiles', "Tiles", "Matching solid tiles optimized once per exemplar, then fast")])
    pieces: IntProperty(name="Pieces", min=1, max=10000, default=10, description="Fracture pieces")
    rigid_bodies: BoolProperty(name="Add Rigid Bodies", default=True,
                               description="Make the pieces active rigid bodies, ready to simulate")
    slice_folder: StringProperty(name="Folder", subtype='DIR_PATH',
                                 description="Folder of the layer images and slices.json")
    slice_height: FloatProperty(name="Height (mm)", min=0.001, max=10000.0, default=50.0,
                                description="Print height: the object's extent along Z")
    slice_dpi: FloatVectorProperty(name="DPI", size=2, min=1.0, max=100000.0, default=(600.0, 300.0),
                                   description="Printer resolution in dots per inch (X, Y)")
    slice_layer: FloatProperty(name="Layer (mm)", min=0.001, max=10.0, default=0.027, precision=3,
                               description="Layer thickness")
    slice_replace: BoolProperty(name="Replace Folder", default=False,
                                description="Replace an existing, non-empty folder")


class TexfabPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    module_folder: StringProperty(name="texfab Module Folder", subtype='DIR_PATH',
                                  description="Folder holding the texfab Python module, added to Python's "
                                              "path (for a Blender whose Python does not see it)")
    backend: EnumProperty(name="Backend", default='cpu', items=[
        ('cpu', "CPU", "Synthesis on the CPU"),
        ('auto', "Auto", "A Vulkan GPU when there is one, else the CPU"),
        ('vulkan', "Vulkan", "A Vulkan GPU (an error without one)")])

    def draw(self, context):
        self.layout.prop(self, "module_folder")
        self.layout.prop(self, "backend")


classes = (TexfabSettings, TexfabPreferences)
