"""Bake lightmaps of the selected mesh objects, merge a farm bake's shards, remove the
lightmap nodes (bpy).

SHGI_OT_bake_lightmaps, on Blender's main thread: checks the request (native module, a mesh
among the selected objects, a usable output folder, the lightmap UV map on every object,
created by Lightmap Pack or xatlas when asked), exports the scene (export_scene on the evaluated
depsgraph, instances named after their objects), finds each object's instance, checks that
something emits light and sizes each lightmap. A BakeTask (engine/lightmap_bake.py) then
commits, solves the field of a field source and runs shgi.bake.bake_scene on a worker thread.
From the UI (invoke) it runs modal: a timer shows progress in the status bar; Esc cancels and
keeps the lightmaps finished before. From a script or in background mode (execute) it waits, so
``blender -b file.blend --python-expr "bpy.ops.shgi.bake_lightmaps()"`` bakes headless (in
background mode printing a line per finished lightmap and per 10% of progress, for a farm's
log) and fails with the report's message (RuntimeError) when the bake cannot run.

Undo: a bake is one undo step. Its only data changes before the end are the UV maps Create UV
Map adds; the images and material nodes are made together when the bake ends, inside the
operator, whose UNDO flag pushes one step covering them all (a cancelled bake that kept
something pushes that step itself). An undo therefore takes back UV maps, images and nodes
together.

Facing: before baking, operators/facing_check.py looks for objects facing away from the scene
(front to the world, back to the other objects: a room built with its normals out) and warns,
naming them and the fixes, as their lightmaps would hold the light outside; with Bake Side
"Facing the Scene" the export turns them around instead, so their backs are baked.

Results: the files shgi.bake writes into the output folder (``<object>.exr`` and ``.png``;
with Shards > 1 the raw shard files of shard Shard, which SHGI_OT_merge_lightmap_shards merges
into the same files a whole bake writes) and the images ``<object>_shgi_lightmap``
(operators/lightmap_images.py), optionally shown in the objects' materials.

Settings: every operator property the caller does not set comes from ``scene.shgi.bake`` (the
Bake panel); light-path limits and the seed from ``scene.shgi`` (bake_settings.py).
"""

import os
import time
from types import SimpleNamespace

import bpy

from .. import bake_settings, native, properties
from ..engine.lightmap_bake import BakeRequest, BakeTask
from . import facing_check, lightmap_images, xatlas_uv
from .modal_task import ModalTaskOperator

REPORT_PREFIX = "SHGI bake: "
# Lightmap Pack's margin between faces, in % of the unit square: its largest.
LIGHTMAP_PACK_MARGIN = 1.0


class BakeError(Exception):
    """A request the bake refuses; the message names the input and the fix."""


class _MethodOf:
    """scene.shgi as solver_recipe reads it, with the bake's source as the method."""

    def __init__(self, props, method):
        self._props = props
        self.method = method

    def __getattr__(self, name):
        return getattr(self._props, name)


def bake_values(operator, scene):
    """The settings of one operator call: the properties the caller set, the others from
    scene.shgi.bake (a namespace with bake_settings.BAKE_PROPERTY_DEFAULTS' names)."""
    group = scene.shgi.bake
    return SimpleNamespace(**{
        name: getattr(operator, name) if operator.properties.is_property_set(name)
        else getattr(group, name) for name in bake_settings.BAKE_PROPERTY_DEFAULTS})


def selected_meshes(context):
    """The selected mesh objects, in name order (the bake order); BakeError when none."""
    objects = sorted((obj for obj in context.selected_objects if obj.type == "MESH"),
                     key=lambda obj: obj.name)
    if not objects:
        raise BakeError("nothing to bake: no mesh object is selected; select the objects to "
                        "bake lightmaps for")
    return objects


def output_dir(folder):
    """The absolute output folder; BakeError for a relative one in an unsaved file."""
    if not folder:
        raise BakeError("no output folder: set Output Folder")
    if folder.startswith("//") and not bpy.data.filepath:
        raise BakeError(f"the output folder {folder!r} is relative to the .blend file, which "
                        "has not been saved: save the file first, or choose an absolute folder")
    return os.path.normpath(bpy.path.abspath(folder))


