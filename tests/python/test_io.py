"""Tests of the image bindings: write_exr / read_exr / read_exr_info, write_png, the sRGB curve.

EXR round trips must be bit-exact for float channels; PNG files are decoded here with zlib and
struct alone (no PIL) and compared with the 8-bit sRGB levels the curve predicts.
"""

import math
import os
import pathlib
import struct
import zlib

import numpy as np
import pytest

import shgi

# 1.055 * 0.5 ** (1 / 2.4) - 0.055: linear 0.5 in sRGB.
SRGB_OF_HALF = 0.7353569830524495


def random_finite_floats(shape, seed):
    """float32 values from random bit patterns: every sign, exponent (denormals too), mantissa."""
    rng = np.random.default_rng(seed)
    bits = rng.integers(0, 2**32, size=shape, dtype=np.uint64).astype(np.uint32)
    values = bits.view(np.float32).copy()
    values[~np.isfinite(values)] = 1.0
    flat = values.reshape(-1)
    flat[:6] = [0.0, -0.0, np.finfo(np.float32).smallest_subnormal, np.finfo(np.float32).max,
                -np.finfo(np.float32).max, 1e-40]
    return values


def assert_bit_exact(actual, expected):
    assert actual.dtype == np.float32 and actual.shape == expected.shape
    np.testing.assert_array_equal(actual.view(np.uint32), expected.view(np.uint32))


# --- EXR ----------------------------------------------------------------------------------------

def test_exr_float_round_trip_is_bit_exact(tmp_path):
    combined = random_finite_floats((23, 37, 4), seed=1)
    depth = random_finite_floats((23, 37), seed=2)
    path = tmp_path / "passes.exr"
    shgi.write_exr(path, {"Combined": combined, "Depth": depth})
    layers = shgi.read_exr(path)
    assert list(layers) == ["Combined", "Depth"]
    assert_bit_exact(layers["Combined"], combined)
    assert_bit_exact(layers["Depth"], depth[:, :, np.newaxis])  # always (H, W, C)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["passes.exr"]  # no temporary file


@pytest.mark.parametrize("compression", ["none", "rle", "zips", "zip", "piz"])
def test_every_compression_is_lossless(tmp_path, compression):
    pixels = random_finite_floats((9, 17, 3), seed=3)
    path = tmp_path / f"{compression}.exr"
    shgi.write_exr(str(path), {"Emit": pixels}, compression=compression)
    assert shgi.read_exr_info(path)["compression"] == compression
    assert_bit_exact(shgi.read_exr(path)["Emit"], pixels)


def test_exr_half_channels(tmp_path):
    rng = np.random.default_rng(4)
    values = (rng.standard_normal((8, 6, 3)) * 100).astype(np.float32)
    path = tmp_path / "half.exr"
    # float16 input is stored as half by default; float32 input when asked.
    shgi.write_exr(path, {"DiffInd": values.astype(np.float16)})
    info = shgi.read_exr_info(path)
    assert info["channels"] == [("DiffInd.R", "half"), ("DiffInd.G", "half"), ("DiffInd.B", "half")]
    expected = values.astype(np.float16).astype(np.float32)  # half is exact in float32
    np.testing.assert_array_equal(shgi.read_exr(path)["DiffInd"], expected)

    shgi.write_exr(path, {"DiffInd": values}, pixel_type="half")
    # Both numpy and OpenEXR round float -> half to nearest even.
    np.testing.assert_array_equal(shgi.read_exr(path)["DiffInd"], expected)


def test_exr_layer_names_and_order_are_preserved(tmp_path):
    h, w = 4, 5
    layers = {
        "ViewLayer.Normal": np.full((h, w, 3), 0.5, np.float32),
        "Combined": np.ones((h, w, 4), np.float32),
        "Depth": np.full((h, w), 3.0, np.float32),
        "DiffInd": np.full((h, w, 3), 2.0, np.float32),
    }
    path = tmp_path / "layers.exr"
    shgi.write_exr(path, layers, channel_names={"ViewLayer.Normal": "XYZ"})
    info = shgi.read_exr_info(path)
    assert (info["width"], info["height"]) == (w, h)
    assert [name for name, _ in info["channels"]] == [
        "ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z",
        "Combined.R", "Combined.G", "Combined.B", "Combined.A",
        "Depth.Z", "DiffInd.R", "DiffInd.G", "DiffInd.B"]
    read = shgi.read_exr(path)
    assert list(read) == list(layers)
    for name, pixels in layers.items():
        np.testing.assert_array_equal(read[name], pixels.reshape(h, w, -1))


