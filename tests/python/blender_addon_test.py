# SPDX-License-Identifier: GPL-3.0-or-later
# Tests the Blender add-on (python/blender/texfab_blender) headless: it registers, and its three
# operators (run as scripts run them: execute, synchronously) texture, fracture and slice the bundled
# elephant as texfab's command line and module do. Run through scripts/blender-addon-check.sh:
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS -- REPO WORK [TEXFAB_PYTHON_DIR]
# TEXFAB_PYTHON_DIR (default REPO/build/python) holds the texfab module; the command line is the
# texfab beside it (../apps/texfab). Prints "blender-addon-test: ok"; any failure raises (exit code 1).
import json
import os
import shutil
import subprocess
import sys

import addon_utils
import bpy
import numpy as np
from mathutils import Matrix, Vector

args = sys.argv[sys.argv.index("--") + 1:]
REPO, WORK = os.path.abspath(args[0]), os.path.abspath(args[1])
MODULE_DIR = os.path.abspath(args[2] if len(args) > 2 else os.path.join(REPO, "build", "python"))
CLI = os.path.join(os.path.dirname(MODULE_DIR), "apps", "texfab")
BRICK = os.path.join(REPO, "models", "exemplars", "brick.png")
MARBLE = os.path.join(REPO, "models", "exemplars", "marble.png")
ELEPHANT = os.path.join(REPO, "models", "meshes", "elephant.off")


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def log(message):
    print("blender-addon-test: " + message, flush=True)


def install_addon():
    """Enables a copy of the add-on (the source tree stays free of __pycache__) with the module folder set."""
    addons = os.path.join(WORK, "addons")
    shutil.copytree(os.path.join(REPO, "python", "blender", "texfab_blender"),
                    os.path.join(addons, "texfab_blender"), ignore=shutil.ignore_patterns("__pycache__", "*.toml"))
    sys.path.insert(0, addons)

    def fail(error):
        raise error
    check(addon_utils.enable("texfab_blender", default_set=True, handle_error=fail), "the add-on did not enable")
    bpy.context.preferences.addons["texfab_blender"].preferences.module_folder = MODULE_DIR
    check({"texture", "fracture", "slices"} <= set(dir(bpy.ops.texfab)), "operators missing: %s" % dir(bpy.ops.texfab))
    check(hasattr(bpy.types, "VIEW3D_PT_texfab") and hasattr(bpy.types.Scene, "texfab"), "panel or settings missing")


