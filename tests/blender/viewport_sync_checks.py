"""The viewport's scene sync in background Blender: which edits read geometry again.

Without a window there is no viewport engine, so a ``depsgraph_update_post`` handler calls
ViewportSync.sync(depsgraph) with the handler's depsgraph, as ``view_update`` calls it with the
viewport's: the same updates (``depsgraph.updates``), the same code. On the project's Cornell
box, one edit at a time, the script records the SyncReport (geometries read with to_mesh,
materials converted, how the snapshot changed) and checks:
* moving an object or a light, a light's power, a material's or the world's colour, a
  selection: no geometry read;
* editing a mesh, adding a modifier, another material in a slot (Blender flags the mesh's
  geometry): that one geometry read;
* after all the edits, the incremental snapshot renders the image a full export renders.
The pytest side (tests/python/test_blender_viewport.py) asserts the counts; this script checks
the equivalence and the panels, and prints VIEWPORT_SYNC_OK.

Runs as ``blender -b --factory-startup --python-exit-code 1 --python <this> -- <build python
dir> <addon dir> <results json>``.
"""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import results_path  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from recording_layout import draw_panel  # noqa: E402
from shgi_blender.engine.viewport_sync import ViewportSync  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

# A small direct-light path trace compares the incremental and the full export (same seed).
CHECK_SIZE = 24
CHECK_SAMPLES = 2


class SyncRecorder:
    """Calls ViewportSync.sync from depsgraph_update_post and keeps the last report."""

    def __init__(self):
        self.sync = ViewportSync()
        self.report = None

    def __call__(self, _scene, depsgraph):
        self.report = self.sync.sync(depsgraph)


def edit(recorder, results, name, change):
    """Applies change(), lets the depsgraph update (which runs the handler), records."""
    recorder.report = None
    change()
    bpy.context.view_layer.update()
    report = recorder.report
    if report is None:
        raise AssertionError(f"{name}: the depsgraph sent no update")
    results[name] = {"meshes_read": report.meshes_read, "change": report.change,
                     "materials_converted": report.materials_converted,
                     "seconds": report.seconds}
    print(f"{name:18s} {results[name]}")


def set_base_color(material, color):
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1)


def move_vertex(mesh):
    mesh.vertices[0].co.z += 0.05
    mesh.update()


def render(scene):
    camera = scene.camera
    camera.resolution_x = camera.resolution_y = CHECK_SIZE
    scene.set_camera(camera)
    scene.commit()
    return shgi.render_path_traced(
        scene, shgi.PathTracerSettings(samples=CHECK_SAMPLES, max_bounces=1))["Combined"]


def check_incremental_equals_full(recorder, bpy_scene):
    """The edited scene's incremental snapshot renders as a fresh full export does."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    incremental, warnings = recorder.sync.snapshot.build()
    if warnings:
        raise AssertionError(f"the snapshot's build warned: {warnings}")
    incremental.set_camera(export_scene(depsgraph, bpy_scene).scene.camera)
    full = export_scene(depsgraph, bpy_scene).scene
    a, b = render(incremental), render(full)
    if not np.array_equal(a, b):
        raise AssertionError(f"incremental and full exports differ: max |diff| "
                             f"{np.abs(a - b).max()}")


def check_panels():
    for panel in ("SHGI_RENDER_PT_method", "SHGI_RENDER_PT_photon_lattice"):
        draw_panel(panel)


def main():
    results = {}
    scene = common.new_scene("cornell_box", 0.25)
    scene.render.engine = "SHGI"
    scene.shgi.method = "PHOTON_LATTICE"
    recorder = SyncRecorder()
    first = recorder.sync.sync(bpy.context.evaluated_depsgraph_get())
    results["first sync"] = {"meshes_read": first.meshes_read, "change": first.change}
    bpy.app.handlers.depsgraph_update_post.append(recorder)
    objects, materials = bpy.data.objects, bpy.data.materials
    edit(recorder, results, "move object",
         lambda: setattr(objects["tall_block"], "location", (0.1, 0.0, 0.0)))
    edit(recorder, results, "move light",
         lambda: setattr(objects["ceiling_light"].location, "x", 0.3))
    edit(recorder, results, "light power",
         lambda: setattr(objects["ceiling_light"].data, "energy", 80.0))
    edit(recorder, results, "material colour",
         lambda: set_base_color(materials["white"], (0.6, 0.6, 0.7)))
    edit(recorder, results, "world colour",
         lambda: setattr(scene.world.node_tree.nodes["Background"].inputs["Strength"],
                         "default_value", 0.2))
    edit(recorder, results, "assign material",
         lambda: setattr(objects["short_block"].material_slots[0], "material", materials["red"]))
    edit(recorder, results, "select", lambda: objects["floor"].select_set(True))
    edit(recorder, results, "edit mesh", lambda: move_vertex(objects["short_block"].data))
    edit(recorder, results, "add modifier",
         lambda: objects["tall_block"].modifiers.new("bevel", "BEVEL"))
    bpy.app.handlers.depsgraph_update_post.remove(recorder)
    check_incremental_equals_full(recorder, scene)
    check_panels()
    with open(results_path("shgi_viewport_sync.json"), "w") as handle:
        json.dump(results, handle, indent=1)
    print("VIEWPORT_SYNC_OK")


main()
