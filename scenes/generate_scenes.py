#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Generates sharcbake's small test and demo scenes as glTF 2.0 (.gltf + .bin, + .png textures).

    python3 scenes/generate_scenes.py            # rewrite scenes/<name>/<name>.gltf|.bin
    python3 scenes/generate_scenes.py --check    # regenerate into a temp dir, compare, validate
    python3 scenes/generate_scenes.py --out DIR  # write DIR/<name>/<name>.gltf|.bin instead
    python3 scenes/generate_scenes.py --scene cornell_box --out DIR
    python3 scenes/generate_scenes.py --furnace-rho 0.9 --scale 1e-3 --offset 1e5 0 0 --out DIR
                                                 # one custom furnace: DIR/furnace/furnace.gltf

Conventions (glTF 2.0): metres, right-handed, +Y up, cameras look down -Z. Every face has its own
four vertices with the exact flat normal, and triangles wind counter-clockwise seen from the side
the normal points to. Diffuse-only materials are metallic 0, roughness 1 and
KHR_materials_specular specularFactor 0, so the glTF BRDF is pure Lambert with albedo = baseColor.
Emission is emissiveFactor x KHR_materials_emissive_strength (radiance, W/(m^2 sr)).

Output is byte-for-byte deterministic: only +, -, *, / and sqrt are used to compute geometry
(IEEE correctly rounded, so identical on every platform), rotations come from Pythagorean
triples, vertex data is packed as little-endian float32/uint32, PNGs use uncompressed deflate blocks and
the JSON is written with a fixed key order and fixed float formatting.