def test_exr_rows_are_top_row_first(tmp_path):
    gradient = np.arange(6, dtype=np.float32).reshape(2, 3)  # row 0 = top
    path = tmp_path / "rows.exr"
    shgi.write_exr(path, {"Gradient": gradient})
    np.testing.assert_array_equal(shgi.read_exr(path)["Gradient"][:, :, 0], gradient)


def test_exr_bare_and_many_channel_layers(tmp_path):
    rgb = np.random.default_rng(5).random((3, 2, 3), dtype=np.float32)
    coefficients = np.random.default_rng(6).random((3, 2, 25), dtype=np.float32)
    names = [f"c{i:02d}" for i in range(25)]
    path = tmp_path / "bare.exr"
    shgi.write_exr(path, {"": rgb, "Lattice": coefficients}, channel_names={"Lattice": names})
    channels = [name for name, _ in shgi.read_exr_info(path)["channels"]]
    assert channels[:3] == ["R", "G", "B"]
    assert channels[3:] == [f"Lattice.{n}" for n in names]
    read = shgi.read_exr(path)
    np.testing.assert_array_equal(read[""], rgb)
    np.testing.assert_array_equal(read["Lattice"], coefficients)


# A multi-part file as Blender 5.0 and Houdini write them, made with OpenEXR's
# Imf::MultiPartOutputFile (3.1.5, no compression, 3 x 2 pixels): part "ViewLayer.Combined"
# (float "ViewLayer.Combined.R", ".G", ".B", ".A": the channel carries the part name), part
# "ViewLayer.Depth" (float "Z") and tiled part "ViewLayer.DiffInd" (half "R", "G", "B": the part
# name gives the layer). Channel k, in that order, holds 100 k + 10 y + x + 0.5 at pixel (x, y).
# The same bytes as kThreePartExr in tests/cpp/io/exr_image_test.cpp.
THREE_PART_EXR = (
    b"v/1\x01\x02\x10\0\0channels\0chlist\0\x95\0\0\0ViewLayer.Combined.A\0\x02\0\0\0\0\0\0\0\x01\0"
    b"\0\0\x01\0\0\0ViewLayer.Combined.B\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0ViewLayer.Combined."
    b"G\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0ViewLayer.Combined.R\0\x02\0\0\0\0\0\0\0\x01\0\0\0"
    b"\x01\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWi"
    b"ndow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0"
    b"\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x12\0\0\0V"
    b"iewLayer.CombinedpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80?screenWindowCenter\0v2f\0\x08\0"
    b"\0\0\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0\x80?type\0string\0\x0d\0\0\0scan"
    b"lineimage\0channels\0chlist\0\x13\0\0\0Z\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\0chunkCount"
    b"\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWindow\0box2i\0\x10\0\0"
    b"\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0"
    b"\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x0f\0\0\0ViewLayer.DepthpixelA"
    b"spectRatio\0float\0\x04\0\0\0\0\0\x80?screenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0scre"
    b"enWindowWidth\0float\0\x04\0\0\0\0\0\x80?type\0string\0\x0d\0\0\0scanlineimage\0channels\0chl"
    b"ist\x007\0\0\0B\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0G\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0"
    b"\0\0R\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compressi"
    b"on\0compression\0\x01\0\0\0\0dataWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0"
    b"\0displayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0"
    b"\x01\0\0\0\0name\0string\0\x11\0\0\0ViewLayer.DiffIndpixelAspectRatio\0float\0\x04\0\0\0\0\0"
    b"\x80?screenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0"
    b"\0\0\x80?tiles\0tiledesc\0\x09\0\0\0\x02\0\0\0\x02\0\0\0\0type\0string\0\x0a\0\0\0tiledimage"
    b"\0\0\x1d\x05\0\0\0\0\0\0Y\x05\0\0\0\0\0\0\x95\x05\0\0\0\0\0\0\xad\x05\0\0\0\0\0\0\xc5\x05\0\0"
    b"\0\0\0\0\xf5\x05\0\0\0\0\0\0\0\0\0\0\0\0\0\x000\0\0\0\0@\x96C\0\xc0\x96C\0@\x97C\0\x80HC\0"
    b"\x80IC\0\x80JC\0\0\xc9B\0\0\xcbB\0\0\xcdB\0\0\0?\0\0\xc0?\0\0 @\0\0\0\0\x01\0\0\x000\0\0\0\0@"
    b"\x9bC\0\xc0\x9bC\0@\x9cC\0\x80RC\0\x80SC\0\x80TC\0\0\xddB\0\0\xdfB\0\0\xe1B\0\0(A\0\08A\0\0HA"
    b"\x01\0\0\0\0\0\0\0\x0c\0\0\0\0@\xc8C\0\xc0\xc8C\0@\xc9C\x01\0\0\0\x01\0\0\0\x0c\0\0\0\0@\xcdC"
    b"\0\xc0\xcdC\0@\xceC\x02\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x18\0\0\0ya{a\xb1`\xb3`\xd2_"
    b"\xd6_\x8da\x8fa\xc5`\xc7`\xfa_\xfe_\x02\0\0\0\x01\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x0c\0\0\0}a"
    b"\xb5`\xda_\x91a\xc9`\x01`"
)


