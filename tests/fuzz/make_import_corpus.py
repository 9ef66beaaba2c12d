#!/usr/bin/env python3
"""make_import_corpus.py: writes the fuzz_import seeds (run once by hand; output checked in):
python3 tests/fuzz/make_import_corpus.py tests/fuzz/corpus/import

Each file is one byte picking the format (0 PLY, 1 OBJ, 2 STL, 3 OFF, 4 glTF, 5 GLB; fuzz_import.c's table)
then the asset. regress-* are the malformed assets of issue 41 that the import refuses cleanly."""
import base64
import json
import os
import struct
import sys

PLY, OBJ, STL, OFF, GLTF, GLB = range(6)

TET = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def ply_header(fmt, vertices, faces):
    return (f"ply\nformat {fmt} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n").encode()


def ply_ascii(vertices, faces, declared_faces=None):
    body = "".join(f"{x} {y} {z}\n" for x, y, z in vertices)
    body += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)
    count = len(faces) if declared_faces is None else declared_faces
    return ply_header("ascii", len(vertices), count) + body.encode()


def ply_binary(vertices, faces):
    body = b"".join(struct.pack("<3f", *v) for v in vertices)
    body += b"".join(struct.pack("<B%di" % len(f), len(f), *f) for f in faces)
    return ply_header("binary_little_endian", len(vertices), len(faces)) + body


def stl_binary(triangles):
    out = b"seed".ljust(80, b"\0") + struct.pack("<I", len(triangles))
    for t in triangles:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *TET[i]) for i in t) + b"\0\0"
    return out


def gltf_triangle():
    """A glTF document with its buffer in a data: URI, and the same as the GLB's JSON and binary chunk."""
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    blob = positions + indices
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "triangle"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    }
    glb_json = json.dumps(doc).encode()
    glb_json += b" " * (-len(glb_json) % 4)
    glb = struct.pack("<I4s", len(glb_json), b"JSON") + glb_json + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    glb = b"glTF" + struct.pack("<II", 2, 12 + len(glb)) + glb
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    return json.dumps(doc).encode(), glb


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/fuzz/corpus/import"
    os.makedirs(out, exist_ok=True)
    gltf, glb = gltf_triangle()
    obj = (b"mtllib seed.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nv 0 0 1\n"
           b"g pentagon\nusemtl red\nf 1 2 3 4 5\ng side\nusemtl blue\nf 1 2 6\nl 1 6\n")
    seeds = {
        "ply-ascii-tetrahedron": (PLY, ply_ascii(TET, TET_FACES)),
        "ply-binary-quad": (PLY, ply_binary(TET, [(0, 1, 2, 3)])),
        "obj-pentagon-materials": (OBJ, obj),
        "stl-ascii-triangle": (STL, b"solid seed\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                    b"vertex 0 1 0\nendloop\nendfacet\nendsolid seed\n"),
        "stl-binary-tetrahedron": (STL, stl_binary(TET_FACES)),
        "off-tetrahedron": (OFF, b"OFF\n4 4 6\n" + "".join(f"{x} {y} {z}\n" for x, y, z in TET).encode()
                            + "".join("3 %d %d %d\n" % f for f in TET_FACES).encode()),
        "gltf-triangle": (GLTF, gltf),
        "glb-triangle": (GLB, glb),
        # issue 41 item 1: face indices past the vertex count (ASCII and binary)
        "regress-ply-index-past-count": (PLY, ply_ascii(TET[:3], [(0, 1, 2), (0, 1, 2147483647)])),
        "regress-ply-binary-index-past-count": (PLY, ply_binary(TET[:3], [(0, 1, 1000000)])),
        # issue 41 item 3: a PLY cut before its faces (assimp leaves them empty; triangulation asserted)
        "regress-ply-faces-cut": (PLY, ply_ascii(TET, [], declared_faces=4)),
    }
    for name, (fmt, data) in seeds.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(bytes([fmt]) + data)


if __name__ == "__main__":
    main()