Python 3 standard library only.
"""

import argparse
import json
import math
import os
import struct
import sys
import tempfile

SCENES_DIR = os.path.dirname(os.path.abspath(__file__))
GENERATOR = "sharcbake scenes/generate_scenes.py"

# glTF enums
FLOAT = 5126
UNSIGNED_INT = 5125
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
TRIANGLES = 4

EXT_SPECULAR = "KHR_materials_specular"
EXT_EMISSIVE_STRENGTH = "KHR_materials_emissive_strength"
EXT_LIGHTS = "KHR_lights_punctual"

LUMENS_PER_WATT = 683.0


# ----------------------------------------------------------------------------------------------
# Small vector / quaternion helpers (tuples of floats)
# ----------------------------------------------------------------------------------------------

def vadd(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def vsub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def vmul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def vdot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def vcross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def vnormalize(a):
    length = math.sqrt(vdot(a, a))
    return (a[0] / length, a[1] / length, a[2] / length)


def quat_from_basis(right, up, back):
    """Unit quaternion (x, y, z, w) of the rotation whose matrix columns are right, up, back."""
    m00, m01, m02 = right[0], up[0], back[0]
    m10, m11, m12 = right[1], up[1], back[1]
    m20, m21, m22 = right[2], up[2], back[2]
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = math.sqrt(trace + 1.0) * 2.0
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2.0
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2.0
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2.0
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def quat_look_at(eye, target, world_up=(0.0, 1.0, 0.0)):
    """Rotation that makes a glTF camera (looking down its local -Z, +Y up) look at target."""
    forward = vnormalize(vsub(target, eye))
    right = vnormalize(vcross(forward, world_up))
    up = vcross(right, forward)
    return quat_from_basis(right, up, vmul(forward, -1.0))


def quat_from_to(a, b):
    """Shortest rotation taking unit vector a to unit vector b (not for b == -a)."""
    c = vcross(a, b)
    q = (c[0], c[1], c[2], 1.0 + vdot(a, b))
    n = math.sqrt(sum(x * x for x in q))
    return tuple(x / n for x in q)


# ----------------------------------------------------------------------------------------------
# Deterministic number formatting
# ----------------------------------------------------------------------------------------------

def jnum(x):
    """A JSON float: 12 significant digits (far beyond float32), shortest repr of that."""
    value = float(format(float(x), ".12g"))
    return 0.0 if value == 0.0 else value  # no "-0.0"


def jvec(v):
    return [jnum(c) for c in v]


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def f32_json(x):
    """Shortest decimal that converts back to exactly the float32 value x (for accessor min/max)."""
    for digits in range(1, 10):
        candidate = float(format(x, ".%dg" % digits))
        if f32(candidate) == x:
            return 0.0 if candidate == 0.0 else candidate
    return x


# ----------------------------------------------------------------------------------------------
# Materials
# ----------------------------------------------------------------------------------------------

def lambert(name, albedo, emission=None, double_sided=False):
    """A pure-Lambert glTF material: metallic 0, roughness 1, specularFactor 0.

    emission: RGB radiance (W/(m^2 sr)) or None. Stored as emissiveFactor when no channel exceeds
    1, otherwise as emissiveFactor = emission / max and KHR_materials_emissive_strength = max.
    """
    material = {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": jvec(albedo) + [1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
        "extensions": {EXT_SPECULAR: {"specularFactor": 0.0}},
    }
    if emission is not None:
        peak = max(emission)
        if peak > 1.0:
            material["emissiveFactor"] = jvec([c / peak for c in emission])
            material["extensions"][EXT_EMISSIVE_STRENGTH] = {"emissiveStrength": jnum(peak)}
        else:
            material["emissiveFactor"] = jvec(emission)
    material["doubleSided"] = bool(double_sided)
    return material


# ----------------------------------------------------------------------------------------------
# Geometry
# ----------------------------------------------------------------------------------------------

class Mesh:
    """One glTF mesh with one triangle primitive: flat-shaded quads with their own vertices."""

    def __init__(self, name, material):
        self.name = name
        self.material = material  # material name
        self.positions = []
        self.normals = []
        self.texcoords = []  # TEXCOORD_0, written only if every quad has uvs
        self.indices = []

    def add_quad(self, p0, p1, p2, p3, normal, uvs=None):
        """Quad p0 p1 p2 p3, counter-clockwise seen from the side `normal` points to."""
        winding = vcross(vsub(p2, p0), vsub(p3, p1))
        assert vdot(winding, normal) > 0.0, "quad %s winds against its normal" % self.name
        expected_uvs = len(self.positions) if uvs is not None else 0
        assert len(self.texcoords) == expected_uvs, \
            "mesh %s mixes quads with and without uvs" % self.name
        base = len(self.positions)
        self.positions.extend([p0, p1, p2, p3])
        self.normals.extend([normal] * 4)
        if uvs is not None:
            self.texcoords.extend(uvs)
        self.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3])


def _unit(axis):
    return tuple(1.0 if i == axis else 0.0 for i in range(3))


def _point(axis, coord, u, v):
    """World point with `coord` on `axis` and (u, v) on the next two axes in cyclic order."""
    p = [0.0, 0.0, 0.0]
    p[axis] = coord
    p[(axis + 1) % 3] = u
    p[(axis + 2) % 3] = v
    return tuple(p)


def add_axis_quad(mesh, axis, coord, sign, u_range, v_range):
    """Axis-aligned rectangle in the plane {axis = coord}, facing sign * axis.

    u runs along axis+1 and v along axis+2 (cyclic: x -> (y, z), y -> (z, x), z -> (x, y)), so
    that e_u x e_v = e_axis. Ranges are (low, high) world coordinates.
    """
    (u0, u1), (v0, v1) = u_range, v_range
    corners = [_point(axis, coord, u0, v0), _point(axis, coord, u1, v0),
               _point(axis, coord, u1, v1), _point(axis, coord, u0, v1)]
    if sign < 0:
        corners.reverse()
    mesh.add_quad(*corners, normal=vmul(_unit(axis), float(sign)))


def add_axis_quad_with_hole(mesh, axis, coord, sign, u_range, v_range, hole):
    """Like add_axis_quad, minus the rectangular hole ((u0, u1), (v0, v1)) inside it.

    Emitted as up to four strips (below, above, left of, right of the hole); zero-width strips
    (a door reaching the floor) are left out.
    """
    (u0, u1), (v0, v1) = u_range, v_range
    (hu0, hu1), (hv0, hv1) = hole
    assert u0 <= hu0 < hu1 <= u1 and v0 <= hv0 < hv1 <= v1, "hole outside its face"
    strips = [((u0, u1), (v0, hv0)), ((u0, u1), (hv1, v1)),
              ((u0, hu0), (hv0, hv1)), ((hu1, u1), (hv0, hv1))]
    for su, sv in strips:
        if su[1] > su[0] and sv[1] > sv[0]:
            add_axis_quad(mesh, axis, coord, sign, su, sv)


# Face names used by add_box(skip=...): "+x", "-x", "+y", "-y", "+z", "-z".
_BOX_FACES = [("+x", 0, 1), ("-x", 0, -1), ("+y", 1, 1), ("-y", 1, -1), ("+z", 2, 1), ("-z", 2, -1)]


def add_box(mesh, center, size, rotation=(1.0, 0.0), inward=False, skip=()):
    """Box of `size` (x, y, z) at `center`, turned about +Y by the angle whose (cos, sin) is
    `rotation`.

    Outward-facing faces for solid objects, inward-facing (inward=True) for rooms. `skip` lists
    faces to leave out, named in the box's own frame ("-y" is the bottom). Pass exact (cos, sin)
    pairs such as Pythagorean triples (0.96, 0.28) so no transcendental function is needed.
    """
    c, s = rotation
    assert abs(c * c + s * s - 1.0) < 1e-12, "rotation must be a unit (cos, sin) pair"
    # Rotation about +Y by angle t maps x -> (cos t, 0, -sin t) and z -> (sin t, 0, cos t).
    axes = [(c, 0.0, -s), (0.0, 1.0, 0.0), (s, 0.0, c)]
    half = [0.5 * size[0], 0.5 * size[1], 0.5 * size[2]]
    for name, axis, sign in _BOX_FACES:
        if name in skip:
            continue
        n = vmul(axes[axis], float(sign))
        # e_u x e_v = e_axis for the cyclic pair; swap them for the negative face.
        u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
        if sign < 0:
            u_axis, v_axis = v_axis, u_axis
        eu = vmul(axes[u_axis], half[u_axis])
        ev = vmul(axes[v_axis], half[v_axis])
        face_center = vadd(center, vmul(n, half[axis]))
        corners = [vsub(vsub(face_center, eu), ev), vsub(vadd(face_center, eu), ev),
                   vadd(vadd(face_center, eu), ev), vadd(vsub(face_center, eu), ev)]
        normal = n
        if inward:
            corners.reverse()
            normal = vmul(n, -1.0)
        mesh.add_quad(*corners, normal=normal)


# ----------------------------------------------------------------------------------------------
# PNG writer (8-bit RGB, uncompressed deflate blocks: identical bytes with every zlib version)
# ----------------------------------------------------------------------------------------------

def png_rgb8(width, height, rows):
    """rows: height lists of width (r, g, b) tuples, 0..255, top row first."""
    import zlib  # only crc32 / adler32, which are fixed checksums
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)
    stream = bytearray(b"\x78\x01")
    for start in range(0, max(len(raw), 1), 65535):
        block = raw[start:start + 65535]
        final = 1 if start + 65535 >= len(raw) else 0
        stream += struct.pack("<BHH", final, len(block), 0xFFFF ^ len(block)) + block
    stream += struct.pack(">I", zlib.adler32(raw))

    def chunk(kind, data):
        crc = zlib.crc32(kind + data)
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", bytes(stream))
            + chunk(b"IEND", b""))


def srgb_to_linear(c8):
    c = c8 / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


# ----------------------------------------------------------------------------------------------
# glTF writer
# ----------------------------------------------------------------------------------------------

class GltfBuilder:
    """Collects meshes, materials, cameras and lights and writes <name>.gltf + <name>.bin.

    scale and offset move the whole scene (p' = p * scale + offset): vertex positions, camera
    and light positions. They are baked into the float32 vertex data rather than put on a node,
    so the loader sees exactly the coordinates a scene of that size and place would have.
    """

    def __init__(self, name, scale=1.0, offset=(0.0, 0.0, 0.0)):
        assert scale > 0.0
        self.name = name
        self.scale = float(scale)
        self.offset = tuple(float(c) for c in offset)
        self.materials = []  # glTF material dicts, referenced by name
        self.meshes = []
        self.cameras = []  # (name, eye, target, yfov)
        self.lights = []  # (light dict, rotation quaternion, position or None)
        self.images = []  # (file name, png bytes); one texture each, NEAREST + CLAMP_TO_EDGE
        self.extras = {}

    def transform(self, p):
        return (p[0] * self.scale + self.offset[0], p[1] * self.scale + self.offset[1],
                p[2] * self.scale + self.offset[2])

    def add_material(self, material):
        assert all(m["name"] != material["name"] for m in self.materials), material["name"]
        self.materials.append(material)
        return material["name"]

    def add_mesh(self, name, material):
        assert any(m["name"] == material for m in self.materials), material
        mesh = Mesh(name, material)
        self.meshes.append(mesh)
        return mesh

    def add_png_texture(self, file_name, png):
        """Adds an image file written next to the .gltf; returns its glTF texture index."""
        self.images.append((file_name, png))
        return len(self.images) - 1

    def add_camera(self, name, eye, target, yfov):
        self.cameras.append((name, eye, target, yfov))

    def add_directional_light(self, name, direction, illuminance_lux, color=(1.0, 1.0, 1.0)):
        """Directional light travelling along `direction`; illuminance (lux) on a surface
        facing it."""
        light = {"name": name, "type": "directional", "color": jvec(color),
                 "intensity": jnum(illuminance_lux)}
        rotation = quat_from_to((0.0, 0.0, -1.0), vnormalize(direction))
        self.lights.append((light, rotation, None))

    # -- packing --------------------------------------------------------------------------------

    def build(self):
        """Returns (gltf_text, bin_bytes)."""
        binary = bytearray()
        buffer_views = []
        accessors = []

        def add_view(data, target):
            while len(binary) % 4:
                binary.append(0)
            buffer_views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data),
                                 "target": target})
            binary.extend(data)
            return len(buffer_views) - 1

        def add_vec3_accessor(vectors, name):
            flat = [f32(c) for v in vectors for c in v]
            data = struct.pack("<%df" % len(flat), *flat)
            view = add_view(data, ARRAY_BUFFER)
            lo = [min(flat[i::3]) for i in range(3)]
            hi = [max(flat[i::3]) for i in range(3)]
            accessors.append({"name": name, "bufferView": view, "byteOffset": 0,
                              "componentType": FLOAT, "count": len(vectors), "type": "VEC3",
                              "min": [f32_json(x) for x in lo], "max": [f32_json(x) for x in hi]})
            return len(accessors) - 1

        def add_vec2_accessor(vectors, name):
            flat = [f32(c) for v in vectors for c in v]
            view = add_view(struct.pack("<%df" % len(flat), *flat), ARRAY_BUFFER)
            accessors.append({"name": name, "bufferView": view, "byteOffset": 0,
                              "componentType": FLOAT, "count": len(vectors), "type": "VEC2"})
            return len(accessors) - 1

        def add_index_accessor(indices, name):
            data = struct.pack("<%dI" % len(indices), *indices)
            view = add_view(data, ELEMENT_ARRAY_BUFFER)
            accessors.append({"name": name, "bufferView": view, "byteOffset": 0,
                              "componentType": UNSIGNED_INT, "count": len(indices),
                              "type": "SCALAR", "min": [min(indices)], "max": [max(indices)]})
            return len(accessors) - 1

        material_index = {m["name"]: i for i, m in enumerate(self.materials)}
        nodes = []
        meshes = []
        for mesh in self.meshes:
            positions = add_vec3_accessor([self.transform(p) for p in mesh.positions],
                                          mesh.name + " positions")
            normals = add_vec3_accessor(mesh.normals, mesh.name + " normals")
            attributes = {"POSITION": positions, "NORMAL": normals}
            if mesh.texcoords:
                attributes["TEXCOORD_0"] = add_vec2_accessor(mesh.texcoords, mesh.name + " uvs")
            indices = add_index_accessor(mesh.indices, mesh.name + " indices")
            meshes.append({"name": mesh.name, "primitives": [{
                "attributes": attributes,
                "indices": indices, "material": material_index[mesh.material],
                "mode": TRIANGLES}]})
            nodes.append({"name": mesh.name, "mesh": len(meshes) - 1})

        cameras = []
        for name, eye, target, yfov in self.cameras:
            cameras.append({"name": name, "type": "perspective", "perspective": {
                "aspectRatio": 1.0, "yfov": jnum(yfov), "znear": jnum(0.01 * self.scale)}})
            nodes.append({"name": name, "camera": len(cameras) - 1,
                          "rotation": jvec(quat_look_at(eye, target)),
                          "translation": jvec(self.transform(eye))})

        lights = []
        for light, rotation, position in self.lights:
            lights.append(light)
            node = {"name": light["name"], "rotation": jvec(rotation)}
            if position is not None:
                node["translation"] = jvec(self.transform(position))
            node["extensions"] = {EXT_LIGHTS: {"light": len(lights) - 1}}
            nodes.append(node)

        used = set()
        for m in self.materials:
            used.update(m.get("extensions", {}).keys())
        if lights:
            used.add(EXT_LIGHTS)

        gltf = {"asset": {"version": "2.0", "generator": GENERATOR}}
        if used:
            gltf["extensionsUsed"] = sorted(used)
        if lights:
            gltf["extensions"] = {EXT_LIGHTS: {"lights": lights}}
        if self.extras:
            gltf["extras"] = {"sharcbake": self.extras}
        gltf["scene"] = 0
        scene = {"name": self.name, "nodes": list(range(len(nodes)))}
        gltf["scenes"] = [scene]
        gltf["nodes"] = nodes
        gltf["meshes"] = meshes
        gltf["materials"] = self.materials
        gltf["cameras"] = cameras
        if self.images:
            gltf["samplers"] = [{"magFilter": 9728, "minFilter": 9728,  # NEAREST
                                 "wrapS": 33071, "wrapT": 33071}]    # CLAMP_TO_EDGE
            gltf["images"] = [{"uri": file_name, "mimeType": "image/png"}
                              for file_name, _ in self.images]
            gltf["textures"] = [{"sampler": 0, "source": i} for i in range(len(self.images))]
        gltf["accessors"] = accessors
        gltf["bufferViews"] = buffer_views
        gltf["buffers"] = [{"uri": self.name + ".bin", "byteLength": len(binary)}]
        text = json.dumps(gltf, indent=2, ensure_ascii=True, allow_nan=False) + "\n"
        return text, bytes(binary)

    def write(self, directory):
        """Writes directory/<name>.gltf, <name>.bin and any images; returns their paths."""
        text, binary = self.build()
        os.makedirs(directory, exist_ok=True)
        gltf_path = os.path.join(directory, self.name + ".gltf")
        bin_path = os.path.join(directory, self.name + ".bin")
        with open(gltf_path, "w", encoding="ascii", newline="\n") as f:
            f.write(text)
        with open(bin_path, "wb") as f:
            f.write(binary)
        written = [gltf_path, bin_path]
        for file_name, png in self.images:
            written.append(os.path.join(directory, file_name))
            with open(written[-1], "wb") as f:
                f.write(png)
        return written

    def surface_area(self, meshes=None):
        """Total triangle area (in the scene's own units, before scale/offset)."""
        area = 0.0
        for mesh in meshes if meshes is not None else self.meshes:
            for t in range(0, len(mesh.indices), 3):
                a, b, c = (mesh.positions[mesh.indices[t + k]] for k in range(3))
                g = vcross(vsub(b, a), vsub(c, a))
                area += 0.5 * math.sqrt(vdot(g, g))
        return area

    def degenerate_triangles(self):
        """Triangles whose float32 vertex positions (after scale/offset) have zero area."""
        count = 0
        for mesh in self.meshes:
            p = [tuple(f32(c) for c in self.transform(q)) for q in mesh.positions]
            for t in range(0, len(mesh.indices), 3):
                a, b, c = (p[mesh.indices[t + k]] for k in range(3))
                if vcross(vsub(b, a), vsub(c, a)) == (0.0, 0.0, 0.0):
                    count += 1
        return count


# ----------------------------------------------------------------------------------------------
# Scenes
# ----------------------------------------------------------------------------------------------

def cornell_box(scale=1.0, offset=(0.0, 0.0, 0.0)):
    """The Cornell box, 1 m wide: x in [-0.5, 0.5], y in [0, 1], z in [-0.5, 0.5], open at +Z."""
    b = GltfBuilder("cornell_box", scale, offset)
    white = b.add_material(lambert("white", (0.725, 0.71, 0.68)))
    red = b.add_material(lambert("red", (0.63, 0.065, 0.05)))
    green = b.add_material(lambert("green", (0.14, 0.45, 0.091)))
    light = b.add_material(lambert("light", (0.78, 0.78, 0.78), emission=(17.0, 12.0, 4.0)))

    room = (-0.5, 0.5)
    add_axis_quad(b.add_mesh("floor", white), 1, 0.0, +1, (-0.5, 0.5), room)
    add_axis_quad(b.add_mesh("ceiling", white), 1, 1.0, -1, (-0.5, 0.5), room)
    add_axis_quad(b.add_mesh("back_wall", white), 2, -0.5, +1, room, (0.0, 1.0))
    add_axis_quad(b.add_mesh("left_wall", red), 0, -0.5, +1, (0.0, 1.0), room)
    add_axis_quad(b.add_mesh("right_wall", green), 0, 0.5, -1, (0.0, 1.0), room)

    # Blocks as in the original: short one front right, tall one back left, both turned ~16 deg
    # (Pythagorean triple 7-24-25: cos 0.96, sin 0.28). Their bottoms rest on the floor and are
    # left out (never visible; no coplanar faces).
    add_box(b.add_mesh("short_block", white), (0.18, 0.15, 0.12), (0.3, 0.3, 0.3),
            rotation=(0.96, -0.28), skip=("-y",))
    add_box(b.add_mesh("tall_block", white), (-0.17, 0.3, -0.15), (0.3, 0.6, 0.3),
            rotation=(0.96, 0.28), skip=("-y",))

    # 0.24 x 0.19 m area light 1 mm below the ceiling, facing down, single-sided.
    add_axis_quad(b.add_mesh("light", light), 1, 0.999, -1, (-0.095, 0.095), (-0.12, 0.12))

    # Framed like the original (1.5 box widths in front of the opening, 39.5 deg): the opening
    # fills about 93% of the frame.
    b.add_camera("camera", eye=(0.0, 0.5, 2.0), target=(0.0, 0.5, 0.0), yfov=0.69)
    return b


def furnace(name, rho, emission=1.0, scale=1.0, offset=(0.0, 0.0, 0.0)):
    """Closed 4 x 3 x 4 m room with a floating 1 m cube; every surface albedo rho, emission Le.

    Every point of a closed scene where all surfaces have the same albedo and emission has the
    same outgoing radiance L = Le / (1 - rho).
    """
    assert 0.0 <= rho < 1.0
    b = GltfBuilder(name, scale, offset)
    material = b.add_material(lambert("furnace", (rho, rho, rho),
                                      emission=(emission, emission, emission), double_sided=True))
    add_box(b.add_mesh("room", material), (0.0, 1.5, 0.0), (4.0, 3.0, 4.0), inward=True)
    add_box(b.add_mesh("cube", material), (0.5, 1.3, -0.5), (1.0, 1.0, 1.0))
    b.add_camera("camera", eye=(-1.4, 1.7, 1.7), target=(0.5, 1.3, -0.5), yfov=0.9)
    b.extras = {"expected_radiance": jnum(emission / (1.0 - rho))}
    return b


def two_rooms(scale=1.0, offset=(0.0, 0.0, 0.0)):
    """Two 4 x 3 x 4 m rooms joined by a 1 x 2 m doorway through a 0.2 m thick wall.

    Room A: x in [-4.1, -0.1], with a 1 x 1 m emitter flush in its ceiling.
    Room B: x in [0.1, 4.1], no emitter. Both: y in [0, 3], z in [-2, 2].
    The doorway (x in [-0.1, 0.1], y in [0, 2], z in [-0.5, 0.5]) is lined with its own quads,
    so the interior is one closed, watertight volume of inward-facing surfaces.
    """
    b = GltfBuilder("two_rooms", scale, offset)
    wall = b.add_material(lambert("wall", (0.7, 0.7, 0.7)))
    light = b.add_material(lambert("light", (0.7, 0.7, 0.7), emission=(10.0, 10.0, 10.0)))

    depth = (-2.0, 2.0)
    height = (0.0, 3.0)
    door = ((0.0, 2.0), (-0.5, 0.5))          # (y range, z range) on an x = const wall
    lamp = ((-0.5, 0.5), (-2.6, -1.6))        # (z range, x range) on the y = 3 ceiling

    room_a = b.add_mesh("room_a", wall)
    xa = (-4.1, -0.1)
    add_axis_quad(room_a, 1, 0.0, +1, depth, xa)                                   # floor
    add_axis_quad_with_hole(room_a, 1, 3.0, -1, depth, xa, lamp)                   # ceiling
    add_axis_quad(room_a, 0, xa[0], +1, height, depth)                             # far wall
    add_axis_quad_with_hole(room_a, 0, xa[1], -1, height, depth, door)             # door wall
    add_axis_quad(room_a, 2, depth[0], +1, xa, height)
    add_axis_quad(room_a, 2, depth[1], -1, xa, height)

    room_b = b.add_mesh("room_b", wall)
    xb = (0.1, 4.1)
    add_axis_quad(room_b, 1, 0.0, +1, depth, xb)
    add_axis_quad(room_b, 1, 3.0, -1, depth, xb)
    add_axis_quad_with_hole(room_b, 0, xb[0], +1, height, depth, door)             # door wall
    add_axis_quad(room_b, 0, xb[1], -1, height, depth)                             # far wall
    add_axis_quad(room_b, 2, depth[0], +1, xb, height)
    add_axis_quad(room_b, 2, depth[1], -1, xb, height)

    doorway = b.add_mesh("doorway", wall)
    xd = (-0.1, 0.1)
    add_axis_quad(doorway, 1, 0.0, +1, door[1], xd)     # threshold
    add_axis_quad(doorway, 1, 2.0, -1, door[1], xd)     # lintel
    add_axis_quad(doorway, 2, -0.5, +1, xd, door[0])    # jambs
    add_axis_quad(doorway, 2, 0.5, -1, xd, door[0])

    light_a = b.add_mesh("light_a", light)
    add_axis_quad(light_a, 1, 3.0, -1, lamp[0], lamp[1])

    b.add_camera("camera_room_a", eye=(-3.9, 1.6, 1.2), target=(-0.1, 1.1, -0.2), yfov=0.9)
    b.add_camera("camera_room_b", eye=(3.9, 1.6, -1.2), target=(0.1, 1.1, 0.2), yfov=0.9)

    # Energy balance of a closed scene with one albedo everywhere: all emitted power is
    # eventually absorbed, so sum (1 - rho) E A = Phi and the area-weighted mean irradiance is
    # Phi / ((1 - rho) A). Power and area scale with scale^2; the irradiance does not.
    power = math.pi * 10.0 * b.surface_area([light_a])
    area = b.surface_area()
    b.extras = {
        "emitted_power": jnum(power * b.scale * b.scale),
        "surface_area": jnum(area * b.scale * b.scale),
        "expected_mean_irradiance": jnum(power / ((1.0 - 0.7) * area)),
    }
    return b


OUTDOOR_SKY = (0.5, 0.6, 0.8)
OUTDOOR_SUN_WM2 = 3.0
# Travel direction of the sunlight: elevation 45 deg (horizontal and vertical parts equal),
# coming from -X/+Z and travelling towards +X/-Z.
OUTDOOR_SUN_DIRECTION = vnormalize((1.0, -math.sqrt(2.0), -1.0))
OUTDOOR_GROUND_ALBEDO = 0.5
OUTDOOR_PROBE = (-14.0, 0.0, 14.0)


def outdoor_expected_ground_radiance():
    """Radiance of sunlit, unoccluded ground: albedo/pi * (E_sun cos(theta) + pi * L_sky)."""
    cos_theta = -OUTDOOR_SUN_DIRECTION[1]
    return tuple(OUTDOOR_GROUND_ALBEDO / math.pi * (OUTDOOR_SUN_WM2 * cos_theta + math.pi * sky)
                 for sky in OUTDOOR_SKY)


def outdoor(scale=1.0, offset=(0.0, 0.0, 0.0)):
    """40 x 40 m ground with four boxes, a 45-degree sun and a uniform sky."""
    b = GltfBuilder("outdoor", scale, offset)
    ground = b.add_material(lambert("ground", (OUTDOOR_GROUND_ALBEDO,) * 3))
    red = b.add_material(lambert("red", (0.6, 0.3, 0.3)))
    green = b.add_material(lambert("green", (0.3, 0.6, 0.3)))
    blue = b.add_material(lambert("blue", (0.3, 0.3, 0.6)))
    grey = b.add_material(lambert("grey", (0.6, 0.6, 0.6)))

    add_axis_quad(b.add_mesh("ground", ground), 1, 0.0, +1, (-20.0, 20.0), (-20.0, 20.0))
    add_box(b.add_mesh("red_box", red), (-4.0, 1.0, -3.0), (2.0, 2.0, 2.0),
            rotation=(0.8, 0.6), skip=("-y",))
    add_box(b.add_mesh("green_tower", green), (3.0, 1.5, -5.0), (1.0, 3.0, 1.0), skip=("-y",))
    add_box(b.add_mesh("blue_slab", blue), (1.0, 0.5, 2.0), (4.0, 1.0, 2.0),
            rotation=(0.96, -0.28), skip=("-y",))
    add_box(b.add_mesh("grey_cube", grey), (6.0, 0.75, 3.0), (1.5, 1.5, 1.5), skip=("-y",))

    b.add_directional_light("sun", OUTDOOR_SUN_DIRECTION, OUTDOOR_SUN_WM2 * LUMENS_PER_WATT)
    b.add_camera("camera", eye=(-3.0, 6.5, 14.0), target=(1.5, 0.5, -1.5), yfov=0.8)
    b.extras = {
        "sky_radiance": jvec(OUTDOOR_SKY),
        "expected_ground_radiance": jvec(outdoor_expected_ground_radiance()),
        "ground_probe": jvec(b.transform(OUTDOOR_PROBE)),
    }
    return b


# 2 x 2 texels, top row first: the four quadrants of the textured quad as the camera sees them.
TEXTURED_TEXELS = [[(255, 0, 0), (0, 255, 0)],
                   [(0, 0, 255), (188, 188, 188)]]
TEXTURED_QUADRANTS = ["top_left", "top_right", "bottom_left", "bottom_right"]


def textured_quad(scale=1.0, offset=(0.0, 0.0, 0.0)):
    """A 2 x 2 m quad facing +Z, lit by nothing, showing an emissive 2 x 2 texel texture.

    The camera sees each quadrant's emission directly: radiance = sRGB-decoded texel (the
    grey 188 decodes to 0.5029, not 0.737), which checks uv orientation, sRGB decoding and
    NEAREST/CLAMP sampling. Base colour is black so nothing is reflected.
    """
    b = GltfBuilder("textured_quad", scale, offset)
    texture = b.add_png_texture("textured_quad.png", png_rgb8(2, 2, TEXTURED_TEXELS))
    material = lambert("emissive_texture", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0))
    material["emissiveTexture"] = {"index": texture}
    quad = b.add_mesh("quad", b.add_material(material))
    # uv (0, 0) is the top-left of the image (glTF convention): put it at the top-left corner.
    quad.add_quad((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 2.0, 0.0), (-1.0, 2.0, 0.0),
                  normal=(0.0, 0.0, 1.0), uvs=[(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)])
    b.add_camera("camera", eye=(0.0, 1.0, 3.0), target=(0.0, 1.0, 0.0), yfov=0.8)
    b.extras = {"expected_quadrant_radiance": {
        quadrant: jvec([srgb_to_linear(c) for c in TEXTURED_TEXELS[i // 2][i % 2]])
        for i, quadrant in enumerate(TEXTURED_QUADRANTS)}}
    return b


SCENES = {
    "cornell_box": cornell_box,
    "furnace_rho050": lambda **kw: furnace("furnace_rho050", 0.5, **kw),
    "furnace_rho090": lambda **kw: furnace("furnace_rho090", 0.9, **kw),
    "furnace_rho099": lambda **kw: furnace("furnace_rho099", 0.99, **kw),
    "two_rooms": two_rooms,
    "outdoor": outdoor,
    "textured_quad": textured_quad,
}


# ----------------------------------------------------------------------------------------------
# Structural validation (run by --check on the committed files)
# ----------------------------------------------------------------------------------------------

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_COMPONENT_FORMATS = {FLOAT: "f", UNSIGNED_INT: "I"}


def validate_gltf(path):
    """Structural checks on one .gltf with an external .bin. Returns a list of problems."""
    errors = []

    def err(message):
        errors.append("%s: %s" % (path, message))

    try:
        with open(path, encoding="ascii") as f:
            gltf = json.load(f)
    except (OSError, ValueError) as e:
        return ["%s: not readable JSON: %s" % (path, e)]

    if gltf.get("asset", {}).get("version") != "2.0":
        err("asset.version is not 2.0")
    buffers = gltf.get("buffers", [])
    if len(buffers) != 1 or "uri" not in buffers[0]:
        return errors + ["%s: expected exactly one buffer with a uri" % path]
    bin_path = os.path.join(os.path.dirname(path), buffers[0]["uri"])
    try:
        with open(bin_path, "rb") as f:
            binary = f.read()
    except OSError as e:
        return errors + ["%s: buffer: %s" % (path, e)]
    if buffers[0]["byteLength"] != len(binary):
        err("buffer byteLength %d != %d bytes in %s" % (buffers[0]["byteLength"], len(binary),
                                                       bin_path))

    views = gltf.get("bufferViews", [])
    for i, view in enumerate(views):
        start, length = view.get("byteOffset", 0), view["byteLength"]
        if view["buffer"] != 0 or start % 4 or start + length > len(binary):
            err("bufferView %d out of range or misaligned" % i)

    def read_accessor(index):
        a = gltf["accessors"][index]
        view = views[a["bufferView"]]
        count, ncomp = a["count"], _COMPONENTS[a["type"]]
        fmt = _COMPONENT_FORMATS.get(a["componentType"])
        if fmt is None:
            err("accessor %d: unexpected componentType %d" % (index, a["componentType"]))
            return None
        offset = a.get("byteOffset", 0)
        size = 4 * ncomp * count
        if offset % 4 or offset + size > view["byteLength"]:
            err("accessor %d does not fit its bufferView" % index)
            return None
        start = view.get("byteOffset", 0) + offset
        flat = struct.unpack_from("<%d%s" % (count * ncomp, fmt), binary, start)
        elements = [flat[i * ncomp:(i + 1) * ncomp] for i in range(count)]
        if count and ("min" in a or "max" in a):
            lo = [min(e[c] for e in elements) for c in range(ncomp)]
            hi = [max(e[c] for e in elements) for c in range(ncomp)]
            conv = f32 if fmt == "f" else int
            stored_lo = [conv(x) for x in a.get("min", lo)]
            stored_hi = [conv(x) for x in a.get("max", hi)]
            if stored_lo != lo or stored_hi != hi:
                err("accessor %d: min/max do not match the data" % index)
        return elements

    materials = gltf.get("materials", [])
    used = set(gltf.get("extensionsUsed", []))
    for i, m in enumerate(materials):
        for ext in m.get("extensions", {}):
            if ext not in used:
                err("material %d uses %s, missing from extensionsUsed" % (i, ext))
    for ext in gltf.get("extensionsRequired", []):
        if ext not in used:
            err("extensionsRequired %s not in extensionsUsed" % ext)

    for mi, mesh in enumerate(gltf.get("meshes", [])):
        for prim in mesh["primitives"]:
            if prim.get("mode", TRIANGLES) != TRIANGLES:
                err("mesh %d: not triangles" % mi)
                continue
            if not 0 <= prim.get("material", -1) < len(materials):
                err("mesh %d: bad material index" % mi)
            attributes = prim["attributes"]
            position_accessor = gltf["accessors"][attributes["POSITION"]]
            if "min" not in position_accessor or "max" not in position_accessor:
                err("mesh %d: POSITION accessor without min/max" % mi)
            positions = read_accessor(attributes["POSITION"])
            normals = read_accessor(attributes["NORMAL"]) if "NORMAL" in attributes else None
            indices = read_accessor(prim["indices"])
            if positions is None or indices is None:
                continue
            if normals is not None and len(normals) != len(positions):
                err("mesh %d: NORMAL count != POSITION count" % mi)
                normals = None
            indices = [i[0] for i in indices]
            if len(indices) % 3:
                err("mesh %d: index count not a multiple of 3" % mi)
                continue
            if any(i >= len(positions) for i in indices):
                err("mesh %d: index out of range" % mi)
                continue
            for n in normals or []:
                if abs(math.sqrt(vdot(n, n)) - 1.0) > 1e-6:
                    err("mesh %d: normal %s is not unit length" % (mi, n))
                    break
            for t in range(0, len(indices), 3):
                p0, p1, p2 = (positions[indices[t + k]] for k in range(3))
                g = vcross(vsub(p1, p0), vsub(p2, p0))
                area2 = math.sqrt(vdot(g, g))
                if area2 == 0.0:
                    err("mesh %d: degenerate triangle %d" % (mi, t // 3))
                    break
                if normals is not None:
                    if any(vdot(g, normals[indices[t + k]]) < 0.999 * area2 for k in range(3)):
                        err("mesh %d: triangle %d winds against its vertex normals" % (mi, t // 3))
                        break

    nodes = gltf.get("nodes", [])
    cameras = gltf.get("cameras", [])
    camera_nodes = 0
    for ni, node in enumerate(nodes):
        if "mesh" in node and not 0 <= node["mesh"] < len(gltf.get("meshes", [])):
            err("node %d: bad mesh index" % ni)
        if "camera" in node:
            camera_nodes += 1
            if not 0 <= node["camera"] < len(cameras) or \
                    cameras[node["camera"]]["type"] != "perspective":
                err("node %d: bad camera" % ni)
        if "rotation" in node and abs(math.sqrt(sum(c * c for c in node["rotation"])) - 1.0) > 1e-6:
            err("node %d: rotation is not a unit quaternion" % ni)
        light = node.get("extensions", {}).get(EXT_LIGHTS)
        if light is not None:
            lights = gltf.get("extensions", {}).get(EXT_LIGHTS, {}).get("lights", [])
            if EXT_LIGHTS not in used or not 0 <= light["light"] < len(lights):
                err("node %d: bad light" % ni)
    if camera_nodes == 0:
        err("no camera node")
    for i, image in enumerate(gltf.get("images", [])):
        image_path = os.path.join(os.path.dirname(path), image.get("uri", ""))
        try:
            with open(image_path, "rb") as f:
                if f.read(8) != b"\x89PNG\r\n\x1a\n":
                    err("image %d is not a PNG" % i)
        except OSError as e:
            err("image %d: %s" % (i, e))
    for i, texture in enumerate(gltf.get("textures", [])):
        if not 0 <= texture.get("source", -1) < len(gltf.get("images", [])):
            err("texture %d: bad image index" % i)
    for scene in gltf.get("scenes", []):
        if any(not 0 <= n < len(nodes) for n in scene["nodes"]):
            err("scene node index out of range")
    return errors


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------

def generate(builders, out_dir):
    written = []
    for builder in builders:
        written += builder.write(os.path.join(out_dir, builder.name))
    return written


def check(builders):
    """Regenerates into a temp dir and compares with the committed files; validates both."""
    problems = []
    with tempfile.TemporaryDirectory(prefix="sharcbake_scenes_") as tmp:
        generated = generate(builders, tmp)
        for path in generated:
            rel = os.path.relpath(path, tmp)
            committed = os.path.join(SCENES_DIR, rel)
            if not os.path.exists(committed):
                problems.append("missing: scenes/%s" % rel)
                continue
            with open(path, "rb") as a, open(committed, "rb") as b:
                if a.read() != b.read():
                    problems.append("differs: scenes/%s" % rel)
            if path.endswith(".gltf"):
                problems += validate_gltf(committed)
                problems += validate_gltf(path)
        expected = {os.path.relpath(p, tmp) for p in generated}
        for builder in builders:
            scene_dir = os.path.join(SCENES_DIR, builder.name)
            for entry in sorted(os.listdir(scene_dir)) if os.path.isdir(scene_dir) else []:
                rel = os.path.join(builder.name, entry)
                if rel not in expected:
                    problems.append("unexpected: scenes/%s" % rel)
    return problems


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Generate sharcbake's glTF test scenes (deterministic .gltf + .bin).")
    parser.add_argument("--check", action="store_true",
                        help="regenerate into a temp dir and exit 1 if anything differs from the "
                             "committed scenes/ files (or fails structural validation)")
    parser.add_argument("--out", metavar="DIR",
                        help="write DIR/<name>/<name>.gltf|.bin (default: next to this script)")
    parser.add_argument("--scene", action="append", choices=sorted(SCENES), metavar="NAME",
                        help="generate only this scene (repeatable); one of: "
                             + ", ".join(SCENES))
    parser.add_argument("--furnace-rho", type=float, metavar="R",
                        help="generate one custom furnace scene with albedo R in [0, 1) instead")
    parser.add_argument("--emission", type=float, default=1.0, metavar="LE",
                        help="emitted radiance of the custom furnace (default 1)")
    parser.add_argument("--name", default="furnace",
                        help="name of the custom furnace scene (default: furnace)")
    parser.add_argument("--scale", type=float, default=1.0, metavar="S",
                        help="scale the generated scenes by S (needs --out)")
    parser.add_argument("--offset", type=float, nargs=3, default=(0.0, 0.0, 0.0),
                        metavar=("X", "Y", "Z"),
                        help="then translate them by (X, Y, Z) (needs --out)")
    parser.add_argument("--validate", action="store_true",
                        help="also run the structural checks on what was written")
    args = parser.parse_args(argv)

    custom = args.furnace_rho is not None
    transformed = args.scale != 1.0 or any(c != 0.0 for c in args.offset)
    if args.check and (args.out or custom or transformed):
        parser.error("--check compares the committed scenes; it takes no other option but --scene")
    if (custom or transformed) and not args.out:
        parser.error("custom or transformed scenes need --out "
                     "(the committed ones are the defaults)")
    if not (args.scale > 0.0 and math.isfinite(args.scale)):
        parser.error("--scale must be positive and finite")
    if not all(math.isfinite(c) for c in args.offset):
        parser.error("--offset must be finite")
    if custom and not 0.0 <= args.furnace_rho < 1.0:
        parser.error("--furnace-rho must be in [0, 1)")
    if custom and args.scene:
        parser.error("--furnace-rho and --scene are exclusive")

    kw = {"scale": args.scale, "offset": tuple(args.offset)}
    if custom:
        builders = [furnace(args.name, args.furnace_rho, args.emission, **kw)]
    else:
        builders = [SCENES[name](**kw) for name in (args.scene or SCENES)]

    if args.check:
        problems = check(builders)
        for p in problems:
            print(p, file=sys.stderr)
        if problems:
            print("scenes/ is out of date or invalid: run python3 scenes/generate_scenes.py "
                  "and commit the result", file=sys.stderr)
            return 1
        print("%d scenes up to date and valid" % len(builders))
        return 0

    out_dir = args.out or SCENES_DIR
    for builder in builders:
        degenerate = builder.degenerate_triangles()
        if degenerate:
            print("warning: %s: %d triangles collapse to zero area in float32 at this scale and "
                  "offset" % (builder.name, degenerate), file=sys.stderr)
    written = generate(builders, out_dir)
    for path in written:
        print(path)
    if args.validate:
        problems = [p for path in written if path.endswith(".gltf") for p in validate_gltf(path)]
        for p in problems:
            print(p, file=sys.stderr)
        return 1 if problems else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
