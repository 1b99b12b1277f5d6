# SPDX-License-Identifier: Apache-2.0
# Blender script for window_room.sh: a room built the way an archviz user builds one (a cube with
# its normals flipped, made 0.2 m thick by a Solidify modifier, a window cut by a Boolean), with a
# floor, a table, a sofa and a chrome ball, on a lawn 200 m wide under a sky colour, and two
# cameras inside ("Camera" across the room, "Window view" towards the window). Exported with the
# glTF exporter's defaults (lights and cameras included).
# LIGHT: sun (a 5 W/m^2 sun through the window), lamp (a 200 W point light under the ceiling) or
# panel (a 0.6 m emissive ceiling panel, strength 30).
#
# Usage: blender -b --factory-startup --python window_room.py -- OUT.glb sun|lamp|panel
import math
import sys

import bpy
import mathutils

out, light = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.wm.read_factory_settings(use_empty=True)


def material(name, color, roughness=0.8, metallic=0.0, emission=None, strength=1.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    if emission:
        bsdf.inputs["Emission"].default_value = (*emission, 1)
        bsdf.inputs["Emission Strength"].default_value = strength
    return m


def box(name, location, size, mat):
    bpy.ops.mesh.primitive_cube_add(size=1, location=location)
    o = bpy.context.object
    o.name, o.scale = name, size
    o.data.materials.append(mat)
    return o


# The room: 6 x 4 x 2.8 m inside, walls 0.2 m thick, a 1.6 x 1.2 m window in the +Y wall.
room = box("Room", (0, 0, 1.4), (6, 4, 2.8), material("plaster", (0.8, 0.78, 0.75), 0.9))
bpy.ops.object.transform_apply(scale=True)
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.flip_normals()
bpy.ops.object.mode_set(mode="OBJECT")
room.modifiers.new("walls", "SOLIDIFY").thickness = 0.2
cutter = box("Cutter", (0.5, 2.05, 1.5), (1.6, 0.8, 1.2), material("cutter", (1, 1, 1)))
window = room.modifiers.new("window", "BOOLEAN")
window.object, window.operation = cutter, "DIFFERENCE"
bpy.context.view_layer.objects.active = room
for modifier in ("walls", "window"):
    bpy.ops.object.modifier_apply(modifier=modifier)
bpy.data.objects.remove(cutter)

bpy.ops.mesh.primitive_plane_add(size=1, location=(0, 0, 0.001))
floor = bpy.context.object
floor.scale = (5.9, 3.9, 1)
floor.data.materials.append(material("wood", (0.45, 0.28, 0.15), 0.5))
box("Table", (-1, -0.5, 0.375), (1.6, 0.9, 0.75), material("table", (0.6, 0.6, 0.6), 0.3))
box("Sofa", (1.5, -1.4, 0.4), (2.2, 0.9, 0.8), material("fabric", (0.2, 0.3, 0.6), 1.0))
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.3, location=(-1, -0.5, 1.05))
bpy.ops.object.shade_smooth()
bpy.context.object.data.materials.append(material("chrome", (0.9, 0.9, 0.9), 0.05, 1.0))
bpy.ops.mesh.primitive_plane_add(size=200, location=(0, 0, -0.01))
bpy.context.object.data.materials.append(material("grass", (0.2, 0.35, 0.1), 1.0))

if light == "sun":
    bpy.ops.object.light_add(type="SUN", location=(0, 10, 10), rotation=(math.radians(-50), 0, math.radians(180)))
    bpy.context.object.data.energy = 5.0
    bpy.context.object.name = "Sun"
elif light == "lamp":
    bpy.ops.object.light_add(type="POINT", location=(1.5, 0.5, 2.3))
    bpy.context.object.data.energy = 200
    bpy.context.object.data.shadow_soft_size = 0.05
    bpy.context.object.name = "Ceiling lamp"
elif light == "panel":
    bpy.ops.mesh.primitive_plane_add(size=0.6, location=(0, 0, 2.78), rotation=(math.pi, 0, 0))
    bpy.context.object.data.materials.append(material("panel", (1, 1, 1), emission=(1, 0.95, 0.9), strength=30))
else:
    sys.exit("LIGHT must be sun, lamp or panel, not " + light)

world = bpy.data.worlds.new("World")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.5, 0.6, 0.8, 1)
bpy.context.scene.world = world
for name, eye, target in (("Camera", (-2.6, -1.7, 1.6), (1.0, 1.5, 1.0)),
                          ("Window view", (2.5, -1.5, 1.2), (0.3, 1.9, 1.4))):
    bpy.ops.object.camera_add(location=eye)
    camera = bpy.context.object
    camera.name = name
    camera.rotation_euler = (mathutils.Vector(target) - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.lens = 24
    bpy.context.scene.camera = camera
bpy.ops.export_scene.gltf(filepath=out, export_lights=True, export_cameras=True)