def add_object(name, source, matrix=Matrix()):
    """A mesh object of a texfab.Mesh, built without the add-on, active and selected."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(source.vertices.tolist(), [], source.triangles.tolist())
    obj = bpy.data.objects.new(name, mesh)
    obj.matrix_world = matrix
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def image_array(image):
    """A Blender image's pixels as texfab's (H, W, 4) arrays, top row first."""
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(height, width, 4)[::-1]


def linked_image(socket, through=None):
    """The image of the Image Texture node feeding `socket` (through one node of type `through`)."""
    check(socket.is_linked, socket.name + " is not linked")
    node = socket.links[0].from_node
    if through is not None:
        check(node.type == through, "%s: %s, not %s" % (socket.name, node.type, through))
        node = node.inputs["Color"].links[0].from_node
    check(node.type == 'TEX_IMAGE' and node.image is not None, socket.name + ": no image texture")
    check(node.image.packed_file is not None, node.image.name + " is not packed")
    return node.image


def same_image(image, expected, what):
    expected = np.asarray(expected, np.float32)
    expected = expected[:, :, None] if expected.ndim == 2 else expected
    actual = image_array(image)
    check(actual.shape[:2] == expected.shape[:2], "%s: %s, expected %s" % (what, actual.shape, expected.shape))
    channels = min(expected.shape[2], 3)
    error = np.abs(actual[:, :, :channels] - expected[:, :, :channels]).max()
    check(error <= 1 / 255 + 1e-6, "%s differs from the command line's by %g" % (what, error))


def test_error(texfab, obj):
    """A texfab error is reported and leaves the object as it was."""
    settings = bpy.context.scene.texfab
    settings.exemplar = os.path.join(WORK, "missing.png")
    mesh = obj.data
    try:
        bpy.ops.texfab.texture()
    except RuntimeError as error:  # what bpy.ops raises for an operator's error report
        message = str(error).strip()
    else:
        raise AssertionError("a missing exemplar was not reported")
    check("missing.png" in message and "Traceback" not in message, "not texfab's error: " + message)
    log("an error is reported: " + message)
    check(obj.data == mesh and not mesh.materials, "the failed operator changed the object")


def test_texture(texfab, obj, source):
    """The textured object has the material, UVs and images, equal to the command line's."""
    settings = bpy.context.scene.texfab
    settings.exemplar, settings.normal_map, settings.roughness_map = BRICK, BRICK, BRICK
    check(bpy.ops.texfab.texture() == {'FINISHED'}, "texture did not finish")
    mesh = obj.data
    check(mesh.uv_layers.get("texfab") is not None, "no UV map texfab")
    check(len(mesh.uv_layers["texfab"].data) == len(mesh.loops), "not one UV per loop")
    material = mesh.materials[0]
    check(material.name.startswith("texfab brick"), "material " + material.name)
    bsdf = next(n for n in material.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    base_color = linked_image(bsdf.inputs["Base Color"])
    check(tuple(base_color.size) == (256, 256), "atlas size %s" % (tuple(base_color.size),))
    check(base_color.colorspace_settings.name == 'sRGB', "base colour is not sRGB")
    normal = linked_image(bsdf.inputs["Normal"], through='NORMAL_MAP')
    check(normal.colorspace_settings.name == 'Non-Color', "normal map is not Non-Color")
    roughness = linked_image(bsdf.inputs["Roughness"], through='SEPARATE_COLOR')

    source.save(os.path.join(WORK, "input.glb"))
    subprocess.run([CLI, "texture", os.path.join(WORK, "input.glb"), "-e", BRICK, "-o", os.path.join(WORK, "cli.glb"),
                    "--resolution", "256", "--seed", "1", "--direction", "0,0,1", "-q",
                    "--maps", "normal=%s,roughness=%s" % (BRICK, BRICK)], check=True)
    cli = texfab.load_mesh(os.path.join(WORK, "cli.glb"))
    same_image(base_color, cli.materials[0].base_color, "base colour")
    same_image(normal, cli.materials[0].normal, "normal map")
    same_image(roughness, cli.materials[0].metallic_roughness, "metallic-roughness")
    uvs = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers["texfab"].data.foreach_get("uv", uvs)
    check(np.allclose(np.sort(uvs.reshape(-1, 2), axis=0), np.sort(cli.uvs.reshape(-1, 2), axis=0), atol=1e-5),
          "UVs differ from the command line's")
    log("texture: %d faces, %dx%d atlas, images equal to the command line's" % (
        len(mesh.polygons), *base_color.size))


def test_fracture(texfab, source):
    """The pieces are the module's, placed at their centroids, with both materials and rigid bodies."""
    matrix = Matrix.LocRotScale(Vector((1, 2, 3)), Matrix.Rotation(0.5, 3, 'Z').to_quaternion(), Vector((2, 2, 2)))
    obj = add_object("broken", source, matrix)
    settings = bpy.context.scene.texfab
    settings.exemplar, settings.interior, settings.mode, settings.pieces = BRICK, MARBLE, 'solid', 4
    check(bpy.ops.texfab.fracture() == {'FINISHED'}, "fracture did not finish")
    expected = texfab.fracture(source, pieces=4, exemplar=BRICK, interior=MARBLE, mode="solid", resolution=256, seed=1)
    objects = {o.name: o for o in bpy.data.collections["broken pieces"].objects}
    check(len(objects) == len(expected.pieces) > 1, "%d pieces, expected %d" % (len(objects), len(expected.pieces)))
    for piece in expected.pieces:
        o = objects[piece.name]
        check((o.matrix_world.translation - matrix @ Vector(piece.centroid)).length < 1e-5, o.name + ": origin")
        world = np.array([o.matrix_world @ v.co for v in o.data.vertices])
        model = np.array([matrix @ Vector(v) for v in piece.mesh.vertices.astype(np.float64)])
        check(np.allclose(world, model, atol=1e-4), o.name + ": vertices moved")
        names = [m.name for m in o.data.materials]
        check(len(names) == 2 and "outer" in names[0] and "interior" in names[1], o.name + ": materials %s" % names)
        for m in o.data.materials:
            bsdf = next(n for n in m.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
            linked_image(bsdf.inputs["Base Color"])
        check(len(o.data.uv_layers["texfab"].data) == len(o.data.loops), o.name + ": UVs")
        check(o.rigid_body is not None and o.rigid_body.type == 'ACTIVE', o.name + ": no rigid body")
    check(obj.hide_get(), "the original is not hidden")
    log("fracture: %d pieces, as the module's" % len(objects))


def test_slices(obj):
    """The slice folder holds the manifest and every layer it names."""
    bpy.context.view_layer.objects.active = obj
    settings = bpy.context.scene.texfab
    folder = os.path.join(WORK, "slices")
    settings.slice_folder, settings.slice_height, settings.slice_dpi, settings.slice_layer = folder, 5.0, (100, 100), 0.5
    check(bpy.ops.texfab.slices() == {'FINISHED'}, "slices did not finish")
    with open(os.path.join(folder, "slices.json")) as file:
        manifest = json.load(file)
    files = [entry["file"] for entry in manifest["files"]]
    check(len(files) == manifest["layers"]["count"] > 0, "layers: %s" % manifest["layers"])
    check(all(os.path.isfile(os.path.join(folder, f)) for f in files), "a layer image is missing")
    log("slices: %d layers" % len(files))


def test_cancel(texfab, source):
    """A job whose progress asks to stop ends in texfab.Cancelled."""
    from texfab_blender.operators import Job
    job = Job(lambda progress: texfab.texture_mesh(source, BRICK, resolution=256, progress=progress))
    job.cancel = True
    job.thread.join()
    check(isinstance(job.error, texfab.Cancelled), "not cancelled: %r" % job.error)
    log("cancel: texfab.Cancelled after stage %r" % job.stage)


def test_saved():
    """Packed images survive saving and reopening the file."""
    path = os.path.join(WORK, "saved.blend")
    before = {i.name: image_array(i) for i in bpy.data.images if i.name.startswith("texfab")}
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    for name, pixels in before.items():
        check(np.array_equal(image_array(bpy.data.images[name]), pixels), name + " changed in the saved file")
    log("saved: %d images packed" % len(before))


def main():
    os.makedirs(WORK, exist_ok=True)
    os.environ.setdefault("TEXFAB_CACHE_DIR", os.path.join(WORK, "cache"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    install_addon()
    import texfab
    source = texfab.load_mesh(ELEPHANT)
    bpy.context.scene.texfab.resolution = '256'
    obj = add_object("elephant", source)
    test_error(texfab, obj)
    test_texture(texfab, obj, source)
    test_fracture(texfab, source)
    test_slices(obj)
    test_cancel(texfab, source)
    test_saved()
    log("ok")


main()
