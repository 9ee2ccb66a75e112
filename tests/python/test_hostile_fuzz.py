"""A seeded, bounded mutation fuzzer for the file readers: glTF (JSON), GLB, OBJ/MTL and EXR.

Each format starts from small valid files written here (the builders of test_loaders.py and
shgi.write_exr), mutates them (byte flips, truncation, duplicated or removed chunks, JSON values
swapped for huge, negative, NaN or wrong-typed ones, index changes, deep nesting, long strings,
OBJ/MTL lines with hostile numbers and statements, EXR header fields and offsets) and loads every
mutant in a child Python under hostile_support's address-space cap, a batch of mutants per child.
The child prints one verdict line per mutant; the parent finds a crash (a signal) or a hang (the
batch's generous timeout) by the last verdict printed, re-runs that mutant alone to confirm it,
saves it under hostile_cases/ and goes on with the rest of the batch.

A finding fails the test: a crash, a hang, or an exception that is not one the readers document
(OSError, ValueError, MemoryError; a RuntimeError, SystemError or UnicodeDecodeError is one). A
successful load is also read back (every property of every mesh, material, light and instance;
every array of read_exr) so that a conversion failing on the way to Python counts too.

Deterministic: random.Random seeded per format from SHGI_FUZZ_SEED. SHGI_FUZZ_INPUTS sets the
mutants per format (default below); run by hand with more, e.g.
    SHGI_FUZZ_INPUTS=50000 pytest -s test_hostile_fuzz.py
SHGI_FUZZ_LOG=<file> appends every verdict line (with the exception's message) to that file, and
SHGI_FUZZ_COMMIT=1 also commits (builds the BVH of) every scene that loaded.
"""

import base64
import collections
import json
import os
import pathlib
import random
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

import shgi
from hostile_support import CHILD_PRELUDE, TIMEOUT_SECONDS
from test_loaders import MTL_TEXT, OBJ_TEXT, gltf_document

SEED = int(os.environ.get("SHGI_FUZZ_SEED", "1128"))
INPUTS = int(os.environ.get("SHGI_FUZZ_INPUTS", "2000"))
BATCH = 200
LOG = os.environ.get("SHGI_FUZZ_LOG")  # a file to append every verdict line to (runs by hand)
# Loading a batch of these small files takes well under a second or two; a batch still running
# after this holds a hang (generous: other builds may share the machine).
BATCH_TIMEOUT_SECONDS = 120
CASES = pathlib.Path(__file__).parent / "hostile_cases"

# The child: loads each task's file with each named reader in turn, prints "<index> <verdict>"
# per task, flushing, so that the last line printed tells the parent how far it got.
CHILD_CODE = CHILD_PRELUDE + r'''
import json
import numpy as np

import os
import signal
import time
COMMIT = os.environ.get("SHGI_FUZZ_COMMIT") == "1"
shgi.set_log_level(shgi.LogLevel.ERROR)  # the warnings of thousands of mutants are only noise


def touch(value, depth=0):
    """Reads back what a load returned, as a caller would."""
    if depth > 4:
        return
    if isinstance(value, dict):
        for key, item in list(value.items()):
            str(key)
            touch(item, depth + 1)
    elif isinstance(value, (list, tuple)):
        for item in value:
            touch(item, depth + 1)
    elif isinstance(value, np.ndarray):
        value.sum()
    elif isinstance(value, shgi.Scene):
        for group in ("meshes", "materials", "lights", "instances", "textures"):
            for item in getattr(value, group):
                touch_properties(item, depth + 1)
        if value.has_camera:
            touch_properties(value.camera, depth + 1)
        touch_properties(value.world, depth + 1)
        touch(value.stats(), depth + 1)
        touch(value.bounds(), depth + 1)
        if COMMIT:
            value.commit()


def touch_properties(item, depth):
    for name in dir(type(item)):
        if not name.startswith("_") and isinstance(getattr(type(item), name), property):
            touch(getattr(item, name), depth)


def stand_in(kind):
    """For the harness's own test: a reader that crashes, hangs or raises what none documents."""
    def read(path):
        if kind == "crash":
            os.kill(os.getpid(), signal.SIGSEGV)
        if kind == "hang":
            time.sleep(3600)
        raise RuntimeError("undocumented")
    return read


def call(reader, path):
    if reader.startswith("stand_in_"):
        function = stand_in(reader[len("stand_in_"):])
    elif reader == "import_exr":
        function = shgi.ProbeField.import_exr
    else:
        function = getattr(shgi, reader)
    try:
        touch(function(path))
    except (OSError, ValueError, MemoryError) as error:
        return "error:" + type(error).__name__ + ":" + json.dumps(str(error)[:300])
    except BaseException as error:
        return "unexpected:" + type(error).__name__ + ":" + json.dumps(str(error)[:300])
    return "loaded"


print("ready", flush=True)
for index, readers, path in json.load(open(sys.argv[1])):
    print(index, "\t".join(call(reader, path) for reader in readers), flush=True)
'''

HOSTILE_INTS = [0, 1, -1, 2, 3, 7, 255, 256, 65535, 65536, 2**31 - 1, 2**31, -2**31, 2**32 - 1,
                2**32, 2**53, 2**63 - 1, 2**63, 2**64, -2**63, 10**30]
HOSTILE_FLOATS = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e-320, -0.0, 1e39,
                  -1e39, 3.4028235e38]
