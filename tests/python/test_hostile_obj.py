"""Hostile OBJ and MTL files: a number tinyobjloader cannot read ("nan", "inf", "1e39", an index
past 2^31) must not load as 0 or as another vertex without a word, but be refused with the file,
the line and the number. Loaded in a capped child (hostile_support.load_in_child)."""

import pytest

from hostile_support import load_in_child as load_file


def load_in_child(path):
    return load_file(path, "load_obj")

QUAD = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"


def write_obj(tmp_path, body, mtl=None):
    path = tmp_path / "scene.obj"
    head = "mtllib scene.mtl\nusemtl red\n" if mtl is not None else ""
    path.write_text(head + body)
    if mtl is not None:
        (tmp_path / "scene.mtl").write_text("newmtl red\n" + mtl)
    return path


@pytest.mark.parametrize("line, number", [
    ("v nan 5 5", "nan"), ("v inf 5 5", "inf"), ("v 1e39 0 0", "1e39"), ("vn 0 0 nan", "nan"),
    ("vt inf nan", "inf"), ("v 1 2", None)])
def test_bad_numbers_in_vertex_statements_are_refused(tmp_path, line, number):
    path = write_obj(tmp_path, QUAD + line + "\nf 1 2 3\n")
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert f"{path}:9:" in message, message  # the line after QUAD's eight
    assert (f"'{number}' is not a finite number" if number else "needs at least 3") in message


@pytest.mark.parametrize("face, part", [("f 1 2 18446744073709551616", "18446744073709551616"),
                                        ("f 1 2 0", "0"), ("f 1/x 2 3", "x"),
                                        ("f 1 2 -2147483649", "-2147483649")])
def test_face_indices_that_are_no_vertex_numbers_are_refused(tmp_path, face, part):
    path = write_obj(tmp_path, QUAD + face + "\n")
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert f"{path}:9: index '{part}'" in message


@pytest.mark.parametrize("statement, number", [("Kd nan 0 0", "nan"), ("Ke 1 inf 1", "inf"),
                                               ("Ns nan", "nan"), ("d 1e40", "1e40")])
def test_bad_numbers_in_materials_are_refused(tmp_path, statement, number):
    path = write_obj(tmp_path, QUAD + "f 1 2 3\n", mtl=statement + "\n")
    (kind, message), _ = load_in_child(path)
    assert kind == "OSError"
    assert f"scene.mtl:2:" in message and f"'{number}' is not a finite number" in message


def test_valid_numbers_of_every_form_still_load(tmp_path):
    body = ("v +1 0 0\nv 1e-50 1.5E+0 -0\nv .5 1. 2 0.1 0.2 0.3\nvt 0.5\nvn 0 0 1\n"
            "f 1/1/1 2//1 3\nf -1 -2 -3\n")
    path = write_obj(tmp_path, body, mtl="Kd 0.8 0.8 0.8\nNs 10\nd -halo 0.5\nKs spectral x.rfl\n")
    verdict, _ = load_in_child(path)
    assert verdict == ("loaded", "")
