"""The exported shgi.Camera projects points where Blender does, for every type and sensor fit.

For perspective and orthographic cameras, each sensor fit, landscape and portrait renders and a
lens shift, points in front of the camera are projected with shgi's Camera.project() and with
Blender's bpy_extras.object_utils.world_to_camera_view(); the film positions must agree, and
the ray shgi generates through that film position must pass through the point. Prints
EXPORT_CAMERA_OK when every check passed.
"""

import itertools
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from bpy_extras.object_utils import world_to_camera_view  # noqa: E402
from mathutils import Vector  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

# Film positions agree to this many pixels (float32 maths on both sides, 60-pixel images).
PIXEL_TOLERANCE = 1e-3
# A generated ray passes this close (m) to the point it was generated for.
RAY_TOLERANCE = 1e-4
# Render sizes before the 50% resolution_percentage: landscape and portrait.
RESOLUTIONS = ((128, 96), (80, 120))
RESOLUTION_PERCENTAGE = 50
SHIFT = (0.1, -0.05)
SEED = 3


def camera_points(camera_object, count=6):
    """World points in front of the camera, within its view for a 35 mm lens or ortho scale 6."""
    rng = np.random.default_rng(SEED)
    depth = rng.uniform(3.0, 8.0, count)
    local = np.stack([rng.uniform(-0.3, 0.3, count) * depth,
                      rng.uniform(-0.3, 0.3, count) * depth, -depth], axis=1)
    return [camera_object.matrix_world @ Vector(p) for p in local]


def build_camera():
    setup.clear_scene()
    data = bpy.data.cameras.new("CameraData")
    data.lens, data.sensor_width, data.sensor_height, data.ortho_scale = 35.0, 36.0, 20.0, 6.0
    data.shift_x, data.shift_y = SHIFT
    camera = bpy.data.objects.new("Camera", data)
    camera.location = (1.0, -6.0, 2.0)
    camera.rotation_euler = (1.2, 0.1, 0.4)
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    bpy.context.scene.render.resolution_percentage = RESOLUTION_PERCENTAGE
    return camera


def check_configuration(camera, camera_type, sensor_fit, resolution):
    scene = bpy.context.scene
    camera.data.type, camera.data.sensor_fit = camera_type, sensor_fit
    scene.render.resolution_x, scene.render.resolution_y = resolution
    bpy.context.view_layer.update()
    exported = export_scene(bpy.context.evaluated_depsgraph_get()).scene.camera
    width = resolution[0] * RESOLUTION_PERCENTAGE // 100
    height = resolution[1] * RESOLUTION_PERCENTAGE // 100
    if (exported.resolution_x, exported.resolution_y) != (width, height):
        raise AssertionError(f"resolution {exported.resolution_x} x {exported.resolution_y}")
    what = f"{camera_type} {sensor_fit} {resolution}"
    for point in camera_points(camera):
        ndc = world_to_camera_view(scene, camera, point)
        blender_film = (ndc.x * width, (1.0 - ndc.y) * height)
        shgi_film = exported.project(tuple(point))
        if shgi_film is None:
            raise AssertionError(f"{what}: shgi says {tuple(point)} is behind the camera")
        setup.check_close(f"{what}: film position of {tuple(point)}", shgi_film, blender_film,
                          PIXEL_TOLERANCE)
        origins, directions = exported.generate_rays(np.array([blender_film], np.float32))
        to_point = np.array(point) - origins[0]
        miss = np.linalg.norm(to_point - np.dot(to_point, directions[0]) * directions[0])
        setup.check_close(f"{what}: ray miss distance", miss, 0.0, RAY_TOLERANCE)


def main():
    camera = build_camera()
    configurations = list(itertools.product(("PERSP", "ORTHO"), ("AUTO", "HORIZONTAL",
                                                                 "VERTICAL"), RESOLUTIONS))
    for configuration in configurations:
        check_configuration(camera, *configuration)
    print(f"{len(configurations)} camera configurations agree")
    print("EXPORT_CAMERA_OK")


main()