HOSTILE_STRINGS = ["", "x" * 100000, "\x00", "\udc80", "\ud800x", "../" * 40 + "missing",
                   "missing.bin", "data:", "data:,", "data:application/octet-stream;base64,!!!",
                   "data:application/octet-stream;base64,AAAA", "data:image/png;base64,iVBORw0K",
                   "%00", "a%2", "\u00e9\u4e2d", "image/png", "image/jpeg", "KHR_unknown"]


# --- byte-level mutations (every format) ----------------------------------------------------------

def interesting_word(rng):
    value = rng.choice(HOSTILE_INTS + [rng.randrange(2**32)])
    size = rng.choice([1, 2, 4, 4, 4, 8])
    return (value % (1 << (8 * size))).to_bytes(size, "little")


def mutate_bytes(rng, data):
    data = bytearray(data)
    if not data:
        return bytes(rng.randbytes(rng.randrange(1, 64)))
    kind = rng.randrange(9)
    n = len(data)
    if kind == 0:  # flip bits
        for _ in range(rng.randrange(1, 9)):
            data[rng.randrange(n)] ^= 1 << rng.randrange(8)
    elif kind == 1:  # set bytes to edge values
        for _ in range(rng.randrange(1, 5)):
            data[rng.randrange(n)] = rng.choice([0, 0xFF, 0x7F, 0x80, 0x20, 0x0A])
    elif kind == 2:  # an edge-valued integer at a random place
        word = interesting_word(rng)
        at = rng.randrange(n)
        data[at:at + len(word)] = word
    elif kind == 3:  # truncate
        del data[rng.randrange(n):]
    elif kind == 4:  # remove a chunk
        a = rng.randrange(n)
        del data[a:a + rng.randrange(1, max(2, n // 4))]
    elif kind == 5:  # duplicate a chunk
        a = rng.randrange(n)
        chunk = data[a:a + rng.randrange(1, max(2, n // 4))]
        at = rng.randrange(n + 1)
        data[at:at] = chunk * rng.choice([1, 1, 2, 8])
    elif kind == 6:  # insert random bytes
        at = rng.randrange(n + 1)
        data[at:at] = rng.randbytes(rng.randrange(1, 32))
    elif kind == 7:  # swap two chunks
        size = rng.randrange(1, max(2, n // 8))
        a, b = sorted(rng.randrange(max(1, n - size)) for _ in range(2))
        if a + size <= b:
            data[a:a + size], data[b:b + size] = data[b:b + size], data[a:a + size]
    else:  # append junk
        data += rng.randbytes(rng.randrange(1, 64))
    return bytes(data)


# --- JSON-level mutations (glTF, GLB's JSON chunk) ------------------------------------------------

def json_slots(value, out, depth=0):
    """(container, key) of every value in the tree."""
    if isinstance(value, dict):
        for key in value:
            out.append((value, key))
            json_slots(value[key], out, depth + 1)
    elif isinstance(value, list):
        for key in range(len(value)):
            out.append((value, key))
            json_slots(value[key], out, depth + 1)
    return out


def hostile_value(rng, old):
    kind = rng.randrange(10)
    if kind <= 2 and isinstance(old, int) and not isinstance(old, bool):
        return rng.choice([old + 1, old - 1, old + 2, old * 2, rng.randrange(0, 8), -old - 1])
    if kind == 3:
        return rng.choice(HOSTILE_INTS) * rng.choice([1, 1, -1])
    if kind == 4:
        return rng.choice(HOSTILE_FLOATS)
    if kind == 5:
        return rng.choice(HOSTILE_STRINGS)
    if kind == 6:
        depth = rng.choice([2, 50, 200, 255, 300])
        nested = 0
        for _ in range(depth):
            nested = [nested]
        return nested
    if kind == 7:
        return rng.choice([None, True, False, [], {}, [0] * rng.choice([1, 3, 16, 10000]),
                           {"": 0}, [None], [float("nan")] * 16])
    if kind == 8 and isinstance(old, list) and old:
        return old * rng.choice([2, 3, 100])
    if kind == 8 and isinstance(old, str):
        return old * rng.choice([2, 1000])
    return rng.choice(HOSTILE_INTS + HOSTILE_FLOATS)


# Keys a loader looks at, with values that are valid-looking but hostile.
INSERTED_KEYS = [
    ("byteStride", lambda r: r.choice([0, 1, 3, 4, 252, 256, 2**31, -4])),
    ("byteOffset", lambda r: r.choice(HOSTILE_INTS)),
    ("count", lambda r: r.choice(HOSTILE_INTS)),
    ("normalized", lambda r: True),
    ("matrix", lambda r: r.choice([[float("nan")] * 16, [0] * 16, [1e308] * 16, [1] * 15])),
    ("rotation", lambda r: r.choice([[0, 0, 0, 0], [float("nan")] * 4, [1e308] * 4])),
    ("scale", lambda r: r.choice([[0, 0, 0], [-1e308, 1, 1], [float("inf")] * 3])),
    ("children", lambda r: [r.randrange(-1, 6) for _ in range(r.randrange(0, 5))]),
    ("mesh", lambda r: r.randrange(-1, 4)),
    ("camera", lambda r: r.randrange(-1, 3)),
    ("material", lambda r: r.randrange(-1, 3)),
    ("indices", lambda r: r.randrange(-1, 5)),
    ("mode", lambda r: r.choice([0, 1, 2, 3, 5, 6, 7, -1])),
    ("targets", lambda r: [{"POSITION": r.randrange(0, 4)}]),
    ("sparse", lambda r: {"count": r.choice([1, 4, 2**31]),
                          "indices": {"bufferView": r.randrange(0, 4),
                                      "componentType": r.choice([5121, 5123, 5125, 5126])},
                          "values": {"bufferView": r.randrange(0, 4)}}),
    ("texCoord", lambda r: r.choice([0, 1, 7, 2**31])),
    ("baseColorTexture", lambda r: {"index": r.randrange(-1, 3), "texCoord": r.randrange(0, 3)}),
    ("extensionsRequired", lambda r: [r.choice(["KHR_draco_mesh_compression", "KHR_x",
                                                "KHR_lights_punctual"])]),
    ("extensions", lambda r: {"KHR_lights_punctual": {"light": r.randrange(-1, 4)},
                              "KHR_texture_transform": {"scale": [0, float("nan")]},
                              "KHR_materials_emissive_strength": {"emissiveStrength": 1e308}}),
    ("spot", lambda r: {"innerConeAngle": r.choice([-1, 2, float("nan")]),
                        "outerConeAngle": r.choice([0, 10, float("inf")])}),
    ("range", lambda r: r.choice([0, -1, float("nan")])),
    ("type", lambda r: r.choice(["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4",
                                 "spot", "directional", "orthographic", "nope", ""])),
    ("componentType", lambda r: r.choice([5120, 5121, 5122, 5123, 5125, 5126, 5124, 0])),
    ("uri", lambda r: r.choice(HOSTILE_STRINGS)),
    ("bufferView", lambda r: r.randrange(-1, 6)),
    ("buffer", lambda r: r.randrange(-1, 3)),
    ("source", lambda r: r.randrange(-1, 3)),
    ("sampler", lambda r: r.randrange(-1, 3)),
    ("scene", lambda r: r.randrange(-1, 3)),
    ("mimeType", lambda r: r.choice(["image/png", "image/jpeg", "image/ktx2", ""])),
]


def mutate_json(rng, document):
    slots = json_slots(document, [])
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        container, key = rng.choice(slots)
        kind = rng.randrange(6)
        try:
            old = container[key]
        except (KeyError, IndexError):
            continue
        if kind <= 2:
            container[key] = hostile_value(rng, old)
        elif kind == 3:  # remove
            del container[key]
        elif kind == 4 and isinstance(container, list):  # duplicate
            container.insert(key, old)
        else:  # insert a key a loader reads, into a random object
            objects = [value for value, _ in slots if isinstance(value, dict)]
            target = rng.choice(objects)
            name, make = rng.choice(INSERTED_KEYS)
            target[name] = make(rng)
        slots = json_slots(document, [])
    return document


def dump_json(document):
    """JSON text (ASCII: a lone surrogate as \\udc80); NaN stays the invalid token NaN, the
    infinities become 1e999, valid JSON that overflows a double."""
    text = json.dumps(document, allow_nan=True)
    return text.replace("-Infinity", "-1e999").replace("Infinity", "1e999").encode()


# --- glTF and GLB -------------------------------------------------------------------------------

def png_bytes(tmp_path):
    path = tmp_path / "seed_texture.png"
    shgi.write_png(path, np.linspace(0, 1, 4 * 4 * 4, dtype=np.float32).reshape(4, 4, 4))
    return path.read_bytes()


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(
        ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def make_png(width, height, color_type, bit_depth):
    """A PNG of those dimensions and type (palette: 4 entries), filter 0, pixels in a ramp."""
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[color_type]
    row_bytes = (width * channels * bit_depth + 7) // 8
    raw = b"".join(b"\0" + bytes((7 * x + 31 * y) % 256 if color_type != 3 else (x + y) % 4
                                  for x in range(row_bytes)) for y in range(height))
    if color_type == 3:
        raw = b"".join(b"\0" + bytes([0b00011011] * row_bytes) for _ in range(height))
    chunks = png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, color_type,
                                            0, 0, 0))
    if color_type == 3:
        chunks += png_chunk(b"PLTE", bytes(range(12)))
    return b"\x89PNG\r\n\x1a\n" + chunks + png_chunk(b"IDAT", zlib.compress(raw)) + png_chunk(
        b"IEND", b"")


def mutate_png(rng, png):
    """An IHDR field (width, height, depth, colour type, interlace) or the bytes."""
    if rng.random() < 0.5:
        data = bytearray(png)
        at = rng.choice([16, 20, 24, 25, 26, 27, 28])
        value = rng.choice(HOSTILE_INTS + [rng.randrange(1, 300)])
        size = 4 if at in (16, 20) else 1
        data[at:at + size] = (value % (1 << (8 * size))).to_bytes(size, "big")
        data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])) & 0xFFFFFFFF)
        return bytes(data)
    return mutate_bytes(rng, png)


PNG_SEEDS = [make_png(5, 3, 6, 16), make_png(4, 4, 0, 8), make_png(3, 2, 4, 8),
             make_png(9, 2, 3, 2), make_png(2, 7, 2, 16), make_png(1, 1, 0, 1)]


def gltf_seeds(png):
    """The loaders' test scene, and one with a texture, a node hierarchy, strided normals, spot
    and sun lights and an orthographic camera."""
    plain = gltf_document()
    rich = gltf_document()
    rich["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png).decode()}]
    rich["samplers"] = [{"magFilter": 9729, "wrapS": 33648}]
    rich["textures"] = [{"source": 0, "sampler": 0}]
    rich["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    rich["materials"][0]["emissiveFactor"] = [1, 0.5, 0]
    rich["materials"].append({"name": "Second", "alphaMode": "MASK", "doubleSided": True})
    rich["meshes"][0]["primitives"].append(
        {"attributes": {"POSITION": 0, "NORMAL": 3}, "indices": 2, "material": 1})
    data = base64.b64decode(rich["buffers"][0]["uri"].split(",", 1)[1])
    normals = struct.pack("<12f", *[0, 1, 0] * 4)
    sparse_indices = struct.pack("<2H", 1, 3)
    sparse_values = struct.pack("<6f", 0, 1, 0, 0, 1, 0)
    offset = len(data) + (-len(data) % 4)
    data = data + b"\0" * (offset - len(data)) + normals + sparse_indices + sparse_values
    rich["bufferViews"] += [
        {"buffer": 0, "byteOffset": offset, "byteLength": 48, "byteStride": 12},
        {"buffer": 0, "byteOffset": offset + 48, "byteLength": 4},
        {"buffer": 0, "byteOffset": offset + 52, "byteLength": 24}]
    rich["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC3"})
    # Views 4 and 5 are there for a "sparse" object the mutations may add (the loader refuses
    # sparse accessors by name).
    rich["buffers"][0] = {"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                          + base64.b64encode(data).decode()}
    rich["nodes"][0]["children"] = [3]
    rich["nodes"].append({"name": "Child", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,
                                                                 0, 3, 0, 0, 1]})
    rich["nodes"].append({"name": "Sun", "rotation": [-0.7071, 0, 0, 0.7071],
                          "extensions": {"KHR_lights_punctual": {"light": 1}}})
    rich["nodes"].append({"name": "Spot", "extensions": {"KHR_lights_punctual": {"light": 2}}})
    rich["nodes"].append({"name": "Ortho", "camera": 1})
    rich["scenes"][0]["nodes"] += [4, 5, 6]
    rich["extensions"]["KHR_lights_punctual"]["lights"] += [
        {"type": "directional", "intensity": 3, "color": [1, 0.9, 0.8]},
        {"type": "spot", "intensity": 100, "spot": {"innerConeAngle": 0.2,
                                                     "outerConeAngle": 0.6}}]
    rich["cameras"].append({"type": "orthographic",
                            "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.1, "zfar": 50}})
    return [plain, rich]


def glb_parts(document):
    """(JSON document without the data URI, BIN bytes): the buffer moves into GLB's BIN chunk."""
    document = json.loads(json.dumps(document))
    data = base64.b64decode(document["buffers"][0].pop("uri").split(",", 1)[1])
    for image in document.get("images", []):  # the PNG goes into the BIN chunk too
        png = base64.b64decode(image.pop("uri").split(",", 1)[1])
        data += b"\0" * (-len(data) % 4)
        document["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(data), "byteLength": len(png)})
        image.update(bufferView=len(document["bufferViews"]) - 1, mimeType="image/png")
        data += png
    data += b"\0" * (-len(data) % 4)
    document["buffers"][0]["byteLength"] = len(data)
    return document, data


def glb_pack(json_bytes, chunks, version=2):
    """A .glb: the JSON chunk (space-padded) and the other (type, bytes) chunks."""
    body = b""
    for kind, data in [(b"JSON", json_bytes + b" " * (-len(json_bytes) % 4))] + chunks:
        body += struct.pack("<I4s", len(data), kind) + data
    return struct.pack("<4sII", b"glTF", version, 12 + len(body)) + body


def with_mutated_image(rng, document):
    """The document with its image replaced by a mutant of one of the PNG seeds."""
    png = mutate_png(rng, rng.choice(PNG_SEEDS))
    document["images"][0]["uri"] = "data:image/png;base64," + base64.b64encode(png).decode()
    return document


def mutate_gltf(rng, seed):
    document = json.loads(json.dumps(seed))
    if "images" in document and rng.random() < 0.2:
        return dump_json(with_mutated_image(rng, document))
    if rng.random() < 0.8:
        data = dump_json(mutate_json(rng, document))
        return mutate_bytes(rng, data) if rng.random() < 0.1 else data
    return mutate_bytes(rng, dump_json(document))


def mutate_glb(rng, seed):
    if "images" in seed and rng.random() < 0.15:
        document, data = glb_parts(with_mutated_image(rng, json.loads(json.dumps(seed))))
        return glb_pack(dump_json(document), [(b"BIN\0", data)])
    document, data = glb_parts(seed)
    kind = rng.randrange(10)
    chunks = [(b"BIN\0", data)]
    if kind <= 3:  # the JSON
        return glb_pack(dump_json(mutate_json(rng, document)), chunks)
    if kind == 4:  # the BIN chunk's bytes
        return glb_pack(dump_json(document), [(b"BIN\0", mutate_bytes(rng, data))])
    if kind == 5:  # chunks: removed, repeated, unknown, reordered
        choice = rng.randrange(4)
        if choice == 0:
            chunks = []
        elif choice == 1:
            chunks = chunks * rng.choice([2, 3])
        elif choice == 2:
            chunks.insert(rng.randrange(2), (rng.choice([b"XTRA", b"JSON", b"\0\0\0\0"]),
                                             rng.randbytes(rng.randrange(0, 64))))
        else:
            whole = glb_pack(dump_json(document), chunks)
            json_end = 20 + struct.unpack_from("<I", whole, 12)[0]
            return whole[:12] + whole[json_end:] + whole[12:json_end]
        return glb_pack(dump_json(document), chunks)
    whole = bytearray(glb_pack(dump_json(document), chunks))
    if kind <= 7:  # a header or chunk-header field
        json_end = 20 + struct.unpack_from("<I", whole, 12)[0]
        at = rng.choice([0, 4, 8, 12, 16, json_end, json_end + 4])
        value = rng.choice(HOSTILE_INTS + [len(whole), len(whole) + 4, len(whole) - 4, json_end])
        whole[at:at + 4] = (value % 2**32).to_bytes(4, "little")
        return bytes(whole)
    return mutate_bytes(rng, bytes(whole))


# --- OBJ and MTL --------------------------------------------------------------------------------

HOSTILE_NUMBERS = ["nan", "-nan", "inf", "-inf", "NaN", "infinity", "1e39", "-1e39", "1e-400",
                   "1e400", "0x10", "1e", "--1", "+-1", "1..2", ".", "-", "+", "e5",
                   "99999999999999999999", "2147483647", "2147483648", "-2147483648",
                   "-2147483649", "4294967295", "4294967296", "9223372036854775808", "0", "-0",
                   "-1", "-99", "1.#IND", "1/", "//", "1//1", "/1/1", "1/1/1/1", "1/-1", "1/0",
                   "1" * 400, "0." + "0" * 400 + "1", "1e-45", "3.4028236e38"]
HOSTILE_OBJ_LINES = [
    "f", "f 1", "f 1 2", "f 1 1 1", "f -1 -1 -1", "f 0 0 0", "f 1/1/1 2/2/2 3/3/3",
    "f 1// 2// 3//", "f 1/ 2/ 3/", "f 1/99 2/99 3/99", "f 1//99 2//99 3//99", "v", "v 1",
    "vt", "vn 1", "vp 1 2", "l 1 2", "l 1", "p 1", "p 99", "s off", "s 1", "s 99999999999",
    "g", "o", "usemtl", "usemtl Missing", "mtllib", "mtllib missing.mtl", "mtllib ../" * 3,
    "mtllib /dev/zero", "mtllib /dev", "cstype bspline", "curv 0 1 1 2", "surf 0 1 0 1 1 2 3",
    "#", "\\", "f 1 2 \\", "\x00", "\t\t", "v 1 2 3 4 5 6 7 8 9 10",
]
HOSTILE_MTL_LINES = [
    "newmtl", "newmtl Red", "newmtl " + "x" * 10000, "Kd", "Kd 1", "Kd 1 2 3 4 5", "Ke -1 -1 -1",
    "Ns", "Ns -1", "Ns 1e38", "Ni 0", "Ni -1", "Pr 2", "Pm -5", "d", "d -halo", "Tr 2", "illum",
    "illum 99999999999", "Tf xyz 1 1 1", "Ks spectral", "Ks xyz 1", "map_Kd",
    "map_Kd -bm nan x.png",
    "map_Kd -o 1 1 1 " + "y" * 5000, "map_Ke /dev/zero", "bump -imfchan z", "refl -type sphere",
    "Pc 1", "aniso nan", "norm x.png", "#", "\x00",
]


def mutate_lines(rng, text, extras):
    lines = text.split("\n")
    for _ in range(rng.choice([1, 1, 2, 3])):
        kind = rng.randrange(8)
        i = rng.randrange(len(lines))
        words = lines[i].split(" ")
        if kind <= 2 and len(words) > 1:  # a number becomes a hostile one
            words[rng.randrange(1, len(words))] = rng.choice(HOSTILE_NUMBERS)
            lines[i] = " ".join(words)
        elif kind == 3 and len(words) > 1:  # an index or number nearby
            j = rng.randrange(1, len(words))
            words[j] = str(rng.randrange(-12, 20)) + rng.choice(["", "/1", "//1", "/1/1", "/-1"])
            lines[i] = " ".join(words)
        elif kind == 4:  # remove, duplicate or swap lines
            choice = rng.randrange(3)
            if choice == 0:
                del lines[i]
            elif choice == 1:
                lines.insert(i, lines[i])
            else:
                j = rng.randrange(len(lines))
                lines[i], lines[j] = lines[j], lines[i]
        elif kind == 5:  # a hostile statement
            lines.insert(i, rng.choice(extras))
        elif kind == 6:  # a long face or a long line
            if rng.random() < 0.5:
                lines.insert(i, "f " + " ".join(str(rng.randrange(-8, 9) or 1)
                                                for _ in range(rng.choice([3, 40, 3000]))))
            else:
                lines.insert(i, words[0] + " " + " ".join(["1"] * rng.choice([100, 20000])))
        else:  # line endings, continuation, no final newline
            joiner = rng.choice(["\r\n", "\r", "\\\n", "\n\n"])
            return joiner.join(lines).rstrip("\n")
        if not lines:
            lines = [""]
    return "\n".join(lines)


OBJ_SEEDS = [
    OBJ_TEXT.replace("two.mtl", "{mtl}"),
    "mtllib {mtl}\nusemtl Red\n" + "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
    "vt 0 1\nvn 0 0 1\ng quad\nf 1/1/1 2/2/1 3/3/1 4/4/1\ng tri\ns 1\nf -4//1 -3//1 -2//1\n"
    "o line\nl 1 2\nusemtl Glow\nf 1 2 3\n",
]


def mutate_obj(rng, seed, name):
    """(OBJ bytes, MTL bytes) for mutant files <name>.obj / <name>.mtl."""
    obj = seed.replace("{mtl}", name + ".mtl")
    mtl = MTL_TEXT
    target = rng.randrange(10)
    if target <= 5:
        obj = mutate_lines(rng, obj, HOSTILE_OBJ_LINES)
    elif target <= 8:
        mtl = mutate_lines(rng, mtl, HOSTILE_MTL_LINES)
    obj_bytes, mtl_bytes = obj.encode(), mtl.encode()
    if target == 9 or rng.random() < 0.1:
        if rng.random() < 0.7:
            obj_bytes = mutate_bytes(rng, obj_bytes)
        else:
            mtl_bytes = mutate_bytes(rng, mtl_bytes)
    return obj_bytes, mtl_bytes


# --- EXR ----------------------------------------------------------------------------------------

EXR_ATTRIBUTES = [b"channels", b"compression", b"dataWindow", b"displayWindow", b"lineOrder",
                  b"pixelAspectRatio", b"screenWindowWidth", b"chunkCount", b"name", b"type",
                  b"tiles", b"version"]


def exr_seeds(tmp_path):
    from test_io import THREE_PART_EXR
    y, x = np.mgrid[0:5, 0:7].astype(np.float32)
    rgba = np.stack([x, y, x * y, np.ones_like(x)], axis=-1)
    seeds = []
    for i, (compression, pixel_type) in enumerate([("zip", "float"), ("piz", "half"),
                                                    ("rle", "float"), ("none", "half"),
                                                    ("zips", "float"), ("piz", "float")]):
        path = tmp_path / f"seed{i}.exr"
        layers = {"Combined": rgba}
        if i >= 4:
            layers.update({"": rgba[..., :3], "Depth": x,
                           "Lattice": np.repeat(rgba, 3, axis=-1)[..., :9]})
        shgi.write_exr(path, layers, pixel_type=pixel_type, compression=compression,
                       channel_names={"Lattice": [f"c{k}" for k in range(9)]} if i >= 4 else {})
        seeds.append(path.read_bytes())
    return seeds + [THREE_PART_EXR]


def mutate_exr(rng, seed):
    data = bytearray(seed)
    for _ in range(rng.choice([1, 1, 2, 3])):
        kind = rng.randrange(10)
        names = [name for name in EXR_ATTRIBUTES if name + b"\0" in data]
        end = data.find(b"\0\0", 8)  # about where the header ends
        if kind <= 3 and names:  # a header attribute's size or value
            name = rng.choice(names)
            at = data.find(name + b"\0")
            at = data.find(b"\0", at + len(name) + 1) + 1  # past the type name
            target = at + rng.choice([0, 4, 4, 8, 12, 16, 20]) if kind else at
            word = interesting_word(rng)
            data[target:target + len(word)] = word
        elif kind == 4 and 8 < end < len(data) - 72:  # the offset table: a chunk offset
            at = rng.randrange(end, min(len(data) - 8, end + 200))
            data[at:at + 8] = rng.choice(HOSTILE_INTS + [len(data), len(data) - 1]).__mod__(
                2**64).to_bytes(8, "little")
        else:
            data = bytearray(mutate_bytes(rng, bytes(data)))
    return bytes(data)


# --- probe field exports (ProbeField.import_exr: a JSON naming an SH and a visibility EXR) ------

def probe_export_seed(workdir):
    """A small solved probe grid's export: seed.json, seed_volume0.exr and
    seed_volume0_visibility.exr."""
    from scene_support import committed
    from test_probe_grid import scenes, solved_grid
    scene = committed(scenes.cornell_box(0.05))
    solved_grid(scene, 1, rays_per_probe=8, spacing=1.0).field().export(str(workdir / "seed.json"))
    return json.loads((workdir / "seed.json").read_text())


def mutate_probe_export(rng, seed, workdir, name):
    """Writes <name>.json, and <name>_sh.exr or <name>_vis.exr when that one is the mutant."""
    document = json.loads(json.dumps(seed))
    volume = document["volumes"][0]
    target = rng.randrange(4)
    if target <= 1:
        document = mutate_json(rng, document)
    else:
        key, suffix = [("sh_file", "_sh.exr"), ("visibility_file", "_vis.exr")][target - 2]
        exr = workdir / (name + suffix)
        exr.write_bytes(mutate_exr(rng, (workdir / volume[key]).read_bytes()))
        volume[key] = exr.name
    (workdir / (name + ".json")).write_bytes(dump_json(document))


# --- the runner ---------------------------------------------------------------------------------

Task = collections.namedtuple("Task", "index readers path")


def run_child(tasks, workdir, tag, timeouts=(BATCH_TIMEOUT_SECONDS, TIMEOUT_SECONDS)):
    """Runs `tasks` in one capped child: (verdict lines by index, return code or "hang", stderr).
    timeouts: for a batch, for a task alone."""
    tasks_file = workdir / f"tasks_{tag}.json"
    tasks_file.write_text(json.dumps([list(task) for task in tasks]))
    timeout = timeouts[0] if len(tasks) > 1 else timeouts[1]
    try:
        child = subprocess.run([sys.executable, "-c", CHILD_CODE, str(tasks_file)],
                               capture_output=True, text=True, timeout=timeout)
        stdout, stderr, code = child.stdout, child.stderr, child.returncode
    except subprocess.TimeoutExpired as expired:
        stdout = (expired.stdout or b"").decode(errors="replace")
        stderr = (expired.stderr or b"").decode(errors="replace")
        code = "hang"
    if not stdout.startswith("ready\n"):  # before any mutant: no finding, a broken harness
        pytest.fail(f"the fuzzing child did not start (code {code}):\n{stderr[-2000:]}")
    verdicts = {}
    for line in stdout.splitlines():
        index, _, verdict = line.partition(" ")
        if index.lstrip("-").isdigit():
            verdicts[int(index)] = verdict
    return verdicts, code, stderr


def save_case(fmt, task, files, cases):
    """Copies a confirmed crasher and the files beside it that it names to its own folder
    <cases>/<format>_seed<seed>_<name>/, under their own names (an OBJ names its MTL)."""
    folder = cases / f"{fmt}_seed{SEED}_{pathlib.Path(task.path).stem}"
    folder.mkdir(parents=True, exist_ok=True)
    for path in files:
        (folder / path.name).write_bytes(path.read_bytes())
    return str(folder)


def fuzz(fmt, tasks, files_of, workdir, cases=CASES,
         timeouts=(BATCH_TIMEOUT_SECONDS, TIMEOUT_SECONDS)):
    """Runs every task in batches; returns Counter of outcomes and the findings' descriptions."""
    counts = collections.Counter()
    findings = []
    for start in range(0, len(tasks), BATCH):
        pending = tasks[start:start + BATCH]
        while pending:
            verdicts, code, stderr = run_child(pending, workdir, f"{fmt}_{start}", timeouts)
            done = [task for task in pending if task.index in verdicts]
            if LOG:
                with open(LOG, "a") as log:
                    log.writelines(f"{fmt} {t.index} {verdicts[t.index]}\n" for t in done)
            for task in done:
                results = verdicts[task.index].split("\t")
                unexpected = [r for r in results if r.startswith("unexpected:")]
                if unexpected:
                    counts["unexpected exceptions"] += 1
                    findings.append(f"{fmt} #{task.index} {task.path}: {unexpected[0]}")
                elif results[-1] == "loaded":
                    counts["loaded fine"] += 1
                else:
                    counts["clear exceptions"] += 1
            if code == 0 and len(done) == len(pending):
                break
            if len(done) == len(pending):  # every verdict printed, then the child died
                counts["crashes"] += 1
                findings.append(f"{fmt}: a child ended with {code} after its last verdict "
                                f"({pending[-1].path}):\n{stderr[-1500:]}")
                break
            # The child died (a signal or another code) or hung on the first task without a
            # verdict: confirm that task alone, then go on with the ones after it.
            culprit = pending[len(done)]
            _, alone_code, alone_stderr = run_child([culprit], workdir, f"{fmt}_alone", timeouts)
            hung = "hang" in (code, alone_code)
            if alone_code == 0:  # only in company (state left by an earlier mutant): still one
                alone_stderr = stderr
            counts["hangs" if hung else "crashes"] += 1
            saved = save_case(fmt, culprit, files_of(culprit), cases)
            findings.append(f"{fmt} #{culprit.index} {culprit.path}: "
                            f"{'hang' if hung else 'crash'} (code {code}, alone {alone_code}); "
                            f"saved as {saved}:\n"
                            f"{alone_stderr[-1500:]}")
            pending = pending[len(done) + 1:]
    counts["inputs"] = len(tasks)
    return counts, findings


def build_tasks(fmt, workdir, tmp_path):
    """Writes INPUTS mutants of `fmt` into workdir; returns (tasks, files_of, seeds' tasks)."""
    rng = random.Random(f"{SEED}:{fmt}")
    tasks, seed_tasks = [], []
    if fmt in ("gltf", "glb"):
        seeds = gltf_seeds(png_bytes(tmp_path))
        for k, seed in enumerate(seeds):
            path = workdir / f"seed{k}.{fmt}"
            path.write_bytes(dump_json(seed) if fmt == "gltf" else glb_pack(
                dump_json(glb_parts(seed)[0]), [(b"BIN\0", glb_parts(seed)[1])]))
            seed_tasks.append(Task(-1 - k, ["load_gltf"], str(path)))
        mutate = mutate_gltf if fmt == "gltf" else mutate_glb
        for i in range(INPUTS):
            path = workdir / f"m{i:06d}.{fmt}"
            path.write_bytes(mutate(rng, rng.choice(seeds)))
            tasks.append(Task(i, ["load_gltf"], str(path)))
        return tasks, lambda task: [pathlib.Path(task.path)], seed_tasks
    if fmt == "obj":
        for k, seed in enumerate(OBJ_SEEDS):
            (workdir / f"seed{k}.obj").write_text(seed.replace("{mtl}", f"seed{k}.mtl"))
            (workdir / f"seed{k}.mtl").write_text(MTL_TEXT)
            seed_tasks.append(Task(-1 - k, ["load_obj"], str(workdir / f"seed{k}.obj")))
        for i in range(INPUTS):
            name = f"m{i:06d}"
            obj, mtl = mutate_obj(rng, rng.choice(OBJ_SEEDS), name)
            (workdir / f"{name}.obj").write_bytes(obj)
            (workdir / f"{name}.mtl").write_bytes(mtl)
            tasks.append(Task(i, ["load_obj"], str(workdir / f"{name}.obj")))
        return tasks, lambda task: [pathlib.Path(task.path),
                                    pathlib.Path(task.path).with_suffix(".mtl")], seed_tasks
    if fmt == "probe_export":
        seed = probe_export_seed(workdir)
        seed_tasks.append(Task(-1, ["import_exr"], str(workdir / "seed.json")))
        for i in range(INPUTS):
            mutate_probe_export(rng, seed, workdir, f"m{i:06d}")
            tasks.append(Task(i, ["import_exr"], str(workdir / f"m{i:06d}.json")))
        return tasks, lambda task: sorted(pathlib.Path(task.path).parent.glob(
            pathlib.Path(task.path).stem + "*")) + sorted(workdir.glob("seed_volume0*")), seed_tasks
    assert fmt == "exr"
    seeds = exr_seeds(tmp_path)
    readers = ["read_exr_info", "read_exr"]
    for k, seed in enumerate(seeds):
        (workdir / f"seed{k}.exr").write_bytes(seed)
        seed_tasks.append(Task(-1 - k, readers, str(workdir / f"seed{k}.exr")))
    for i in range(INPUTS):
        path = workdir / f"m{i:06d}.exr"
        path.write_bytes(mutate_exr(rng, rng.choice(seeds)))
        tasks.append(Task(i, readers, str(path)))
    return tasks, lambda task: [pathlib.Path(task.path)], seed_tasks


# Per format: the suffix of the file a reader is given, and the readers.
FORMATS = {"gltf": (".gltf", ["load_gltf"]), "glb": (".glb", ["load_gltf"]),
           "obj": (".obj", ["load_obj"]), "exr": (".exr", ["read_exr_info", "read_exr"]),
           "probe_export": (".json", ["import_exr"])}


@pytest.mark.parametrize("case", sorted(p.name for p in CASES.glob("*_seed*") if p.is_dir()))
def test_saved_reproducers_end_in_documented_exceptions(tmp_path, case):
    """Every mutant the fuzzer crashed or hung on, kept in hostile_cases/<format>_seed<seed>_<name>/
    with the files it names, loaded alone."""
    fmt, _, rest = case.partition("_seed")
    suffix, readers = FORMATS[fmt]
    path = CASES / case / (rest.partition("_")[2] + suffix)
    verdicts, code, stderr = run_child([Task(0, readers, str(path))], tmp_path, "case")
    assert code == 0, f"{case}: ended with {code}:\n{stderr[-2000:]}"
    assert not any(v.startswith("unexpected:") for v in verdicts[0].split("\t")), verdicts[0]


@pytest.mark.parametrize("fmt", ["gltf", "glb", "obj", "exr", "probe_export"])
def test_mutated_files_end_in_documented_exceptions(tmp_path, fmt):
    workdir = tmp_path / fmt
    workdir.mkdir()
    tasks, files_of, seed_tasks = build_tasks(fmt, workdir, tmp_path)

    # The seeds are valid files, so the mutants start from what the readers accept.
    verdicts, code, stderr = run_child(seed_tasks, workdir, "seeds")
    assert code == 0, stderr[-2000:]
    assert {verdicts.get(t.index) for t in seed_tasks} <= {"loaded", "loaded\tloaded"}, verdicts

    counts, findings = fuzz(fmt, tasks, files_of, workdir)
    order = ["inputs", "clear exceptions", "loaded fine", "unexpected exceptions", "crashes",
             "hangs"]
    summary = f"{fmt} (seed {SEED}): " + ", ".join(f"{counts[k]} {k}" for k in order)
    print("\n" + summary)
    assert not findings, summary + "\n" + "\n".join(findings[:20])
    assert counts["clear exceptions"] + counts["loaded fine"] + counts[
        "unexpected exceptions"] + counts["crashes"] + counts["hangs"] == len(tasks), summary


def test_the_png_seeds_decode_as_textures(tmp_path):
    """The PNGs the glTF mutants embed are valid to begin with (a texture that does not decode is
    only a warning, so the seed check of the fuzz test would not see it)."""
    document = gltf_seeds(png_bytes(tmp_path))[1]
    for png in PNG_SEEDS:
        width, height = struct.unpack(">II", png[16:24])
        document["images"][0]["uri"] = "data:image/png;base64," + base64.b64encode(png).decode()
        path = tmp_path / "textured.gltf"
        path.write_bytes(dump_json(document))
        textures = shgi.load_gltf(path).textures
        assert [(t.width, t.height) for t in textures] == [(width, height)]


def test_the_harness_pins_a_crash_a_hang_and_an_undocumented_exception_on_their_input(tmp_path):
    """The detection itself: stand-in readers that crash (SIGSEGV), hang or raise RuntimeError
    among ordinary loads are each found, named by their input, confirmed alone and saved, and
    the mutants after them are still loaded. Short timeouts: the stand-in hang never ends."""
    good = tmp_path / "good.obj"
    good.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    readers = (["load_obj"] * 3 + ["stand_in_crash"] + ["load_obj"] * 2
               + ["stand_in_hang", "stand_in_raise", "load_obj"])
    tasks = [Task(i, [reader], str(good if reader == "load_obj" else tmp_path / f"t{i}.obj"))
             for i, reader in enumerate(readers)]
    for task in tasks[3::3]:
        pathlib.Path(task.path).write_text("v 0 0 0\n")
    cases = tmp_path / "cases"
    counts, findings = fuzz("obj", tasks, lambda task: [pathlib.Path(task.path)], tmp_path,
                            cases, timeouts=(10, 5))
    assert counts == {"inputs": 9, "loaded fine": 6, "crashes": 1, "hangs": 1,
                      "unexpected exceptions": 1}, counts
    assert [f.split(":")[0].split(" #")[1].split(" ")[0] for f in findings] == ["3", "6", "7"]
    # -11 is SIGSEGV; under ASan, which catches the signal and aborts, -6
    assert "crash (code -" in findings[0] and ", alone -" in findings[0]
    assert "hang (code hang" in findings[1]
    assert "unexpected:RuntimeError" in findings[2]
    assert sorted(p.name for p in cases.iterdir()) == [f"obj_seed{SEED}_t3", f"obj_seed{SEED}_t6"]
