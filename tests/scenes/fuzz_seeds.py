#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Seeds for fuzz_gltf_loader: each glTF or GLB given, written as one self-contained file (the
fuzzer hands the loader a single file), twice for a .gltf: with its external buffers and images
as data: URIs, and as a GLB whose first buffer is the binary chunk. GLB files are copied. One
more seed, `features()`, holds what the shipped scenes do not: sparse, normalized and interleaved
accessors, triangle strips, a skin, morph targets, instancing, every light and camera type,
textures with samplers and transforms, and the material extensions the loader reads.

Usage: fuzz_seeds.py OUT_DIR FILE...
"""
import base64
import hashlib
import json
import os
import struct
import sys


def embedded(path):
    """The glTF's JSON with every external buffer and image it names read into a data: URI."""
    folder = os.path.dirname(path)
    with open(path) as f:
        doc = json.load(f)
    for key, mime in (("buffers", "application/octet-stream"), ("images", "image/png")):
        for item in doc.get(key, []):
            uri = item.get("uri")
            if uri is None or uri.startswith("data:"):
                continue
            with open(os.path.join(folder, uri), "rb") as f:
                item["uri"] = "data:%s;base64,%s" % (mime, base64.b64encode(f.read()).decode())
    return doc


def glb(doc):
    """`doc` as a GLB: its first buffer's data: URI becomes the binary chunk."""
    doc = json.loads(json.dumps(doc))
    binary = b""
    buffers = doc.get("buffers", [])
    if buffers and buffers[0].get("uri", "").startswith("data:application/octet-stream"):
        binary = base64.b64decode(buffers[0].pop("uri").split(",", 1)[1])
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
    if binary:
        chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