def test_read_exr_reads_every_part_of_a_multi_part_file(tmp_path):
    path = tmp_path / "three_parts.exr"
    path.write_bytes(THREE_PART_EXR)
    y, x = np.mgrid[0:2, 0:3].astype(np.float32)
    expected = {name: np.stack([100 * k + 10 * y + x + 0.5 for k in ks], axis=-1)
                for name, ks in [("ViewLayer.Combined", range(0, 4)),
                                 ("ViewLayer.Depth", range(4, 5)),
                                 ("ViewLayer.DiffInd", range(5, 8))]}
    layers = shgi.read_exr(path)
    assert list(layers) == list(expected)  # as in the single-part file with these passes
    for name, pixels in expected.items():
        assert_bit_exact(layers[name], pixels)
    info = shgi.read_exr_info(path)
    assert (info["width"], info["height"]) == (3, 2)
    assert info["channels"] == (
        [(f"ViewLayer.Combined.{c}", "float") for c in "RGBA"] + [("ViewLayer.Depth.Z", "float")]
        + [(f"ViewLayer.DiffInd.{c}", "half") for c in "RGB"])


def test_write_exr_survives_layers_that_edit_the_dict_while_converted(tmp_path):
    """The layers dict was read through borrowed references: a layer whose __array__ removed
    entries (itself among them) or added some made write_exr read freed memory (a segfault)."""

    class Popping:
        def __init__(self, layers, key):
            self.layers, self.key = layers, key

        def __array__(self, dtype=None, copy=None):
            self.layers.pop(self.key, None)  # may drop the last other reference to self
            return np.full((4, 4), 0.5, np.float32)

    class Growing:
        def __init__(self, layers):
            self.layers = layers

        def __array__(self, dtype=None, copy=None):
            for i in range(50):
                self.layers[f"extra{i}"] = np.zeros((4, 4), np.float32)
            return np.full((4, 4), 0.25, np.float32)

    popping = {}
    for key in "abcde":
        popping[key] = Popping(popping, key)
    shgi.write_exr(tmp_path / "popping.exr", popping)
    assert sorted(shgi.read_exr(tmp_path / "popping.exr")) == list("abcde")
    growing = {}
    growing["a"] = Growing(growing)
    shgi.write_exr(tmp_path / "growing.exr", growing)  # the items as they were at the call
    written = shgi.read_exr(tmp_path / "growing.exr")
    assert list(written) == ["a"] and np.all(written["a"] == 0.25)


def test_read_exr_enforces_max_pixels(tmp_path):
    path = tmp_path / "big.exr"
    shgi.write_exr(path, {"Combined": np.zeros((8, 8, 4), np.float32)})
    with pytest.raises(OSError, match="max_pixels = 63"):
        shgi.read_exr(path, max_pixels=63)
    assert shgi.read_exr(path, max_pixels=64)["Combined"].shape == (8, 8, 4)
    # "no limit": 16 * max_pixels once overflowed to a negative budget that refused every file
    assert shgi.read_exr(path, max_pixels=2**63 - 1)["Combined"].shape == (8, 8, 4)


