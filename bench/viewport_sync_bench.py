"""Sync cost of the SHGI viewport on a scene of >= 500k triangles. Prints figures.

    blender -b --factory-startup --python bench/viewport_sync_bench.py -- \
        [build python dir (build/python)] [addon dir (addon)] [runs (7)]

(Debian's Blender needs pyenv's folders off PATH, see tests/python/blender_support.py.)

How it is driven: background Blender has no viewport, so no RenderEngine.view_update runs. A
``depsgraph_update_post`` handler calls ``ViewportSync.sync(depsgraph)`` — the function
view_update calls — with the handler's depsgraph and its ``depsgraph.updates``, which Blender
fills for an edit exactly as it does for the viewport's depsgraph. Each edit is made from
Python and followed by ``view_layer.update()``; "sync" is the time inside ViewportSync.sync
(what view_update costs on Blender's main thread), "depsgraph" the whole update including
Blender's own evaluation. "worker" is what the viewport's worker thread then does before it
can render: viewport_worker.updated_scene (edit the scene in place when only transforms
changed, else build a new shgi.Scene from the snapshot) and the commit. Medians of `runs`.

The scene: the project's Cornell box (examples/blender_scenes.py) holding a UV sphere of
SPHERE_SEGMENTS x SPHERE_RINGS (~523k triangles) with its own material.
"""

import os
import statistics
import sys
import time

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
sys.path[:0] = [ARGS[1] if len(ARGS) > 1 else os.path.join(REPO_ROOT, "addon"),
                ARGS[0] if len(ARGS) > 0 else os.path.join(REPO_ROOT, "build", "python"),
                os.path.join(REPO_ROOT, "examples")]
RUNS = int(ARGS[2]) if len(ARGS) > 2 else 7

import addon_utils  # noqa: E402
import blender_scenes  # noqa: E402

SPHERE_SEGMENTS, SPHERE_RINGS = 512, 512
MIN_TRIANGLES = 500_000


class Recorder:
    """depsgraph_update_post handler: syncs and keeps the report."""

    def __init__(self, sync):
        self.sync = sync
        self.report = None

    def __call__(self, _scene, depsgraph):
        self.report = self.sync.sync(depsgraph)


def build_scene():
    if "shgi_blender" not in bpy.context.preferences.addons:
        addon_utils.enable("shgi_blender", default_set=True, handle_error=None)
    scene = blender_scenes.build("cornell_box", 0.25)  # a new file, the add-on kept
    scene.render.engine = "SHGI"
    bpy.ops.mesh.primitive_uv_sphere_add(segments=SPHERE_SEGMENTS, ring_count=SPHERE_RINGS,
                                         radius=0.3, location=(0.3, 0.8, 0.9))
    sphere = bpy.context.active_object
    sphere.name = "sphere"
    material = bpy.data.materials.new("sphere")
    material.use_nodes = True
    sphere.data.materials.append(material)
    return scene, sphere, material


def edits(scene, sphere, material):
    """(name, function of the run index making a real change)."""
    objects = bpy.data.objects
    principled = material.node_tree.nodes["Principled BSDF"]
    background = scene.world.node_tree.nodes["Background"]

    def move_vertex(run):
        sphere.data.vertices[run].co.z += 0.001
        sphere.data.update()

    return [
        ("move small object", lambda run: setattr(objects["tall_block"].location, "x",
                                                  0.01 * (run + 1))),
        ("move 523k-triangle object", lambda run: setattr(sphere.location, "y",
                                                          0.8 + 0.01 * (run + 1))),
        ("move light", lambda run: setattr(objects["ceiling_light"].location, "x",
                                           0.01 * (run + 1))),
        ("light power", lambda run: setattr(objects["ceiling_light"].data, "energy",
                                            61.0 + run)),
        ("material colour", lambda run: setattr(principled.inputs["Base Color"],
                                                "default_value", (0.5, 0.5, 0.1 * run, 1))),
        ("world colour", lambda run: setattr(background.inputs["Strength"], "default_value",
                                             0.01 * (run + 1))),
        ("edit 523k-triangle mesh", move_vertex),
    ]


def worker_update(shgi, viewport_worker, state, snapshot, camera):
    """Seconds of the worker's scene update + commit for a new snapshot."""
    start = time.perf_counter()
    scene, change = viewport_worker.updated_scene(state["scene"], state["snapshot"], snapshot,
                                                  camera)
    scene.commit()
    state.update(scene=scene, snapshot=snapshot)
    return time.perf_counter() - start, change


def main():
    import shgi
    from shgi_blender.engine import viewport_worker
    from shgi_blender.engine.viewport_sync import ViewportSync

    scene, sphere, material = build_scene()
    sync = ViewportSync()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    first = sync.sync(depsgraph)
    triangles = sync.snapshot.triangles
    if triangles < MIN_TRIANGLES:
        raise AssertionError(f"the scene has {triangles} triangles, fewer than {MIN_TRIANGLES}")
    camera = shgi.Camera(resolution_x=64, resolution_y=64)
    state = {"scene": None, "snapshot": None}
    first_worker, _ = worker_update(shgi, viewport_worker, state, sync.snapshot, camera)
    rows = [("first sync (full export)", [first.seconds], [first.seconds], first.meshes_read,
             "DIFFERENT", [first_worker])]
    recorder = Recorder(sync)
    bpy.app.handlers.depsgraph_update_post.append(recorder)
    for name, change in edits(scene, sphere, material):
        syncs, totals, workers, reads, kinds = [], [], [], 0, set()
        for run in range(RUNS):
            recorder.report = None
            start = time.perf_counter()
            change(run)
            bpy.context.view_layer.update()
            totals.append(time.perf_counter() - start)
            report = recorder.report
            syncs.append(report.seconds)
            reads += report.meshes_read
            seconds, kind = worker_update(shgi, viewport_worker, state, sync.snapshot, camera)
            workers.append(seconds)
            kinds.add(kind)
        rows.append((name, syncs, totals, reads / RUNS, "/".join(sorted(kinds)), workers))
    bpy.app.handlers.depsgraph_update_post.remove(recorder)
    print_table(triangles, len(sync.snapshot.instances), rows)


def print_table(triangles, instances, rows):
    print(f"\nviewport sync: {triangles:,} triangles in {instances} objects, Blender "
          f"{bpy.app.version_string}, {os.cpu_count()} cores, medians of {RUNS} runs")
    print(f"{'edit':28s} {'sync (view_update)':>19s} {'depsgraph':>10s} {'meshes read':>12s} "
          f"{'snapshot':>10s} {'worker update+commit':>21s}")
    for name, syncs, totals, reads, kind, workers in rows:
        print(f"{name:28s} {1000 * statistics.median(syncs):16.2f} ms "
              f"{1000 * statistics.median(totals):7.1f} ms {reads:12.1f} {kind:>10s} "
              f"{1000 * statistics.median(workers):18.1f} ms")


main()
