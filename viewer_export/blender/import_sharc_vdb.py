# SPDX-License-Identifier: Apache-2.0
"""Import a cache exported by `sharcbake export-vdb` into Blender, ready to look at.

Blender's own Add > Volume > Import OpenVDB loads the grids but gives them no material, so the
volume renders as dim grey smoke, and leaves the glTF scene's +Y up pointing along Blender's -Y.
This script adds the volume, turns it upright (unless the file was exported with
`sharcbake export-vdb --up z`, which turns it already: then pass --up z here too) and
gives it an emission shader that shows each voxel's cached radiance as its colour: a ray that
crosses one voxel picks up about that voxel's radiance, whatever its size.

Usage (Blender 3.x or later, interactive or headless):

    blender --python import_sharc_vdb.py -- cache.vdb [--level N] [--up y|z] [--strength S]
    blender -b --python import_sharc_vdb.py -- cache.vdb --render still.png [--resolution 256]

--level picks a SHaRC level's grids (levelN_color); by default the finest level (color).
--render renders a still with Cycles from outside the volume's bounds, prints the image's mean
colour as a line "sharcbake_vdb_render: {json}" and quits: a headless check that the import works.
"""

import argparse
import json
import math
import os
import sys

import bpy
import mathutils


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="import_sharc_vdb.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("vdb", help="a .vdb written by sharcbake export-vdb")
    parser.add_argument("--level", type=int, default=None, help="SHaRC level to show (default: the finest)")
    parser.add_argument("--up", choices=["y", "z"], default="y",
                        help="the up axis the file was exported with (export-vdb's default is y, glTF's)")
    parser.add_argument("--strength", type=float, default=1.0, help="multiplies the shown radiance")
    parser.add_argument("--render", metavar="PNG", help="render a still to PNG with Cycles, report, and quit")
    parser.add_argument("--resolution", type=int, default=256, help="--render image size in pixels")
    return parser.parse_args(argv)


def voxel_size(grid):
    """Length of the grid's first index axis in object space (the export's voxels are cubes)."""
    return mathutils.Vector([grid.matrix_object[row][0] for row in range(3)]).length


def add_volume(path, level, up):
    volume = bpy.data.volumes.new("sharc_cache")
    volume.filepath = os.path.abspath(path)
    if not volume.grids.load():
        raise SystemExit(f"import_sharc_vdb: Blender could not read {path}: {volume.grids.error_message}")
    names = [grid.name for grid in volume.grids]
    color_name = ("level%d_" % level if level is not None else "") + "color"
    if color_name not in names:
        raise SystemExit(f"import_sharc_vdb: {path} has no grid '{color_name}'; it has: {', '.join(names)}")
    obj = bpy.data.objects.new("sharc_cache", volume)
    bpy.context.scene.collection.objects.link(obj)
    if up == "y":
        # glTF's (x, y, z) is Blender's (x, -z, y), as Blender's glTF importer maps it.
        obj.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    return obj, volume.grids[color_name]


def add_emission_material(obj, color_grid, strength):
    """Emission from the colour grid, scaled by 1 / voxel size: emission in a volume adds up along
    the ray, and a ray crossing a voxel travels about one voxel size through it."""
    material = bpy.data.materials.new("sharc_radiance")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = color_grid.name
    material.node_tree.links.new(attribute.outputs["Color"], emission.inputs["Color"])
    emission.inputs["Strength"].default_value = strength / voxel_size(color_grid)
    material.node_tree.links.new(emission.outputs["Emission"], output.inputs["Volume"])
    obj.data.materials.append(material)


def render_still(obj, path, resolution):
    """A still from outside the volume's bounds, looking at their centre along Blender's +Y (a
    glTF scene's -Z, where glTF cameras usually look), with a black world and no tone curve."""
    scene = bpy.context.scene
    bpy.context.view_layer.update()
    corners = [obj.matrix_world @ mathutils.Vector(corner) for corner in obj.bound_box]
    low = mathutils.Vector([min(c[i] for c in corners) for i in range(3)])
    high = mathutils.Vector([max(c[i] for c in corners) for i in range(3)])
    centre, size = (low + high) / 2, (high - low).length
    camera = bpy.data.objects.new("sharc_camera", bpy.data.cameras.new("sharc_camera"))
    scene.collection.objects.link(camera)
    camera.location = centre + mathutils.Vector((0.0, -1.2 * size, 0.0))
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    # Blender's default clip range (0.1 to 1000 units) would cut off a volume over about 400 units
    # across (a --length-scale 1000 export, a model in millimetres): a black still, without a word.
    # The range follows the volume: its far side is 1.7 sizes away at most.
    camera.data.clip_start = 1e-3 * size
    camera.data.clip_end = 4.0 * size
    scene.camera = camera
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0.0, 0.0, 0.0)
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    scene.render.resolution_x = scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.abspath(path)
    bpy.ops.render.render(write_still=True)
    report = image_statistics(bpy.data.images.load(os.path.abspath(path)))
    report["file"] = path
    print("sharcbake_vdb_render: " + json.dumps(report))


def image_statistics(image):
    """Mean colour of the image and of its left and right quarters, the share of pixels that are
    not black, and the mean height of its white pixels."""
    width, height = image.size
    pixels = image.pixels[:]  # RGBA rows, bottom row first

    def mean_rgb(columns):
        values = [pixels[4 * (y * width + x) + c] for y in range(height) for x in columns for c in range(3)]
        return [sum(values[c::3]) / (len(values) // 3) for c in range(3)]

    brightness = [sum(pixels[4 * i:4 * i + 3]) for i in range(width * height)]
    white_rows = [i // width for i in range(width * height) if min(pixels[4 * i:4 * i + 3]) > 0.95]
    return {
        "mean_rgb": mean_rgb(range(width)),
        "left_rgb": mean_rgb(range(width // 4)),
        "right_rgb": mean_rgb(range(width - width // 4, width)),
        "lit_fraction": sum(1 for b in brightness if b > 0.06) / (width * height),
        # Where the white (clipped) pixels are, as a share of the height from the top: an
        # emitter's place, which shows which way is up. None without white pixels.
        "white_from_top": 1.0 - (sum(white_rows) / len(white_rows) + 0.5) / height if white_rows else None,
    }


def remove_startup_objects():
    """A new, unsaved file's default cube, light and camera: the cube would hide the volume."""
    if bpy.data.filepath:
        return
    for name in ("Cube", "Light", "Camera"):
        if name in bpy.data.objects:
            bpy.data.objects.remove(bpy.data.objects[name], do_unlink=True)


def main():
    args = parse_arguments()
    remove_startup_objects()
    obj, color_grid = add_volume(args.vdb, args.level, args.up)
    add_emission_material(obj, color_grid, args.strength)
    if args.render:
        render_still(obj, args.render, args.resolution)
        bpy.ops.wm.quit_blender()


main()
