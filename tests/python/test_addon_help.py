"""The add-on's help without Blender (addon/shgi_blender/help.py, bpy-free): where the
Documentation button finds the manual, the Report a Bug text, and that `make dist`'s packages
carry the manual (addon/make_dist.py run on a stand-in wheel, so no build is needed).

Blender's side: the Preferences draw both buttons and the operators run headless
(tests/blender/addon_register.py); here, both buttons run from the Preferences window of a real
Blender window under Xvfb (tests/blender/preferences_window.py).
"""

import datetime
import json
import pathlib
import stat
import sys
import zipfile
from types import SimpleNamespace

import pytest

from blender_support import ADDON_DIR, needs_window, run_in_window

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "addon"))

from shgi_blender import help as shgi_help  # noqa: E402
import make_dist  # noqa: E402  (addon/ is on sys.path)


def test_bundled_docs_come_first(tmp_path):
    addon = tmp_path / "repo" / "addon" / "shgi_blender"
    (addon / "docs" / "docs").mkdir(parents=True)
    (addon / "docs" / "README.md").write_text("bundled")
    (tmp_path / "repo" / "README.md").write_text("checkout")
    assert shgi_help.find_docs(addon) == addon / "docs" / "README.md"


def test_a_checkout_falls_back_to_the_repository_readme(tmp_path):
    addon = tmp_path / "repo" / "addon" / "shgi_blender"
    addon.mkdir(parents=True)
    (tmp_path / "repo" / "README.md").write_text("checkout")
    assert shgi_help.find_docs(addon) == tmp_path / "repo" / "README.md"
    assert shgi_help.file_url(tmp_path / "repo" / "README.md").startswith("file:///")


def test_no_docs_anywhere_gives_none(tmp_path):
    addon = tmp_path / "scripts" / "addons" / "shgi_blender"
    addon.mkdir(parents=True)
    assert shgi_help.find_docs(addon) is None
    assert "make dist" in shgi_help.DOCS_MISSING


def test_this_checkout_finds_its_readme():
    assert shgi_help.find_docs(REPO / "addon" / "shgi_blender") == REPO / "README.md"


def _props(values, pointers=None):
    """A stand-in for an RNA property group: bl_rna.properties and the values."""
    pointers = pointers or {}
    props = [SimpleNamespace(identifier="rna_type", type="POINTER")]
    props += [SimpleNamespace(identifier=name, type="POINTER" if name in pointers else
                              ("COLLECTION" if isinstance(value, list) else "INT"))
              for name, value in {**values, **pointers}.items()]
    return SimpleNamespace(bl_rna=SimpleNamespace(properties=props), **values, **pointers)


def test_settings_lines_walk_nested_groups():
    bake = _props({"samples": 256, "bake_side": "FRONT"})
    shgi = _props({"method": "PROBE_GRID", "samples": 64, "items": [1, 2]}, {"bake": bake})
    lines = shgi_help.property_lines(shgi, "scene.shgi")
    assert "scene.shgi.method = 'PROBE_GRID'" in lines
    assert "scene.shgi.samples = 64" in lines
    assert "scene.shgi.items = <2 items>" in lines
    assert "scene.shgi.bake.bake_side = 'FRONT'" in lines
    assert not any("rna_type" in line for line in lines)


def _report(**overrides):
    arguments = dict(blender_version="5.0.1", os_name="Linux-6.1-x86_64", shgi_version="0.1.0",
                     module_path="/x/shgi/__init__.py", import_error=None,
                     settings_lines=["scene.shgi.method = 'PATH_TRACE'"], last_render={},
                     now=datetime.datetime(2026, 11, 28, 6, 0, tzinfo=datetime.timezone.utc))
    arguments.update(overrides)
    return shgi_help.bug_report_text(**arguments)


def test_the_report_names_versions_module_settings_and_errors():
    text = _report(last_render={"method": "PHOTON_LATTICE", "size": (64, 48), "samples": 16,
                                "cancelled": True, "errors": ["SHGI: boom"],
                                "warnings": ["object 'x' has no material"]})
    for expected in ("Blender: 5.0.1", "OS: Linux-6.1-x86_64", "SHGI add-on: 0.1.0",
                     "imported from /x/shgi/__init__.py", "scene.shgi.method = 'PATH_TRACE'",
                     "method PHOTON_LATTICE, 64x48 px, 16 samples, cancelled",
                     "error: SHGI: boom", "warning: object 'x' has no material",
                     "2026-11-28 06:00:00"):
        assert expected in text, expected