def prepare_uv_maps(context, objects, values, report, created):
    """Makes sure every object's mesh has the lightmap UV map: creates it when asked (by
    Lightmap Pack or xatlas, values.uv_layout; xatlas's chart count and utilisation go to
    `report`; the meshes' names are appended to `created`), else BakeError naming the objects
    without it and the fixes."""
    missing = [obj for obj in objects if values.uv_map not in obj.data.uv_layers]
    if not missing:
        return
    if not values.create_uv:
        names = ", ".join(repr(obj.name) for obj in missing)
        raise BakeError(
            f"{names} {'has' if len(missing) == 1 else 'have'} no UV map {values.uv_map!r}: "
            "turn on Create UV Map (Lightmap Pack or xatlas lays one out), add that UV map, or "
            "set UV Map to one the objects have")
    done = set()
    for obj in missing:
        if obj.data.name_full not in done:
            create_lightmap_uv(context, obj, values, report)
            done.add(obj.data.name_full)
            created.append(obj.data.name_full)


def create_lightmap_uv(context, obj, values, report):
    """Adds UV map values.uv_map to the object's mesh, laid out by Lightmap Pack (each face its
    own box in the unit square) or by xatlas (operators/xatlas_uv.py, at the object's lightmap
    size); the mesh's active UV map stays the one it was."""
    name = values.uv_map
    mesh = obj.data
    if mesh.library is not None:
        raise BakeError(f"object {obj.name!r}: its mesh {mesh.name!r} is linked from a library "
                        f"and cannot get a UV map {name!r}; add it in the library file")
    if not mesh.polygons:
        raise BakeError(f"object {obj.name!r}: its mesh {mesh.name!r} has no faces to lay out a "
                        f"UV map {name!r} on (nothing to bake a lightmap on); add faces or "
                        "deselect it")
    # By name: Lightmap Pack's trip through Edit Mode rebuilds the UV layers, and in Blender 5.0
    # a reference taken before it makes another layer active.
    previous = mesh.uv_layers.active.name if mesh.uv_layers.active is not None else None
    layer = mesh.uv_layers.new(name=name, do_init=False)
    if layer is None:
        raise BakeError(f"object {obj.name!r}: its mesh has the most UV maps Blender allows; "
                        f"remove one or set UV Map to an existing one")
    mesh.uv_layers.active = layer
    if values.uv_layout == "XATLAS":
        _xatlas_layout(obj, layer, values, report)
    else:
        _lightmap_pack(context, obj, name)
    if previous is not None:
        mesh.uv_layers.active = mesh.uv_layers[previous]


def _xatlas_layout(obj, layer, values, report):
    from shgi import bake as shgi_bake

    try:
        layout, disagreeing = xatlas_uv.lay_out(
            obj, layer, values.resolution, values.texel_density,
            (shgi_bake.MIN_RESOLUTION, shgi_bake.MAX_RESOLUTION))
    except (ImportError, ValueError) as error:
        obj.data.uv_layers.remove(layer)
        raise BakeError(f"object {obj.name!r}: xatlas could not lay out {values.uv_map!r}: "
                        f"{error}") from None
    report({"INFO"}, f"{REPORT_PREFIX}{obj.name}: {shgi_bake.describe_uv_layout(layout)}")
    if disagreeing:
        report({"WARNING"}, f"{REPORT_PREFIX}{obj.name}: {disagreeing} face corners of "
                            "non-planar polygons lie in two xatlas charts and took one chart's "
                            "UV; triangulate those polygons for a clean layout")


def _lightmap_pack(context, obj, name):
    """Lays out the object's new, active UV map `name` with Lightmap Pack; BakeError, without
    that UV map, when Blender refuses."""
    options = {"PREF_CONTEXT": "ALL_FACES", "PREF_PACK_IN_ONE": False,
               "PREF_NEW_UVLAYER": False, "PREF_MARGIN_DIV": LIGHTMAP_PACK_MARGIN}
    # Blender 3.4's "New Image" (an unused image per mesh) is off; Blender 5.0 has no such option.
    if "PREF_APPLY_IMAGE" in bpy.ops.uv.lightmap_pack.get_rna_type().properties:
        options["PREF_APPLY_IMAGE"] = False
    try:
        with context.temp_override(active_object=obj, object=obj, selected_objects=[obj],
                                   selected_editable_objects=[obj]):
            bpy.ops.uv.lightmap_pack(**options)
    except RuntimeError as error:  # the operator's ERROR report
        obj.data.uv_layers.remove(obj.data.uv_layers[name])  # by name: edit mode rebuilt them
        raise BakeError(f"object {obj.name!r}: Lightmap Pack could not lay out {name!r}: "
                        f"{report_text(error)}") from None


def report_text(error):
    """The message of an operator's ERROR report that bpy.ops raised as RuntimeError."""
    return str(error).strip().removeprefix("Error: ")


