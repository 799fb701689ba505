# SPDX-License-Identifier: GPL-3.0-or-later
# The operators. Each reads its inputs on the main thread (prepare), runs texfab (work) and writes the
# result into the scene on the main thread (apply). Invoked from the interface, the work runs on a
# worker thread while a timer shows its progress and Esc cancels it; from execute() (scripts,
# background mode) it runs at once.
import os
import sys
import threading

import bpy
import numpy as np
from mathutils import Matrix

from . import convert


class UserError(Exception):
    """A problem the user can fix, reported as an error."""


def import_texfab(context):
    """The texfab module, after adding the preferences' module folder to sys.path."""
    addon = context.preferences.addons.get(__package__)
    folder = bpy.path.abspath(addon.preferences.module_folder) if addon else ""
    if folder and folder not in sys.path:
        sys.path.insert(0, folder)
    try:
        import texfab
    except ImportError as error:
        raise UserError("cannot import the texfab Python module (%s): install it, or set its folder "
                        "in the texfab add-on's preferences" % error) from error
    return texfab


def backend(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences.backend if addon else "cpu"


def file_path(path, what, required=True):
    """An absolute path of a file property, None when empty and not required."""
    if not path:
        if required:
            raise UserError("choose the %s file in the texfab panel" % what)
        return None
    return bpy.path.abspath(path)


def stem(path):
    return os.path.splitext(os.path.basename(path))[0]


class Job:
    """texfab's work on a worker thread; texfab calls `progress` back, without touching Blender."""
    running = None

    def __init__(self, work):
        self.stage, self.fraction = "starting", 0.0
        self.cancel = False
        self.result = self.error = None
        self.thread = threading.Thread(target=self.run, args=(work,), daemon=True)
        self.thread.start()

    def progress(self, stage, fraction):
        self.stage, self.fraction = stage, fraction
        return not self.cancel

    def run(self, work):
        try:
            self.result = work(self.progress)
        except BaseException as error:  # reported on the main thread
            self.error = error


class TexfabOperator:
    """The common part: poll, the synchronous and the modal runs, reports."""
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        if obj is None or obj.type != 'MESH':
            cls.poll_message_set("Select a mesh object")
        elif context.mode != 'OBJECT':
            cls.poll_message_set("Switch to Object Mode")
        elif Job.running is not None:
            cls.poll_message_set("texfab is busy")
        else:
            return True
        return False

    def execute(self, context):
        try:
            return self.finish(context, self.prepare(context)(None))
        except Exception as error:
            return self.fail(error)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        try:
            work = self.prepare(context)
        except Exception as error:
            return self.fail(error)
        Job.running = self.job = Job(work)
        wm = context.window_manager
        self.timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        if event.type == 'ESC' and event.value == 'PRESS':
            self.job.cancel = True
            return {'RUNNING_MODAL'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        job = self.job
        if job.thread.is_alive():
            context.window_manager.progress_update(100 * job.fraction)
            context.workspace.status_text_set("texfab: %s %d%%" % (job.stage, round(100 * job.fraction)))
            return {'PASS_THROUGH'}
        self.stop(context)
        if job.error is not None:
            return self.fail(job.error)
        try:
            return self.finish(context, job.result)
        except Exception as error:
            return self.fail(error)

    def cancel(self, context):
        self.job.cancel = True
        self.stop(context)

    def stop(self, context):
        Job.running = None
        context.window_manager.event_timer_remove(self.timer)
        context.window_manager.progress_end()
        context.workspace.status_text_set(None)

    def finish(self, context, result):
        self.report({'INFO'}, "texfab: " + self.apply(context, result))
        return {'FINISHED'}

    def fail(self, error):
        texfab = sys.modules.get("texfab")
        if texfab is not None and isinstance(error, texfab.Cancelled):
            self.report({'WARNING'}, "texfab: cancelled")
        elif isinstance(error, UserError) or (texfab is not None and isinstance(error, texfab.Error)):
            self.report({'ERROR'}, str(error))
        else:
            raise error  # a bug: Blender prints its traceback (the worker's, for the worker's errors)
        return {'CANCELLED'}

    def source(self, context):
        """The active object's triangles for texfab; remembers the object for apply()."""
        obj = context.active_object
        self.object_name = obj.name
        vertices, triangles, self.smooth = convert.object_triangles(context, obj)
        if len(triangles) == 0:
            raise UserError("%s has no faces" % obj.name)
        return vertices, triangles

    def target(self):
        obj = bpy.data.objects.get(self.object_name)
        if obj is None or obj.type != 'MESH':
            raise UserError("%s was removed while texfab ran" % self.object_name)
        return obj


class TEXFAB_OT_texture(TexfabOperator, bpy.types.Operator):
    """Synthesize a texture over the active object from an exemplar (texfab texture)"""
    bl_idname = "texfab.texture"
    bl_label = "Texture from Exemplar"

    def prepare(self, context):
        texfab = import_texfab(context)
        s = context.scene.texfab
        exemplar = file_path(s.exemplar, "exemplar")
        maps = {name: file_path(path, name) for name, path in
                (("normal", s.normal_map), ("roughness", s.roughness_map)) if path}
        vertices, triangles = self.source(context)
        self.material_name = "texfab " + stem(exemplar)
        options = dict(mode=s.mode, resolution=int(s.resolution), texture_scale=s.texture_scale, seed=s.seed,
                       direction=(0.0, 0.0, 1.0), maps=maps or None, solid_method=s.solid_method,
                       backend=backend(context))
        return lambda progress: texfab.texture_mesh(texfab.Mesh(vertices, triangles), exemplar,
                                                    progress=progress, **options)

    def apply(self, context, result):
        obj = self.target()
        mesh = convert.new_mesh(obj.data.name, result.mesh, self.smooth)
        factors = result.mesh.materials[0] if result.mesh.materials else None
        mesh.materials.append(convert.new_material(self.material_name, result.base_color, result.normal,
                                                   result.metallic_roughness, factors))
        obj.modifiers.clear()  # the result has them applied
        obj.data = mesh
        for warning in result.warnings:
            self.report({'WARNING'}, "texfab: " + warning)
        return "%s textured: %d charts, %g exemplar pixels per unit" % (obj.name, result.charts, result.texture_scale)


class TEXFAB_OT_fracture(TexfabOperator, bpy.types.Operator):
    """Break the active object into pieces whose cut faces show the material's interior (texfab fracture)"""
    bl_idname = "texfab.fracture"
    bl_label = "Fracture with Textured Interiors"

    def prepare(self, context):
        texfab = import_texfab(context)
        s = context.scene.texfab
        exemplar = file_path(s.exemplar, "exemplar")
        interior = file_path(s.interior, "interior exemplar", required=False)
        vertices, triangles = self.source(context)
        self.stems = {"outer": stem(exemplar), "interior": stem(interior or exemplar)}
        self.rigid_bodies = s.rigid_bodies
        options = dict(pieces=s.pieces, exemplar=exemplar, interior=interior, mode=s.mode,
                       texture_scale=s.texture_scale, resolution=int(s.resolution), seed=s.seed,
                       solid_method=s.solid_method, backend=backend(context))
        return lambda progress: texfab.fracture(texfab.Mesh(vertices, triangles), progress=progress, **options)

    def apply(self, context, model):
        obj = self.target()
        collection = bpy.data.collections.new(obj.name + " pieces")
        context.scene.collection.children.link(collection)
        materials = self.materials(model)
        pieces = [self.piece_object(piece, obj.matrix_world, materials) for piece in model.pieces]
        for piece in pieces:
            collection.objects.link(piece)
        if obj.name in context.view_layer.objects:
            obj.hide_set(True)
        obj.hide_render = True
        if self.rigid_bodies and pieces:
            add_rigid_bodies(context, pieces, model.pieces)
        return "%s broken into %d pieces" % (obj.name, len(pieces))

    def materials(self, model):
        """Blender materials of the pieces' (all pieces have the same: outer..., interior...)."""
        if not model.pieces:
            return []
        interior = set()
        for piece in model.pieces:
            cut = np.asarray(piece.mesh.face_tags) == 1
            interior.update(np.asarray(piece.mesh.face_materials)[cut].tolist())
        made = []
        for index, material in enumerate(model.pieces[0].mesh.materials):
            role = "interior" if index in interior else "outer"
            made.append(convert.texfab_material("texfab %s %s" % (self.stems[role], role), material))
        return made

    def piece_object(self, piece, matrix, materials):
        centroid = np.asarray(piece.centroid, np.float64)
        mesh = convert.new_mesh(piece.name, piece.mesh, self.smooth, offset=centroid)
        for material in materials:
            mesh.materials.append(material)
        obj = bpy.data.objects.new(piece.name, mesh)
        obj.matrix_world = matrix @ Matrix.Translation(centroid)
        return obj


def add_rigid_bodies(context, objects, pieces):
    """Active rigid bodies (convex hulls), their mass in proportion to their volume (1000 per unit³)."""
    with context.temp_override(active_object=objects[0], object=objects[0], selected_objects=objects,
                               selected_editable_objects=objects):
        bpy.ops.rigidbody.objects_add(type='ACTIVE')
    for obj, piece in zip(objects, pieces):
        obj.rigid_body.mass = max(1000.0 * piece.volume * abs(obj.matrix_world.to_3x3().determinant()), 1e-3)


class TEXFAB_OT_slices(TexfabOperator, bpy.types.Operator):
    """Slice the active object into coloured layer images for full-colour 3D printing (texfab slice)"""
    bl_idname = "texfab.slices"
    bl_label = "Export Colored Slices"
    bl_options = {'REGISTER'}

    def prepare(self, context):
        texfab = import_texfab(context)
        s = context.scene.texfab
        exemplar = file_path(s.exemplar, "exemplar")
        if not s.slice_folder:
            raise UserError("choose the slices' folder in the texfab panel")
        self.folder = folder = bpy.path.abspath(s.slice_folder)
        vertices, triangles = self.source(context)
        options = dict(exemplar=exemplar, mode=s.mode, up="z",
                       height_mm=s.slice_height, dpi=tuple(s.slice_dpi), layer_mm=s.slice_layer,
                       texture_scale=s.texture_scale, seed=s.seed, solid_method=s.solid_method,
                       resolution=int(s.resolution), force=s.slice_replace, backend=backend(context))
        return lambda progress: texfab.slice(texfab.Mesh(vertices, triangles), folder, progress=progress, **options)

    def apply(self, context, manifest):
        return "%d layers written to %s" % (manifest["layers"]["count"], self.folder)


classes = (TEXFAB_OT_texture, TEXFAB_OT_fracture, TEXFAB_OT_slices)