def test_missing_and_corrupt_exr_raise_os_error_naming_the_file(tmp_path):
    missing = tmp_path / "missing.exr"
    with pytest.raises(OSError, match="missing.exr"):
        shgi.read_exr(missing)
    with pytest.raises(OSError, match="missing.exr"):
        shgi.read_exr_info(missing)
    corrupt = tmp_path / "corrupt.exr"
    corrupt.write_bytes(b"\x76\x2f\x31\x01" + b"\x00" * 40)  # EXR magic, then nonsense
    with pytest.raises(OSError, match="corrupt.exr"):
        shgi.read_exr(corrupt)


def test_folders_special_files_and_nul_bytes_are_refused_by_name(tmp_path):
    """A folder once made load_obj raise MemoryError; a FIFO would block a reader, and a write
    would rename its file over it (as over /dev/null)."""
    for read in (shgi.read_exr, shgi.read_exr_info, shgi.load_obj, shgi.load_gltf):
        with pytest.raises(OSError, match="is a folder; pass a file"):
            read(tmp_path)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for read in (shgi.read_exr, shgi.load_obj, shgi.load_gltf):
        with pytest.raises(OSError, match="not a regular file"):
            read(fifo)
    pixels = np.zeros((2, 2, 3), np.float32)
    with pytest.raises(OSError, match="not a regular file .* would replace"):
        shgi.write_exr(fifo, {"Combined": pixels})
    with pytest.raises(OSError, match="not a regular file .* would replace"):
        shgi.write_png(fifo, pixels)
    assert fifo.is_fifo()


def test_write_exr_into_a_missing_folder_raises_os_error(tmp_path):
    path = tmp_path / "no_such_folder" / "out.exr"
    with pytest.raises(OSError, match="does not exist"):
        shgi.write_exr(path, {"Combined": np.zeros((2, 2, 4), np.float32)})


def test_writing_into_a_folder_that_is_a_file_names_the_file(tmp_path):
    """An output folder that is a file was reported as a folder that "does not exist"."""
    (tmp_path / "out").write_text("a file")
    for write, name in ((lambda p: shgi.write_exr(p, {"Combined": np.zeros((2, 2, 4), np.float32)}),
                         "a.exr"),
                        (lambda p: shgi.write_png(p, np.zeros((2, 2, 3), np.float32)), "a.png")):
        with pytest.raises(OSError) as caught:
            write(tmp_path / "out" / name)
        assert f'"{tmp_path / "out"}" is a file, not a folder' in str(caught.value)
    assert (tmp_path / "out").read_text() == "a file"


GOOD = np.zeros((2, 3, 4), np.float32)