def bake_jobs(export, objects, values):
    """A shgi.bake.BakeJob per object: its instance in the exported scene (the first one
    named after it), its name, its lightmap size. BakeError names an object the export left
    out, and why."""
    from shgi.bake import BakeJob

    scene = export.scene
    instances = {}
    for index, instance in enumerate(scene.instances):
        instances.setdefault(instance.name, index)
    jobs = []
    for obj in objects:
        if obj.name not in instances and obj.name in export.skipped:
            raise BakeError(f"object {obj.name!r} was left out of the exported scene: "
                            f"{export.skipped[obj.name]}; fix it or deselect it")
        if obj.name not in instances:
            raise BakeError(f"object {obj.name!r} is not in the exported scene (hidden for "
                            "render, or without faces): make it renderable or deselect it")
        index = instances[obj.name]
        size = bake_settings.lightmap_size(values, scene, index)
        jobs.append(BakeJob(instance=index, name=obj.name, width=size, height=size))
    return jobs


def check_facing(scene, depsgraph, objects, values, report):
    """Names of the objects the bake exports facing the other way.

    Bake Side "Front": none; each of `objects` (the baked ones) facing away from the scene
    (facing_check.py) is warned about. "Facing the Scene": every renderable mesh object of the
    scene facing away, each reported: the baked objects' backs are baked, and the light they
    get off the others comes off their sides facing the scene too.
    """
    if values.bake_side != "FACING_SCENE":
        for name in facing_check.facing_away(scene, depsgraph, objects):
            report({"WARNING"}, f"{REPORT_PREFIX}{facing_check.warning(name)}")
        return []
    meshes = [obj.original for obj in depsgraph.objects
              if obj.type == "MESH" and not obj.original.hide_render]
    away = facing_check.facing_away(scene, depsgraph, meshes)
    baked = {obj.name for obj in objects}
    for name in away:
        report({"INFO"}, f"{REPORT_PREFIX}{facing_check.turned_around(name, name in baked)}")
    return away


def prepare_bake(context, values, report, merge=False, created=None):
    """The BakeRequest of a bake (or, with `merge`, of a merge of shard files) of the
    selected objects; BakeError when it cannot run. The meshes that got a new UV map are
    appended to `created`; objects facing away from the scene are reported as warnings."""
    shgi = native.module()
    if shgi is None:
        raise BakeError(native.error())
    from ..engine.field_solvers import solver_recipe
    from ..export import export_scene

    if values.farm == "FLAMENCO" and not merge:
        raise BakeError("Farm is Flamenco: Write Flamenco Job writes the job for the farm; set "
                        "Farm to This Computer or Dask to bake from here")
    if merge and values.shard_count <= 1:
        raise BakeError("Shards is 1: there are no shard files to merge; set Shards to the "
                        "number of shards the farm baked")
    objects = selected_meshes(context)
    out_dir = output_dir(values.output_folder)
    if context.mode != "OBJECT":  # edit-mode changes reach the mesh only in object mode
        bpy.ops.object.mode_set(mode="OBJECT")
    prepare_uv_maps(context, objects, values, report, [] if created is None else created)
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    flipped = check_facing(scene, depsgraph, objects, values, report)
    export = export_scene(depsgraph, scene, report=report, for_render=True, with_camera=False,
                          flipped=flipped)
    from shgi import bake as shgi_bake  # shgi is loaded (native.module() above)

    if not shgi_bake.emits_light(export.scene):
        raise BakeError(shgi_bake.NO_LIGHT_MESSAGE)
    try:
        jobs = bake_jobs(export, objects, values)
        options = bake_settings.bake_options(values, scene.shgi, shgi)
        if merge:
            return BakeRequest(export.scene, jobs, options, out_dir,
                               merge_shards=values.shard_count)
        recipe = None
        if bake_settings.uses_field(values):
            # Read through a final gather (Bake > Final Gather), the field is solved one
            # bounce shallower, as F12's (settings.light_path_fields); with the method's Bake
            # Passes where it has them.
            recipe = solver_recipe(_MethodOf(scene.shgi, values.source), shgi,
                                   export.probe_volumes, gather=values.final_gather, bake=True)
        farm = bake_settings.farm_target(values)
        if farm is not None:  # the farm splits the bake itself: no shard of it here
            return BakeRequest(export.scene, jobs, options, out_dir, recipe, farm=farm)
        return BakeRequest(export.scene, jobs, options, out_dir, recipe,
                           bake_settings.shard(values))
    except ValueError as error:
        raise BakeError(str(error)) from None


