"""Packages the add-on for artists (`make dist`), around a wheel of the native module `shgi`.

Usage: ``python addon/make_dist.py --wheel dist/shgi-<v>-cp311-cp311-<platform>.whl --out dist``

Writes two files into --out:

- ``shgi_blender-<v>-addon.zip`` for Blender 3.4 to 4.1 (Preferences > Add-ons > Install): the
  folder shgi_blender/ with the wheel's contents unpacked into shgi_blender/vendor/ (the
  package shgi/ and the shared libraries auditwheel put in shgi.libs/), which native.py puts
  first on sys.path. Blender's own numpy serves it.
- ``shgi_blender-<v>-extension-<platform>.zip`` for Blender 4.2+ (Get Extensions > Install from
  Disk): the add-on's files at the zip's root, blender_manifest.toml with the wheel listed in
  ``wheels`` and its platform in ``platforms``, and the wheel in wheels/. Blender installs the
  wheel into the extension's site-packages.

Both carry the manual: README.md and docs/*.md (not docs/images) under shgi_blender/docs/, in the
repository's layout (docs/README.md, docs/docs/addon.md, ...) so that the pages' links to each
other still work; Preferences > Add-ons > SHGI > Documentation opens it (help.py).

The wheel must be for CPython 3.11 (every Blender from 3.4 to 5.0 embeds 3.11) and carry its
libraries (auditwheel repair). The add-on's version (bl_info, blender_manifest.toml) must match
the wheel's.
"""

import argparse
import pathlib
import re
import sys
import tomllib
import zipfile

ADDON = pathlib.Path(__file__).resolve().parent / "shgi_blender"
REPO_ROOT = ADDON.parent.parent
# The manual's folder inside the add-on (shgi_blender/help.py: BUNDLED_DOCS).
DOCS_ARCHIVE_DIR = "docs"
PYTHON_TAG = "cp311"
# wheel platform tag -> Blender extension platform
PLATFORMS = {"x86_64": "linux-x64", "aarch64": "linux-arm64"}


def addon_files():
    """The add-on's files as (path, archive name under shgi_blender/), without caches."""
    return [(path, path.relative_to(ADDON).as_posix()) for path in sorted(ADDON.rglob("*"))
            if path.is_file() and "__pycache__" not in path.parts
            and path.suffix not in (".pyc", ".pyo")]


def docs_files():
    """The manual as (path, archive name under shgi_blender/): README.md and docs/*.md."""
    pages = [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]
    if not pages[0].is_file() or len(pages) == 1:
        raise SystemExit(f"the manual (README.md, docs/*.md) is missing from {REPO_ROOT}")
    return [(path, f"{DOCS_ARCHIVE_DIR}/{path.relative_to(REPO_ROOT).as_posix()}")
            for path in pages]


def addon_version():
    """The version both bl_info and blender_manifest.toml state; raises if they disagree."""
    manifest = tomllib.loads((ADDON / "blender_manifest.toml").read_text())
    match = re.search(r'"version":\s*\((\d+),\s*(\d+),\s*(\d+)\)',
                      (ADDON / "__init__.py").read_text())
    bl_info = ".".join(match.groups()) if match else None
    if bl_info != manifest["version"]:
        raise SystemExit(f"bl_info version {bl_info} != blender_manifest.toml "
                         f"{manifest['version']}: make them equal")
    return manifest["version"]


def wheel_tags(wheel):
    """(version, python tag, platform tag) from a wheel's file name."""
    parts = wheel.name[:-len(".whl")].split("-")
    if len(parts) != 5 or parts[0] != "shgi":
        raise SystemExit(f"{wheel.name} is not a wheel of shgi (shgi-<v>-<py>-<abi>-<plat>.whl)")
    return parts[1], parts[2], parts[4]


def extension_manifest(wheel_name, platform):
    """blender_manifest.toml with the wheel and its platform, for the extension zip."""
    text = (ADDON / "blender_manifest.toml").read_text()
    if re.search(r"^\s*(\[|wheels\s*=|platforms\s*=)", text, re.MULTILINE):
        raise SystemExit("blender_manifest.toml already has tables, wheels or platforms: "
                         "extend make_dist.py to merge them")
    return text.rstrip("\n") + (
        "\n\n# Added by `make dist`: the native module as a wheel for this platform.\n"
        f'platforms = ["{platform}"]\n'
        f'wheels = ["./wheels/{wheel_name}"]\n'
        "\n[permissions]\n"
        'files = "Write baked lightmaps and exported volumes, read scenes"\n')


def write_addon_zip(path, wheel):
    with zipfile.ZipFile(wheel) as source, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as out:
        for file, name in addon_files():
            if name != "blender_manifest.toml":  # a 4.2+ extension's file; 3.x ignores it
                out.write(file, f"shgi_blender/{name}")
        for file, name in docs_files():
            out.write(file, f"shgi_blender/{name}")
        for info in source.infolist():
            if info.is_dir() or ".dist-info/" in info.filename:
                continue
            # Keep the executable bits of the shared libraries.
            entry = zipfile.ZipInfo(f"shgi_blender/vendor/{info.filename}", info.date_time)
            entry.external_attr = info.external_attr
            entry.compress_type = zipfile.ZIP_DEFLATED
            out.writestr(entry, source.read(info))


def write_extension_zip(path, wheel, platform):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as out:
        for file, name in addon_files():
            if name == "blender_manifest.toml":
                out.writestr(name, extension_manifest(wheel.name, platform))
            else:
                out.write(file, name)
        for file, name in docs_files():
            out.write(file, name)
        out.write(wheel, f"wheels/{wheel.name}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--wheel", type=pathlib.Path, required=True,
                        help="the repaired shgi wheel (auditwheel) to ship")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="output folder")
    args = parser.parse_args(argv)
    version, python, platform_tag = wheel_tags(args.wheel)
    if python != PYTHON_TAG:
        raise SystemExit(f"{args.wheel.name} is for {python}; Blender embeds CPython 3.11 "
                         f"({PYTHON_TAG}): build the wheel with a Python 3.11")
    if version != addon_version():
        raise SystemExit(f"the wheel is shgi {version} but the add-on is {addon_version()}")
    arch = next((a for a in PLATFORMS if platform_tag.endswith(a)), None)
    if arch is None or not platform_tag.startswith(("manylinux", "linux")):
        raise SystemExit(f"no Blender extension platform for the wheel platform {platform_tag}")
    args.out.mkdir(parents=True, exist_ok=True)
    addon_zip = args.out / f"shgi_blender-{version}-addon.zip"
    extension_zip = args.out / f"shgi_blender-{version}-extension-{PLATFORMS[arch]}.zip"
    write_addon_zip(addon_zip, args.wheel)
    write_extension_zip(extension_zip, args.wheel, PLATFORMS[arch])
    for path in (addon_zip, extension_zip):
        print(f"{path} ({path.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    sys.exit(main())
