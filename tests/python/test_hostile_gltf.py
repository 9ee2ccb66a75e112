"""Hostile glTF files: each is loaded in a child Python with an address-space cap and a timeout,
so a crash (a signal), a hang or a runaway allocation fails the test instead of taking pytest
down (hostile_support.load_in_child). Every case must end in a Python exception that names the
file and what is wrong with it.
"""

import base64
import json
import os
import struct

import pytest

from hostile_support import load_in_child

BASE_DOCUMENT = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}]}


def deeply_nested(depth):
    """BASE_DOCUMENT with `extras` holding `depth` nested arrays (JSON text: ~2 bytes a level)."""
    text = json.dumps(BASE_DOCUMENT)
    return text[:-1] + ', "extras": ' + "[" * depth + "]" * depth + "}"


def glb_of(json_text):
    """A .glb holding `json_text` as its JSON chunk (padded to 4 bytes with spaces), no BIN."""
    chunk = json_text.encode() + b" " * (-len(json_text.encode()) % 4)
    header = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(chunk))
    return header + struct.pack("<I4s", len(chunk), b"JSON") + chunk


@pytest.mark.parametrize("container", ["gltf", "glb"])
def test_json_nested_30000_deep_is_refused_not_a_stack_overflow(tmp_path, container):
    path = tmp_path / f"deep.{container}"
    text = deeply_nested(30000)
    if container == "gltf":
        path.write_text(text)
    else:
        path.write_bytes(glb_of(text))
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert str(path) in message and "nests deeper than 256 levels" in message


def test_brackets_inside_strings_do_not_count_as_nesting(tmp_path):
    document = dict(BASE_DOCUMENT, extras={"note": "[" * 1000 + "{\\\"" * 500})
    path = tmp_path / "strings.gltf"
    path.write_text(json.dumps(document))
    assert load_in_child(path)[0] == ("loaded", "")


def test_moderate_nesting_in_extras_still_loads(tmp_path):
    path = tmp_path / "nested.gltf"
    path.write_text(deeply_nested(200))
    assert load_in_child(path)[0] == ("loaded", "")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_buffer_uri_naming_a_fifo_is_refused_without_blocking(tmp_path):
    os.mkfifo(tmp_path / "pipe.bin")
    path = tmp_path / "fifo.gltf"
    path.write_text(json.dumps(dict(BASE_DOCUMENT, buffers=[{"uri": "pipe.bin", "byteLength": 4}])))
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert "pipe.bin" in message and "not a regular file" in message


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_image_uri_naming_a_fifo_costs_only_the_image(tmp_path):
    os.mkfifo(tmp_path / "pipe.png")
    path = tmp_path / "fifo.gltf"
    path.write_text(json.dumps(dict(BASE_DOCUMENT, images=[{"uri": "pipe.png"}])))
    verdict, log = load_in_child(path)
    assert verdict == ("loaded", "")
    assert "pipe.png" in log and "not a regular file" in log


def test_nodes_listing_a_child_twice_are_refused_not_expanded(tmp_path):
    """41 nodes, each listing the next twice: 2^40 paths to the last one (depth first, the last
    node is the first reached again)."""
    nodes = [{"children": [i + 1, i + 1]} for i in range(40)] + [{}]
    document = dict(BASE_DOCUMENT, scenes=[{"nodes": [0]}], nodes=nodes)
    path = tmp_path / "doubling.gltf"
    path.write_text(json.dumps(document))
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert "node 40 is reached twice" in message and str(path) in message


def test_a_node_with_two_parents_is_refused(tmp_path):
    nodes = [{"children": [2]}, {"children": [2]}, {}]
    path = tmp_path / "two_parents.gltf"
    path.write_text(json.dumps(dict(BASE_DOCUMENT, scenes=[{"nodes": [0, 1]}], nodes=nodes)))
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError" and "node 2 is reached twice" in message


@pytest.mark.parametrize("container", ["gltf", "glb"])
def test_an_image_buffer_view_past_its_buffer_is_refused_not_read(tmp_path, container):
    """Found by the fuzzer (a GLB mutant): tinygltf passes an image stored in a buffer view to
    the decoder as buffer.data + byteOffset without checking the view against the buffer, so a
    view at byteOffset 2^31 made stb_image read unmapped memory (a segfault)."""
    png = bytes.fromhex("89504e470d0a1a0a")  # never reached: the view is refused first
    data = png + b"\0" * (-len(png) % 4)
    document = dict(BASE_DOCUMENT, buffers=[{"byteLength": len(data)}],
                    bufferViews=[{"buffer": 0, "byteOffset": 2**31, "byteLength": 142}],
                    images=[{"bufferView": 0, "mimeType": "image/png"}])
    path = tmp_path / f"image_view.{container}"
    if container == "glb":
        json_chunk = glb_of(json.dumps(document))[12:]
        body = json_chunk + struct.pack("<I4s", len(data), b"BIN\0") + data
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    else:
        document["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                         + base64.b64encode(data).decode())
        path.write_text(json.dumps(document))
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert str(path) in message
    assert ("image 0: bufferView 0 (byteOffset 2147483648, byteLength 142) lies outside "
            "buffer 0, which has 8 bytes") in message


def test_a_glb_buffer_of_byte_length_0_is_refused_as_oserror(tmp_path):
    """Found by the fuzzer (a GLB mutant): a BIN buffer declaring byteLength 0 made tinygltf
    copy into data.at(0), and std::out_of_range reached Python as a bare IndexError."""
    document = dict(BASE_DOCUMENT, buffers=[{"byteLength": 0}])
    json_chunk = glb_of(json.dumps(document))[12:]
    data = b"\0" * 4
    body = json_chunk + struct.pack("<I4s", len(data), b"BIN\0") + data
    path = tmp_path / "empty_buffer.glb"
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError", (kind, message)
    assert str(path) in message and "the reader stopped at damaged data" in message