class _BakeOperator(ModalTaskOperator):
    """Shared body of the bake and merge operators: checks, a BakeTask, modal or waiting."""

    # UNDO: Blender pushes one undo step when the operator finishes, covering every data
    # change of the bake (see the module's docstring). Not REGISTER: Adjust Last Operation and
    # Repeat Last would run the bake again through execute(), which waits for it on the UI
    # thread; the bake's settings live in the Bake panel, and its button bakes again modally.
    bl_options = {"UNDO"}
    MERGE = False
    STATUS_PREFIX = "SHGI bake: "
    STATUS_IDLE = "starting"
    PROGRESS_BAR = True
    LOG_STEPS = 10  # a headless bake logs its progress in tenths

    @classmethod
    def poll(cls, context):
        return context.scene is not None

    def _progress(self, task):
        return task.fraction, task.stage

    def _tick(self, _context, task):
        self._collect(task)

    def _waiting(self, task):
        self._collect(task)
        self._log_progress(task.fraction, task.stage)

    def _start(self, context):
        """Checks and starts the bake (None, with an ERROR report, when it cannot run)."""
        self._values = bake_values(self, context.scene)
        self._lightmaps = []      # shgi.bake.Lightmaps finished, made into images at the end
        self._new_uv_maps = []    # meshes that got the lightmap UV map from this bake
        self._logged_steps = 0
        self._log = bpy.app.background
        self._started = time.perf_counter()
        try:
            request = prepare_bake(context, self._values, self.report, merge=self.MERGE,
                                   created=self._new_uv_maps)
        except BakeError as error:
            self.report({"ERROR"}, f"{REPORT_PREFIX}{error}")
            self._push_undo_step()
            return None
        self._job_count = len(request.jobs)
        return BakeTask(native.module(), request).start()

    def _collect(self, task):
        """Keeps the lightmaps finished since the last call (logged in background mode); no
        bpy data changes before the end."""
        for lightmap in task.take_finished():
            self._lightmaps.append(lightmap)
            if self._log:
                print(f"{REPORT_PREFIX}{lightmap.name} done ({len(self._lightmaps)} of "
                      f"{counted(self._job_count, 'lightmap')})", flush=True)

    def _log_progress(self, fraction, stage):
        """In background mode, a line for each tenth of the progress reached since the last."""
        reached = min(self.LOG_STEPS, int(fraction * self.LOG_STEPS + 1e-9))
        while self._log and self._logged_steps < reached:
            self._logged_steps += 1
            print(f"{REPORT_PREFIX}{100 * self._logged_steps // self.LOG_STEPS}% "
                  f"({stage or self.STATUS_IDLE})", flush=True)

    def _store_lightmaps(self):
        """The images (and with Show in Materials, the material nodes) of every lightmap kept,
        made in one go; the lightmap_images.HookUps (its warnings reported)."""
        values = self._values
        hook_ups = lightmap_images.HookUps()
        for lightmap in self._lightmaps:
            image = lightmap_images.store_lightmap_image(lightmap)
            obj = bpy.data.objects.get(lightmap.name)
            if values.hook_up_material and obj is not None:
                lightmap_images.hook_up_lightmap(
                    obj, image, values.uv_map, values.content != "FULL",
                    values.single_user_materials, hook_ups)
        for warning in hook_ups.warnings:
            self.report({"WARNING"}, f"{REPORT_PREFIX}{warning}")
        return hook_ups

    def _push_undo_step(self):
        """One undo step for a bake that ends CANCELLED after changing data (the UNDO flag
        pushes only for FINISHED)."""
        if (self._lightmaps or self._new_uv_maps) and bpy.ops.ed.undo_push.poll():
            bpy.ops.ed.undo_push(message=self.bl_label)

    def _finish(self, _context, task):
        self._collect(task)
        hook_ups = self._store_lightmaps()
        if task.error is not None or task.cancelled:
            self._push_undo_step()
        if task.error is not None:
            self.report({"ERROR"}, f"{REPORT_PREFIX}{task.error}")
            return {"CANCELLED"}
        if task.cancelled:
            self.report({"WARNING"}, f"{REPORT_PREFIX}cancelled; the {len(self._lightmaps)} "
                        "lightmaps finished before are kept")
            return {"CANCELLED"}
        self._log_progress(1.0, "done")
        seconds = time.perf_counter() - self._started
        request = task.request
        if request.farm is not None:
            where = request.farm.scheduler or f"{request.farm.workers} Dask workers here"
            self.report({"INFO"}, f"{REPORT_PREFIX}{counted(len(self._lightmaps), 'lightmap')} "
                        f"baked on {where} into {request.out_dir} ({seconds:.2f} s)")
        elif request.shard is not None:
            self.report({"INFO"}, f"{REPORT_PREFIX}shard {request.shard[0]} of "
                        f"{request.shard[1]}: {len(task.results)} shard files in "
                        f"{request.out_dir} ({seconds:.2f} s); merge them with Merge Shards")
        else:
            shown = (f"; {describe_hook_ups(hook_ups)}" if self._values.hook_up_material
                     else "")
            self.report({"INFO"}, f"{REPORT_PREFIX}{counted(len(self._lightmaps), 'lightmap')} "
                        f"baked into {request.out_dir} ({seconds:.2f} s){shown}")
        return {"FINISHED"}