def features():
    """A small glTF that uses most of what the loader reads, so that fuzzing starts inside it."""
    data = bytearray()

    def view(payload, stride=None):
        while len(data) % 4:
            data.append(0)
        entry = {"buffer": 0, "byteOffset": len(data), "byteLength": len(payload)}
        if stride:
            entry["byteStride"] = stride
        data.extend(payload)
        views.append(entry)
        return len(views) - 1

    def accessor(view_index, component, count, kind, **extra):
        accessors.append(dict({"bufferView": view_index, "componentType": component, "count": count,
                               "type": kind}, **extra))
        return len(accessors) - 1

    views, accessors = [], []
    quad = [0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1]
    position = accessor(view(struct.pack("<12f", *quad)), 5126, 4, "VEC3", min=[0, 0, 0], max=[1, 0, 1])
    # Interleaved normal (3 floats) and texcoord (2 normalized uint16 + padding): stride 16.
    interleaved = b"".join(struct.pack("<3f2H", 0, 1, 0, u, v) for u, v in ((0, 0), (65535, 0), (65535, 65535), (0, 65535)))
    interleaved_view = view(interleaved, stride=16)
    normal = accessor(interleaved_view, 5126, 4, "VEC3")
    texcoord = accessor(interleaved_view, 5123, 4, "VEC2", byteOffset=12, normalized=True)
    color = accessor(view(bytes([255, 128, 0, 255] * 4)), 5121, 4, "VEC4", normalized=True)
    tangent = accessor(view(struct.pack("<16f", *([1, 0, 0, 1] * 4))), 5126, 4, "VEC4")
    indices = accessor(view(struct.pack("<6H", 0, 2, 1, 0, 3, 2)), 5123, 6, "SCALAR")
    strip = accessor(view(bytes([0, 1, 3, 2])), 5121, 4, "SCALAR")
    sparse = {"count": 1, "indices": {"bufferView": view(struct.pack("<H", 2)), "componentType": 5123},
              "values": {"bufferView": view(struct.pack("<3f", 1, 0.5, 1))}}
    lifted = accessor(view(struct.pack("<12f", *quad)), 5126, 4, "VEC3", sparse=sparse)
    joints = accessor(view(bytes([0, 1, 0, 0] * 4)), 5121, 4, "VEC4")
    weights = accessor(view(struct.pack("<16f", *([0.5, 0.5, 0, 0] * 4))), 5126, 4, "VEC4")
    inverse_binds = accessor(view(struct.pack("<32f", *([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] * 2))),
                             5126, 2, "MAT4")
    morph = accessor(view(struct.pack("<12f", *([0, 0.25, 0] * 4))), 5126, 4, "VEC3")
    offsets = accessor(view(struct.pack("<6f", 0, 0, 0, 2, 0, 0)), 5126, 2, "VEC3")
    png = base64.b64decode("iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAFklEQVR4XmNgaPj//z+QZHBwcPgPAgBLGQm5"
                           "p7FuuwAAAABJRU5ErkJggg==")
    image_view = view(png)
    attributes = {"POSITION": position, "NORMAL": normal, "TEXCOORD_0": texcoord, "TEXCOORD_1": texcoord,
                  "COLOR_0": color, "TANGENT": tangent}
    textured = {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2],
                                                                      "rotation": 0.3, "texCoord": 1}}}
    doc = {
        "asset": {"version": "2.0", "generator": "sharcbake fuzz_seeds.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength",
                           "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_specular",
                           "KHR_materials_clearcoat", "KHR_materials_unlit", "EXT_mesh_gpu_instancing"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 100, "color": [1, 0.9, 0.8], "range": 10},
            {"type": "spot", "intensity": 500, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
            {"type": "directional", "intensity": 3}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6, 7]}],
        "nodes": [
            {"mesh": 0, "rotation": [0, 0.3826834, 0, 0.9238795], "scale": [2, 1, 2]},
            {"mesh": 1, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1]},
            {"mesh": 2, "skin": 0, "children": [8]},
            {"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": offsets}}}},
            {"camera": 0, "translation": [0.5, 2, 3]},
            {"camera": 1, "translation": [0.5, 5, 0], "rotation": [-0.7071068, 0, 0, 0.7071068]},
            {"translation": [0.5, 3, 0.5], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"rotation": [-0.7071068, 0, 0, 0.7071068], "children": [9],
             "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"translation": [0, 0.5, 0]},
            {"translation": [0, 4, 0], "extensions": {"KHR_lights_punctual": {"light": 1}}}],
        "skins": [{"joints": [2, 8], "inverseBindMatrices": inverse_binds}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01, "aspectRatio": 1.5}},
                    {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.01, "zfar": 100}}],
        "meshes": [
            {"primitives": [{"attributes": attributes, "indices": indices, "material": 0},
                            {"attributes": {"POSITION": lifted}, "indices": strip, "mode": 5, "material": 1}]},
            {"primitives": [{"attributes": {"POSITION": position}, "mode": 6, "material": 2,
                             "targets": [{"POSITION": morph}]}], "weights": [0.5]},
            {"primitives": [{"attributes": {"POSITION": position, "JOINTS_0": joints, "WEIGHTS_0": weights},
                             "indices": indices, "material": 3}]}],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.7, 0.6, 1], "baseColorTexture": textured,
                                      "metallicFactor": 0.2, "roughnessFactor": 0.4,
                                      "metallicRoughnessTexture": {"index": 0}},
             "normalTexture": {"index": 0, "scale": 0.5}, "occlusionTexture": {"index": 0},
             "emissiveTexture": {"index": 0}, "emissiveFactor": [1, 1, 1],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4},
                            "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1, 0.9, 0.8]},
                            "KHR_materials_clearcoat": {"clearcoatFactor": 0.5}}},
            {"alphaMode": "MASK", "alphaCutoff": 0.4, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.3]},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8},
                            "KHR_materials_ior": {"ior": 1.33}}},
            {"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.9, 0.5]}},
            {"extensions": {"KHR_materials_unlit": {}}, "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9986, "wrapS": 33648, "wrapT": 33071}],
        "images": [{"bufferView": image_view, "mimeType": "image/png"}],
        "bufferViews": views,
        "accessors": accessors,
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode()}],
    }
    return doc


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    seeds = [json.dumps(features(), separators=(",", ":")).encode(), glb(features())]
    for path in sys.argv[2:]:
        with open(path, "rb") as f:
            data = f.read()
        if data[:4] == b"glTF":
            seeds.append(data)
            continue
        doc = embedded(path)
        seeds.append(json.dumps(doc, separators=(",", ":")).encode())
        seeds.append(glb(doc))
    for data in seeds:
        with open(os.path.join(out, hashlib.sha1(data).hexdigest()[:16]), "wb") as f:
            f.write(data)
    print("%d seeds in %s" % (len(seeds), out))


if __name__ == "__main__":
    main()