def test_the_report_says_when_shgi_did_not_import_and_nothing_rendered():
    text = _report(module_path=None, import_error="ImportError: no module named 'shgi'",
                   settings_lines=[], last_render=None)
    assert "NOT imported: ImportError: no module named 'shgi'" in text
    assert "(no scene)" in text and "(no render in this session)" in text


def test_the_report_is_written_into_a_new_temporary_folder(tmp_path):
    path = shgi_help.write_bug_report("hello\n")
    try:
        assert path.name == shgi_help.REPORT_NAME and path.read_text() == "hello\n"
        assert path.parent.name.startswith("shgi_bug_report_")
    finally:
        path.unlink()
        path.parent.rmdir()
    assert shgi_help.write_bug_report("x", tmp_path / "a").read_text() == "x"
    assert shgi_help.version_text({"version": (0, 1, 0)}) == "0.1.0"


def test_make_dist_ships_the_manual_in_both_packages(tmp_path):
    version = make_dist.addon_version()
    wheel = tmp_path / f"shgi-{version}-cp311-cp311-manylinux_2_34_x86_64.whl"
    with zipfile.ZipFile(wheel, "w") as out:
        out.writestr("shgi/__init__.py", "")
    make_dist.main(["--wheel", str(wheel), "--out", str(tmp_path / "dist")])
    pages = ["README.md"] + sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md"))
    assert "docs/addon.md" in pages
    addon_zip = zipfile.ZipFile(tmp_path / "dist" / f"shgi_blender-{version}-addon.zip")
    extension = zipfile.ZipFile(next((tmp_path / "dist").glob("*-extension-*.zip")))
    for names, root in ((addon_zip.namelist(), "shgi_blender/"), (extension.namelist(), "")):
        for page in pages:
            assert f"{root}docs/{page}" in names, (root, page)
        assert not any("images/" in name for name in names), "docs/images shipped"
    assert addon_zip.read("shgi_blender/docs/README.md") == (REPO / "README.md").read_bytes()


@pytest.mark.parametrize("page", ["README.md", "docs/addon.md"])
def test_the_bundled_layout_keeps_the_pages_links(page):
    """README.md links docs/<page>.md and the pages link ../README.md: the bundle keeps both."""
    text = (REPO / page).read_text()
    assert ("docs/addon.md" in text) if page == "README.md" else ("../README.md" in text)


# Stands in for a web browser: Python's webbrowser (Blender's wm.url_open) runs $BROWSER with the
# URL; this appends the URL to the log named by SHGI_OPENED_URLS instead of opening anything.
URL_RECORDER = """#!/bin/sh
printf '%s\\n' "$1" >> "$SHGI_OPENED_URLS"
"""


@needs_window
def test_preferences_buttons_run_in_a_window(build_python_dir, tmp_path):
    """The Preferences window of a real Blender window draws the add-on's preferences without
    an error; from it, Documentation opens this checkout's README.md and Report a Bug writes
    its report and opens it: each operator finishes, and the system's URL handler is asked for
    exactly those two files."""
    recorder = tmp_path / "record_url"
    recorder.write_text(URL_RECORDER)
    recorder.chmod(recorder.stat().st_mode | stat.S_IXUSR)
    opened = tmp_path / "opened_urls.txt"
    scripts = tmp_path / "scripts"  # Blender's user scripts, the add-on installed in them
    (scripts / "addons").mkdir(parents=True)
    (scripts / "addons" / "shgi_blender").symlink_to(ADDON_DIR / "shgi_blender")
    out, folder = tmp_path / "preferences_window.json", tmp_path / "report"
    result = run_in_window("preferences_window.py", (800, 600), build_python_dir, ADDON_DIR, out,
                           folder, env={"BROWSER": str(recorder), "SHGI_OPENED_URLS": str(opened),
                                        "BLENDER_USER_SCRIPTS": str(scripts)})
    log = result.stdout[-4000:] + result.stderr[-2000:]
    assert result.returncode == 0 and "PREFERENCES_WINDOW_OK" in result.stdout, log
    assert "Traceback" not in result.stdout + result.stderr, log  # e.g. from draw()
    r = json.loads(out.read_text())
    assert r["preferences_section"] == "ADDONS" and r["preferences_draws"] > 0, r
    assert r["documentation"] == ["FINISHED"] and r["report_bug"] == ["FINISHED"], r
    assert r["manual_path"] == str(REPO / "README.md")
    assert r["report_first_line"].startswith("SHGI bug report"), r
    assert opened.read_text().splitlines() == [shgi_help.file_url(r["manual_path"]),
                                               shgi_help.file_url(r["report_path"])]