def describe_hook_ups(hook_ups):
    """What Show in Materials did, for the bake's result: "shown in 10 materials (8 of them
    single-user copies of shared materials)", and how many warnings it gave."""
    text = f"shown in {counted(len(hook_ups.materials), 'material')}"
    if hook_ups.copies:
        text += f" ({hook_ups.copies} of them single-user copies of shared materials)"
    if hook_ups.warnings:
        text += f"; {counted(len(hook_ups.warnings), 'warning')} (see the Info editor)"
    return text


def counted(count, noun):
    """"1 lightmap", "10 lightmaps"."""
    return f"{count} {noun}{'' if count == 1 else 's'}"


class SHGI_OT_bake_lightmaps(_BakeOperator, bpy.types.Operator):
    """Bake lightmaps of the selected mesh objects into images and EXR/PNG files"""

    bl_idname = "shgi.bake_lightmaps"
    bl_label = "Bake Lightmaps"
    __annotations__ = properties.bake_properties()


class SHGI_OT_merge_lightmap_shards(_BakeOperator, bpy.types.Operator):
    """Merge the shard files a farm baked for the selected objects into their lightmaps, \
exactly as one whole bake writes them"""

    bl_idname = "shgi.merge_lightmap_shards"
    bl_label = "Merge Shards"
    MERGE = True
    __annotations__ = properties.bake_properties()


class SHGI_OT_write_flamenco_job(bpy.types.Operator):
    """Write a Flamenco job that bakes the selected objects' lightmaps on a Flamenco farm (the \
SHGI Lightmap Bake job type): its tasks open this saved .blend file"""

    bl_idname = "shgi.write_flamenco_job"
    bl_label = "Write Flamenco Job"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(
        name="File", subtype="FILE_PATH", default="",
        description="Where the job's JSON goes (empty: shgi_flamenco_job.json in the Output "
                    "Folder)")

    def execute(self, context):
        import json

        values = context.scene.shgi.bake
        try:
            if not bpy.data.filepath:
                raise BakeError("the .blend file has not been saved: every task of the job "
                                "opens it, so save it first")
            objects = selected_meshes(context)
            out_dir = output_dir(values.output_folder)
        except BakeError as error:
            self.report({"ERROR"}, f"{REPORT_PREFIX}{error}")
            return {"CANCELLED"}
        name = f"{bpy.path.display_name_from_filepath(bpy.data.filepath)} lightmaps"
        job = bake_settings.flamenco_job(values, [obj.name for obj in objects],
                                         bpy.data.filepath, out_dir, name)
        path = (bpy.path.abspath(self.filepath) if self.filepath
                else os.path.join(out_dir, "shgi_flamenco_job.json"))
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as file:
                json.dump(job, file, indent=2)
        except OSError as error:
            self.report({"ERROR"}, f"{REPORT_PREFIX}could not write the job {path!r}: {error}")
            return {"CANCELLED"}
        if bpy.data.is_dirty:
            self.report({"WARNING"}, f"{REPORT_PREFIX}the .blend file has unsaved changes, "
                        "which the job's tasks will not see: save it before submitting")
        self.report({"INFO"}, f"{REPORT_PREFIX}Flamenco job ({values.shard_count} shards, "
                    f"{counted(len(objects), 'object')}) written to {path}")
        return {"FINISHED"}


class SHGI_OT_remove_lightmap_nodes(bpy.types.Operator):
    """Remove the SHGI Lightmap nodes from the selected objects' materials, giving back the \
surfaces they had"""

    bl_idname = "shgi.remove_lightmap_nodes"
    bl_label = "Remove Lightmap Nodes"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return bool(context.selected_objects)

    def execute(self, context):
        materials = {slot.material for obj in context.selected_objects
                     for slot in obj.material_slots if slot.material is not None}
        removed = sum(lightmap_images.remove_lightmap_nodes(material) for material in materials)
        self.report({"INFO"}, f"{REPORT_PREFIX}lightmap nodes removed from {removed} materials")
        return {"FINISHED"}


CLASSES = (SHGI_OT_bake_lightmaps, SHGI_OT_merge_lightmap_shards, SHGI_OT_write_flamenco_job,
           SHGI_OT_remove_lightmap_nodes)
