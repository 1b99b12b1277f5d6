# SPDX-License-Identifier: Apache-2.0
# Blender script for cycles_crosscheck.sh: builds a room the way a Blender user does (a cube scaled
# up, normals pointing out, backface culling off so the exporter writes doubleSided), with a table,
# a 200 W point light and an emissive ceiling panel; exports it to glTF (lights and camera
# included); renders it with Cycles as a linear EXR, both as a plain RGB file and as a multilayer one.
# MODE "metal" makes the table a rough gold-coloured metal and adds a metal sphere.
#
# Cycles is set up to compute the same integral as sharcbake: Lambertian walls (Diffuse BSDF; the
# exported Principled BSDF has Specular 0 and Roughness 1, which sharcbake reads as Lambertian),
# metals as Principled BSDF with Multiscatter GGX (energy-conserving, as sharcbake's GGX is),
# unlimited bounces (Cycles' defaults stop after 4 diffuse bounces), no clamping, no glossy blur,
# no denoising, a point light of zero radius, a black world, the Standard view transform.
#
# Usage: blender -b --factory-startup --python cycles_room.py -- OUT_DIR SAMPLES [diffuse|metal]
import math
import sys

import bpy

arguments = sys.argv[sys.argv.index("--") + 1:]
out_dir, samples = arguments[0], int(arguments[1])
mode = arguments[2] if len(arguments) > 2 else "diffuse"

bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()


def principled_material(name, **inputs):
    """A material whose Principled BSDF has these inputs (names with spaces as underscores)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    principled = material.node_tree.nodes["Principled BSDF"]
    for key, value in inputs.items():
        principled.inputs[key.replace("_", " ")].default_value = value
    return material, principled


wall, _ = principled_material("Wall", Base_Color=(0.7, 0.7, 0.7, 1.0), Specular=0.0, Roughness=1.0)
panel_material, _ = principled_material("Panel", Base_Color=(0.0, 0.0, 0.0, 1.0), Specular=0.0,
                                        Emission=(1.0, 0.9, 0.7, 1.0), Emission_Strength=4.0)

bpy.ops.mesh.primitive_cube_add(size=1, location=(0, 0, 1.5))
room = bpy.context.object
room.name = "Room"
room.scale = (4, 5, 3)
room.data.materials.append(wall)

metal, metal_principled = principled_material("Metal", Base_Color=(0.9, 0.6, 0.3, 1.0), Metallic=1.0, Roughness=0.4)
metal_principled.distribution = "MULTI_GGX"

bpy.ops.mesh.primitive_cube_add(size=1, location=(0.8, 1.0, 0.4))
table = bpy.context.object
table.name = "Table"
table.scale = (1.2, 0.8, 0.8)
table.data.materials.append(metal if mode == "metal" else wall)

if mode == "metal":
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(-0.6, 0.8, 0.5), segments=64, ring_count=32)
    sphere = bpy.context.object
    sphere.name = "Sphere"
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(metal)

# A panel 2 cm below the ceiling, facing down (a plane's normal is +Z: flipped).
bpy.ops.mesh.primitive_plane_add(size=1, location=(-1.0, -1.0, 2.98), rotation=(math.pi, 0, 0))
panel = bpy.context.object
panel.name = "Panel"
panel.scale = (1.0, 0.6, 1.0)
panel.data.materials.append(panel_material)

bpy.ops.object.light_add(type="POINT", location=(0.5, 0.5, 2.6))
light = bpy.context.object.data
light.energy = 200.0
light.shadow_soft_size = 0.0

bpy.ops.object.camera_add(location=(-1.5, -2.0, 1.6), rotation=(math.radians(80), 0, math.radians(-30)))
scene = bpy.context.scene
scene.camera = bpy.context.object
scene.render.resolution_x = 96
scene.render.resolution_y = 96
scene.render.resolution_percentage = 100

bpy.ops.export_scene.gltf(filepath=out_dir + "/room.glb", export_lights=True, export_cameras=True)

# Cycles renders a Lambertian in place of the Principled BSDF (see above).
for material, color in ((wall, (0.7, 0.7, 0.7, 1.0)),):
    tree = material.node_tree
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = color
    diffuse.inputs["Roughness"].default_value = 0.0
    tree.links.new(diffuse.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])

scene.render.engine = "CYCLES"
cycles = scene.cycles
cycles.device = "CPU"
cycles.samples = samples
cycles.use_denoising = False
cycles.max_bounces = cycles.diffuse_bounces = cycles.glossy_bounces = 128
cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
cycles.light_sampling_threshold = 0.0
cycles.blur_glossy = 0.0
scene.view_settings.view_transform = "Standard"
scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
for file_format, name in (("OPEN_EXR", "cycles.exr"), ("OPEN_EXR_MULTILAYER", "cycles_multilayer.exr")):
    scene.render.image_settings.file_format = file_format
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = out_dir + "/" + name
    bpy.ops.render.render(write_still=True)
