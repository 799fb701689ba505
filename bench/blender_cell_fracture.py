# SPDX-License-Identifier: GPL-3.0-or-later
# Blender's Cell Fracture (the object_fracture_cell add-on) on a model, timed: the untextured
# baseline of `texfab fracture` (docs/measurements.md). Usage:
#   blender -b --factory-startup --python bench/blender_cell_fracture.py -- model.obj PIECES
import sys
import time

import addon_utils
import bpy

args = sys.argv[sys.argv.index("--") + 1:]
path, pieces = args[0], int(args[1])
addon_utils.enable("object_fracture_cell", default_set=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
addon_utils.enable("object_fracture_cell", default_set=True)
bpy.ops.import_scene.obj(filepath=path)
model = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = model
start = time.perf_counter()
bpy.ops.object.add_fracture_cell_objects(source={'VERT_OWN'}, source_limit=pieces, source_noise=0.0)
seconds = time.perf_counter() - start
made = [o for o in bpy.data.objects if o.name.startswith(model.name + "_cell")]
print(f"cell fracture: {len(made)} pieces in {seconds:.2f} s")