@pytest.mark.parametrize("kwargs, argument", [
    (dict(layers={"Combined": GOOD.astype(np.int32)}), r"layers\['Combined'\]"),
    (dict(layers={"Combined": np.zeros(5, np.float32)}), r"layers\['Combined'\]"),
    (dict(layers={"Combined": None}), r"layers\['Combined'\]"),
    (dict(layers={"Combined": np.zeros((0, 3, 4), np.float32)}), r"layers\['Combined'\]"),
    (dict(layers={"Combined": GOOD, "Depth": np.zeros((3, 2), np.float32)}), r"layers\['Depth'\]"),
    (dict(layers={"Lattice": np.zeros((2, 3, 9), np.float32)}), r"channel_names\['Lattice'\]"),
    (dict(layers={}), "layers"),
    (dict(layers={1: GOOD}), "layers"),
    (dict(layers={"Combined": GOOD}, channel_names={"Combined": "RGB"}),
     r"channel_names\['Combined'\]"),
    (dict(layers={"Combined": GOOD}, channel_names={"Emit": "RGB"}), "channel_names"),
    (dict(layers={"Combined": GOOD}, channel_names={"Combined": "RRGB"}), "Combined.R"),
    (dict(layers={"Combined": GOOD}, pixel_type="double"), "pixel_type"),
    (dict(layers={"Combined": GOOD}, compression="dwaa"), "compression"),
])
def test_write_exr_bad_input_raises_value_error_naming_the_argument(tmp_path, kwargs, argument):
    with pytest.raises(ValueError, match=argument):
        shgi.write_exr(tmp_path / "bad.exr", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_read_exr_rejects_a_non_positive_budget(tmp_path):
    with pytest.raises(ValueError, match="max_pixels"):
        shgi.read_exr(tmp_path / "any.exr", max_pixels=0)


# --- PNG ----------------------------------------------------------------------------------------

def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def decode_png(path):
    """Minimal decoder for 8-bit RGB/RGBA non-interlaced PNGs: (pixels (H, W, C) uint8, chunks)."""
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    chunks, offset, idat = {}, 8, b""
    while offset < len(data):
        length, kind = struct.unpack(">I4s", data[offset:offset + 8])
        body = data[offset + 8:offset + 8 + length]
        chunks[kind.decode()] = body
        idat += body if kind == b"IDAT" else b""
        offset += 12 + length
    width, height, depth, colour_type, _, _, interlace = struct.unpack(">IIBBBBB", chunks["IHDR"])
    assert depth == 8 and interlace == 0 and colour_type in (2, 6)
    channels = 3 if colour_type == 2 else 4
    stride = width * channels
    raw = zlib.decompress(idat)
    rows, previous = [], bytearray(stride)
    for y in range(height):
        start = y * (stride + 1)
        kind, line = raw[start], bytearray(raw[start + 1:start + 1 + stride])
        for i in range(stride):
            left = line[i - channels] if i >= channels else 0
            up = previous[i]
            up_left = previous[i - channels] if i >= channels else 0
            predictor = [0, left, up, (left + up) // 2, paeth(left, up, up_left)][kind]
            line[i] = (line[i] + predictor) & 0xFF
        rows.append(bytes(line))
        previous = line
    pixels = np.frombuffer(b"".join(rows), np.uint8).reshape(height, width, channels)
    return pixels, chunks


def test_write_png_encodes_srgb_levels(tmp_path):
    # Top row: black, white, linear 0.5; bottom row: 0.18 grey, over-white, negative + threshold.
    pixels = np.array([[[0, 0, 0], [1, 1, 1], [0.5, 0.5, 0.5]],
                       [[0.18, 0.5, 1], [4, 2, 1], [-1, 0.0031308, 0.5]]], np.float32)
    path = tmp_path / "rgb.png"
    shgi.write_png(path, pixels)
    decoded, chunks = decode_png(path)
    expected = [[[0, 0, 0], [255, 255, 255], [188, 188, 188]],
                [[118, 188, 255], [255, 255, 255], [0, 10, 188]]]
    np.testing.assert_array_equal(decoded, np.array(expected, np.uint8))
    assert "sRGB" in chunks
    assert [p.name for p in tmp_path.iterdir()] == ["rgb.png"]


def test_write_png_exposure_and_premultiplied_alpha(tmp_path):
    # Premultiplied 0.125 at alpha 0.5 is straight 0.25; +1 stop makes it 0.5 -> level 188.
    pixels = np.array([[[0.125, 0.125, 0.125, 0.5], [0.3, 0.2, 0.1, 0.0]]], np.float64)
    path = tmp_path / "rgba.png"
    shgi.write_png(path, pixels, exposure=1.0)
    decoded, _ = decode_png(path)
    np.testing.assert_array_equal(decoded, [[[188, 188, 188, 128], [0, 0, 0, 0]]])

    shgi.write_png(path, np.array([[[1.0, 1.0, 1.0, 0.5]]]), exposure=-1.0, premultiplied=False)
    decoded, _ = decode_png(path)
    np.testing.assert_array_equal(decoded, [[[188, 188, 188, 128]]])


@pytest.mark.parametrize("kwargs, argument", [
    (dict(pixels=np.zeros((2, 2, 2), np.float32)), "pixels"),
    (dict(pixels=np.zeros((2, 2), np.float32)), "pixels"),
    (dict(pixels=np.zeros((2, 2, 3), np.uint8)), "pixels"),
    (dict(pixels=np.zeros((2, 2, 3), np.float32), exposure=math.inf), "exposure"),
])
def test_write_png_bad_input_raises_value_error_naming_the_argument(tmp_path, kwargs, argument):
    with pytest.raises(ValueError, match=argument):
        shgi.write_png(tmp_path / "bad.png", **kwargs)


def test_write_png_into_a_missing_folder_raises_os_error(tmp_path):
    path = tmp_path / "missing" / "out.png"
    with pytest.raises(OSError, match="out.png"):
        shgi.write_png(path, np.zeros((1, 1, 3), np.float32))


def test_srgb_curve():
    assert shgi.srgb_from_linear(0.0) == 0.0
    assert shgi.srgb_from_linear(1.0) == 1.0
    assert shgi.srgb_from_linear(0.5) == pytest.approx(SRGB_OF_HALF, abs=1e-7)
    assert shgi.srgb_from_linear(0.0031308) == pytest.approx(12.92 * 0.0031308, abs=1e-7)
    assert shgi.srgb_from_linear(-1.0) == 0.0 and shgi.srgb_from_linear(2.0) == 1.0
    linear = np.linspace(0.0, 1.0, 101, dtype=np.float32)
    encoded = shgi.srgb_from_linear(linear)
    assert encoded.dtype == np.float32 and encoded.shape == linear.shape
    np.testing.assert_allclose(shgi.linear_from_srgb(encoded), linear, atol=1e-6)


def test_file_functions_take_str_bytes_and_path_like_and_name_a_nul_byte(tmp_path):
    """Found by fuzzing: read_exr, write_exr, write_png and the scene loaders made a path holding
    a NUL byte an "incompatible function arguments" TypeError, and the probe files refused
    pathlib.Path. Every file argument now takes what open() takes."""
    layers = {"a": np.ones((2, 3), np.float32)}
    for path in (str(tmp_path / "s.exr"), os.fsencode(tmp_path / "b.exr"), tmp_path / "p.exr"):
        shgi.write_exr(path, layers)
        assert shgi.read_exr(path)["a"].shape == (2, 3, 1)
        assert shgi.read_exr_info(path)["width"] == 3
    nul = str(tmp_path / "x.exr") + "\0.other"
    calls = {
        "read_exr": lambda p: shgi.read_exr(p),
        "read_exr_info": lambda p: shgi.read_exr_info(p),
        "write_exr": lambda p: shgi.write_exr(p, layers),
        "write_png": lambda p: shgi.write_png(p, np.zeros((1, 1, 3), np.float32)),
        "load_obj": lambda p: shgi.load_obj(p),
        "load_gltf": lambda p: shgi.load_gltf(p),
        "ProbeField.load": lambda p: shgi.ProbeField.load(p),
        "ProbeField.import_exr": lambda p: shgi.ProbeField.import_exr(p),
    }
    position = f"position {len(str(tmp_path / 'x.exr'))}"
    for name, call in calls.items():
        for path in (nul, os.fsencode(nul)):
            with pytest.raises(ValueError, match=f"NUL byte at {position}"):
                call(path)
        with pytest.raises(TypeError):  # not a path at all
            call(5)


def test_non_utf8_names_and_paths_give_os_errors_not_unicode_errors(tmp_path):
    """Found by fuzzing: an EXR channel name that is not UTF-8 (another writer's Latin-1) raised a
    bare UnicodeDecodeError from read_exr, as did any native error quoting such a path."""
    path = tmp_path / "latin1.exr"
    shgi.write_exr(path, {"Qz": np.ones((2, 2, 3), np.float32)})
    data = path.read_bytes()
    assert data.count(b"Qz.") == 6  # three channels, listed in the channel list and SHGI's order
    path.write_bytes(data.replace(b"Qz.", b"Q\xe9."))
    for read in (shgi.read_exr, shgi.read_exr_info):
        name = r'(layer|channel) name "Q\\xe9(\.[RGB])?" is not UTF-8'
        with pytest.raises(OSError, match=name):
            read(path)
    missing = os.fsencode(tmp_path) + b"/caf\xe9.exr"
    with pytest.raises(OSError, match=r"caf\\xe9\.exr"):
        shgi.read_exr(missing)
