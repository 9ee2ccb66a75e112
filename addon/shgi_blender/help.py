"""Help for the artist, without bpy: where the manual is and the text of a bug report.

The add-on's Preferences (preferences.py) show two buttons built on this module:

* **Documentation** opens the manual. `make dist` ships README.md and docs/*.md inside the
  add-on, under ``shgi_blender/docs/`` with the repository's layout (``docs/README.md``,
  ``docs/docs/addon.md``, ...) so the pages' links between each other still work; `make install`
  copies it the same way. An add-on run straight from a checkout has no bundled copy; the
  repository's README.md beside the add-on's source (``addon/shgi_blender`` -> ``README.md`` two
  folders up) serves instead. There is no project website to fall back on, so with neither the
  caller shows ``DOCS_MISSING``.
* **Report a Bug** writes a text file with what a maintainer needs to reproduce a problem
  (Blender and OS, SHGI's version, where ``shgi`` came from and whether it imported, the
  scene's SHGI settings, the errors and warnings of the last render) into a new temporary
  folder, for the artist to attach to the report.

pytest tests this module outside Blender (tests/python/test_addon_help.py).
"""

import datetime
import pathlib
import tempfile

ADDON_DIR = pathlib.Path(__file__).resolve().parent
# Where `make dist` puts the manual inside the add-on (addon/make_dist.py: DOCS_ARCHIVE_DIR).
BUNDLED_DOCS = "docs"
DOCS_MISSING = ("SHGI's manual is not bundled with this copy of the add-on: install the add-on "
                "zip or extension built by `make dist` (they carry it), or read README.md and "
                "docs/ in the SHGI source repository")
REPORT_NAME = "shgi_bug_report.txt"


def find_docs(addon_dir=ADDON_DIR):
    """The manual's first page as a pathlib.Path: the bundled docs/README.md of a packaged
    add-on, else the README.md of the repository the add-on's source sits in; None when there
    is neither."""
    addon_dir = pathlib.Path(addon_dir)
    candidates = [addon_dir / BUNDLED_DOCS / "README.md"]
    # A checkout: <repo>/addon/shgi_blender. A symlinked add-on folder resolves to it too.
    for folder in (addon_dir, addon_dir.resolve()):
        candidates.append(folder.parent.parent / "README.md")
    return next((path for path in candidates if path.is_file()), None)


def file_url(path):
    """A file:// URL of `path` for bpy.ops.wm.url_open."""
    return pathlib.Path(path).resolve().as_uri()


def property_lines(group, prefix):
    """``prefix.name = value`` lines for every property of an RNA property group (scene.shgi),
    nested groups (photon_lattice, probe_grid, bake) under their own prefix. Duck-typed on
    bl_rna.properties, so that tests can pass stand-ins."""
    lines = []
    for prop in group.bl_rna.properties:
        name = prop.identifier
        if name in ("rna_type", "name"):
            continue
        try:
            value = getattr(group, name)
        except AttributeError as error:
            lines.append(f"{prefix}.{name} = <unreadable: {error}>")
            continue
        if prop.type == "POINTER" and value is not None and hasattr(value, "bl_rna"):
            lines.extend(property_lines(value, f"{prefix}.{name}"))
        elif prop.type == "COLLECTION":
            lines.append(f"{prefix}.{name} = <{len(value)} items>")
        else:
            if hasattr(value, "__len__") and not isinstance(value, str):
                value = tuple(value)
            lines.append(f"{prefix}.{name} = {value!r}")
    return lines


def bug_report_text(*, blender_version, os_name, shgi_version, module_path, import_error,
                    settings_lines, last_render=None, now=None):
    """The bug report's text.

    `module_path`: the file ``shgi`` was imported from (None when it did not import);
    `import_error`: why it did not (None when it did); `settings_lines`: property_lines() of the
    scene's settings (empty without a scene); `last_render`: final_render.last_render()'s record
    (method, size, samples, cancelled, errors, warnings), empty or None before any render."""
    now = now or datetime.datetime.now(datetime.timezone.utc)
    lines = [
        "SHGI bug report",
        f"Written: {now.strftime('%Y-%m-%d %H:%M:%S %Z').strip()}",
        "",
        "Describe what you did, what you expected and what happened instead; attach the .blend",
        "file (File > External Data > Pack Resources first) if you can share it.",
        "",
        "== System ==",
        f"Blender: {blender_version}",
        f"OS: {os_name}",
        f"SHGI add-on: {shgi_version}",
        f"SHGI add-on folder: {ADDON_DIR}",
        "Native module shgi: " + (f"imported from {module_path}" if import_error is None
                                  else f"NOT imported: {import_error}"),
        "",
        "== Settings of the current scene ==",
    ]
    lines.extend(settings_lines or ["(no scene)"])
    lines += ["", "== Last render of this session =="]
    record = last_render or {}
    if not record:
        lines.append("(no render in this session)")
    else:
        size = record.get("size")
        lines.append(f"method {record.get('method')}, "
                     + (f"{size[0]}x{size[1]} px, " if size else "")
                     + f"{record.get('samples')} samples"
                     + (", cancelled" if record.get("cancelled") else ""))
        errors, warnings = record.get("errors") or [], record.get("warnings") or []
        lines += [f"error: {message}" for message in errors]
        lines += [f"warning: {message}" for message in warnings]
        if not errors and not warnings:
            lines.append("no errors or warnings")
    return "\n".join(lines) + "\n"


def write_bug_report(text, folder=None):
    """Writes `text` into `folder` (default: a new temporary folder) as shgi_bug_report.txt;
    returns the file's path."""
    folder = pathlib.Path(folder) if folder else pathlib.Path(
        tempfile.mkdtemp(prefix="shgi_bug_report_"))
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / REPORT_NAME
    path.write_text(text, encoding="utf-8")
    return path


def version_text(bl_info):
    """The version of bl_info's version tuple, e.g. "0.1.0"."""
    return ".".join(str(part) for part in bl_info.get("version", ()))
