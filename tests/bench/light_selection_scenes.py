#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the scenes of the light-selection benchmark (light_selection.sh) into a folder.

thin_walls.gltf  two closed 5 x 3 x 5 m rooms 0.1 mm apart: room A has a bright ceiling panel,
                 room B, where the camera is, only a 0.5 cd bulb. By power, room B's points pick
                 the panel they cannot see 91% of the time.
thin_walls_both_seen.gltf, thin_walls_off_grid.gltf
                 the same with a camera in room A too (the roaming camera bakes both rooms), the
                 partition at x = 0 and at x = 0.37: walls thinner than a voxel (docs/baking.md).
flat.gltf        four rooms in a row joined by doorways: a sun and a sky through room 0's window,
                 a 30 cd lamp in room 1, a ceiling panel in room 2, a 3 cd lamp in room 3; one
                 camera per room. By power the sun takes 98% of the picks everywhere.
flat_on_ground.gltf
                 the same flat on a sunlit ground 2 km wide: the scene-wide grid's cells are 62.5 m,
                 and by power the lamps get 1e-8 of the picks (their light all but missing).
flat_on_lawn.gltf
                 the same flat on a lawn 200 m wide: free space's level-1 voxels, 0.56 m, are
                 wider than its 10 cm partitions (bake --view-region's test).

Usage: light_selection_scenes.py OUT_DIR
"""
import json
import math
import os
import struct
import sys


class Scene:
    def __init__(self):
        self.materials, self.meshes, self.nodes, self.lights, self.cameras = [], [], [], [], []
        self.accessors, self.views, self.data, self.extras = [], [], bytearray(), None

    def material(self, name, color, emission=None, strength=1.0):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(color) + [1.0], "metallicFactor": 0.0,
                                                      "roughnessFactor": 1.0}}
        if emission:
            m["emissiveFactor"] = list(emission)
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        self.materials.append(m)
        return len(self.materials) - 1

    def _accessor(self, blob, component, kind, count, bounds=None):
        while len(self.data) % 4:
            self.data.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.data), "byteLength": len(blob)})
        self.data += blob
        accessor = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if bounds:
            accessor["min"], accessor["max"] = bounds
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def quads(self, name, quads, material):
        """Quads (corner, edge1, edge2), each facing edge1 x edge2."""
        positions, indices = [], []
        for corner, e1, e2 in quads:
            base = len(positions)
            positions += [corner, add(corner, e1), add(add(corner, e1), e2), add(corner, e2)]
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
        bounds = ([min(p[i] for p in positions) for i in range(3)], [max(p[i] for p in positions) for i in range(3)])
        pos = self._accessor(b"".join(struct.pack("<3f", *p) for p in positions), 5126, "VEC3", len(positions), bounds)
        idx = self._accessor(b"".join(struct.pack("<I", i) for i in indices), 5125, "SCALAR", len(indices))
        self.meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pos}, "indices": idx,
                                                          "material": material}]})
        self.nodes.append({"name": name, "mesh": len(self.meshes) - 1})

    def box(self, name, lo, hi, material, inward):
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        dx, dy, dz = (x1 - x0, 0, 0), (0, y1 - y0, 0), (0, 0, z1 - z0)
        faces = [((x0, y0, z0), dz, dy), ((x1, y0, z0), dy, dz), ((x0, y0, z0), dx, dz),
                 ((x0, y1, z0), dz, dx), ((x0, y0, z0), dy, dx), ((x0, y0, z1), dx, dy)]
        if inward:
            faces = [(c, e2, e1) for c, e1, e2 in faces]
        self.quads(name, faces, material)

    def light(self, name, kind, intensity, position=None, direction=None):
        self.lights.append({"type": kind, "intensity": intensity, "color": [1.0, 1.0, 1.0]})
        node = {"name": name, "extensions": {"KHR_lights_punctual": {"light": len(self.lights) - 1}}}
        if position:
            node["translation"] = list(position)
        if direction:
            node["rotation"] = rotation_from_minus_z(direction)
        self.nodes.append(node)

    def camera(self, name, eye, target, yfov_degrees=70.0):
        self.cameras.append({"type": "perspective", "perspective": {"yfov": math.radians(yfov_degrees), "znear": 0.01,
                                                                    "aspectRatio": 1.0}})
        self.nodes.append({"name": name, "camera": len(self.cameras) - 1, "translation": list(eye),
                           "rotation": rotation_from_minus_z(sub(target, eye))})

    def write(self, path):
        binary = path.rsplit("/", 1)[-1].rsplit(".", 1)[0] + ".bin"
        gltf = {"asset": {"version": "2.0", "generator": "sharcbake tests/bench/light_selection_scenes.py"},
                "scene": 0, "scenes": [{"nodes": list(range(len(self.nodes)))}], "nodes": self.nodes,
                "meshes": self.meshes, "materials": self.materials, "accessors": self.accessors,
                "bufferViews": self.views, "buffers": [{"uri": binary, "byteLength": len(self.data)}],
                "cameras": self.cameras, "extensionsUsed": ["KHR_materials_emissive_strength"]}
        if self.lights:
            gltf["extensions"] = {"KHR_lights_punctual": {"lights": self.lights}}
            gltf["extensionsUsed"].append("KHR_lights_punctual")
        if self.extras:
            gltf["extras"] = self.extras
        with open(path, "w") as out:
            json.dump(gltf, out, indent=1)
        with open(path.rsplit("/", 1)[0] + "/" + binary if "/" in path else binary, "wb") as out:
            out.write(self.data)


def add(a, b):
    return [a[i] + b[i] for i in range(3)]


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(a):
    length = math.sqrt(sum(c * c for c in a))
    return [c / length for c in a]


def rotation_from_minus_z(direction):
    """The unit quaternion (x, y, z, w) turning -Z to `direction` with +Y kept up."""
    back = normalize([-c for c in direction])
    up = [0.0, 1.0, 0.0] if abs(back[1]) < 0.999 else [0.0, 0.0, -1.0]
    right = normalize(cross(up, back))
    up = cross(back, right)
    m = [[right[0], up[0], back[0]], [right[1], up[1], back[1]], [right[2], up[2], back[2]]]
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        return [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    if m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        return [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
    return [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]


def thin_walls(path, wall_x=0.0, camera_in_a=False):
    x = wall_x
    s = Scene()
    wall = s.material("wall", (0.8, 0.8, 0.8))
    panel = s.material("panel", (1.0, 1.0, 1.0), emission=(1.0, 1.0, 1.0), strength=20.0)
    s.box("room_a", (x - 5.0, 0.0, -2.5), (x, 3.0, 2.5), wall, inward=True)
    s.box("room_b", (x + 0.0001, 0.0, -2.5), (x + 5.0001, 3.0, 2.5), wall, inward=True)
    s.quads("panel", [((-3.0, 2.9, -0.5), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))], panel)  # facing down
    s.light("bulb_b", "point", 0.5, position=(x + 4.5, 0.3, 2.0))
    s.camera("room_b", (x + 4.0, 1.5, 2.0), (x + 0.0001, 1.5, 0.0))
    if camera_in_a:
        s.camera("room_a", (x - 4.0, 1.5, 2.0), (x - 0.0001, 1.5, 0.0))
    s.write(path)


def flat(path, ground=0.0):
    s = Scene()
    wall = s.material("wall", (0.75, 0.75, 0.75))
    floor = s.material("floor", (0.5, 0.4, 0.3))
    panel = s.material("panel", (1.0, 1.0, 1.0), emission=(1.0, 0.9, 0.8), strength=8.0)
    length, height, half = 16.0, 2.7, 2.0
    s.quads("floor", [((0, 0, -half), (0, 0, 2 * half), (length, 0, 0))], floor)
    s.quads("shell", [((0, height, -half), (length, 0, 0), (0, 0, 2 * half)),  # ceiling
                      ((0, 0, -half), (length, 0, 0), (0, height, 0)),  # back wall
                      ((0, 0, half), (0, height, 0), (length, 0, 0)),  # front wall
                      ((length, 0, -half), (0, 0, 2 * half), (0, height, 0))], wall)  # end wall
    # The window wall (x = 0) around a 1.2 x 1.2 m opening.
    s.quads("window_wall", [((0, y0, z0), (0, y1 - y0, 0), (0, 0, z1 - z0)) for z0, z1, y0, y1 in
                            [(-half, -0.6, 0, height), (0.6, half, 0, height), (-0.6, 0.6, 0, 0.9),
                             (-0.6, 0.6, 2.1, height)]], wall)
    for k in (1, 2, 3):  # partitions 10 cm thick with a 0.9 x 2.1 m doorway
        x = 4.0 * k
        s.box("partition_%d_a" % k, (x - 0.05, 0, -half), (x + 0.05, height, -0.45), wall, inward=False)
        s.box("partition_%d_b" % k, (x - 0.05, 0, 0.45), (x + 0.05, height, half), wall, inward=False)
        s.box("partition_%d_lintel" % k, (x - 0.05, 2.1, -0.45), (x + 0.05, height, 0.45), wall, inward=False)
    s.light("sun", "directional", 20000.0, direction=(1.0, -0.6, 0.2))
    s.light("lamp_room_1", "point", 30.0, position=(6.0, 2.2, 0.0))
    s.quads("panel_room_2", [((9.6, height - 0.01, -0.4), (0.8, 0, 0), (0, 0, 0.8))], panel)  # facing down
    s.light("lamp_room_3", "point", 3.0, position=(14.0, 1.5, 1.0))
    if ground:
        h = ground / 2
        s.quads("ground", [((-h, -0.02, -h), (0, 0, ground), (ground, 0, 0))], s.material("ground", (0.3, 0.3, 0.3)))
    s.extras = {"sharcbake": {"sky_radiance": [0.3, 0.35, 0.45]}}
    for k in range(4):
        x = 4.0 * k
        s.camera("room_%d" % k, (x + 3.5, 1.6, 1.5), (x + 0.5, 0.7, -1.2))
    s.write(path)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    os.makedirs(sys.argv[1], exist_ok=True)  # the docs' commands name a folder that is not there yet
    thin_walls(sys.argv[1] + "/thin_walls.gltf")
    thin_walls(sys.argv[1] + "/thin_walls_both_seen.gltf", camera_in_a=True)
    thin_walls(sys.argv[1] + "/thin_walls_off_grid.gltf", wall_x=0.37, camera_in_a=True)
    flat(sys.argv[1] + "/flat.gltf")
    flat(sys.argv[1] + "/flat_on_ground.gltf", ground=2000.0)
    flat(sys.argv[1] + "/flat_on_lawn.gltf", ground=200.0)
