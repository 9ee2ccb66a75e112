"""The scene camera → shgi.Camera (bpy side; the field mapping is in conversions.py)."""

import shgi

from . import conversions


def camera_from_scene(scene, depsgraph, log):
    """shgi.Camera of the scene camera as evaluated in `depsgraph`, or None (with a warning)."""
    if scene.camera is None:
        log.warn(f"scene {scene.name!r} has no camera; the export has none")
        return None
    camera_object = scene.camera.original.evaluated_get(depsgraph)
    data = camera_object.data
    render = scene.render
    if render.pixel_aspect_x != render.pixel_aspect_y:
        log.warn(f"scene {scene.name!r}: pixel aspect {render.pixel_aspect_x}:"
                 f"{render.pixel_aspect_y} is not square; SHGI renders square pixels")
    try:
        fields = conversions.camera_fields(
            data.type, camera_object.matrix_world, lens=data.lens,
            sensor_width=data.sensor_width, sensor_height=data.sensor_height,
            sensor_fit=data.sensor_fit, ortho_scale=data.ortho_scale, shift_x=data.shift_x,
            shift_y=data.shift_y, clip_start=data.clip_start, clip_end=data.clip_end,
            resolution_x=render.resolution_x, resolution_y=render.resolution_y,
            resolution_percentage=render.resolution_percentage)
        return shgi.Camera(**fields)
    except ValueError as error:
        log.warn(f"camera {camera_object.name!r}: {error}; the export has no camera")
        return None
