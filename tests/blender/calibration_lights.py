"""Cycles calibration of every light type: an open-topped diffuse room (floor, back and side
walls, a box) lit by one emitter per case. Compares Combined, DiffDir and DiffInd.

The emitters hang in front of the room, above the top of the frame, so the cases measure the
light they cast. In Blender 3.4 a light object's Ray Visibility > Camera (Object.visible_camera)
is off by default and Cycles' camera sees through lights; the two light_camera_* cases check
that SHGI follows the flag, with lights in view.

Run by tests/python/test_cycles_calibration.py; prints CALIBRATION_LIGHTS_DONE and writes the
per-case results as JSON (see calibration_common.py).
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import calibration_common as cal  # noqa: E402

DIFFUSE_PASSES = ("DiffDir", "DiffInd")
SAMPLES = 1024
# Rotation about X that turns a light's -Z axis towards +Y (into the room) and down.
INTO_ROOM = math.radians(35)


def room_scene(**world):
    cal.reset_scene(**world)
    cal.add_room()
    cal.add_box("box", (0.4, 0.3, 0.45), (0.45, 0.45, 0.45),
                cal.principled("box", (0.6, 0.6, 0.8)))
    cal.add_camera()


def point(name, tmpdir, results):
    room_scene()
    cal.add_light("POINT", (-0.6, -2.8, 2.8), energy=600.0, shadow_soft_size=0.1)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def point_exposure(name, tmpdir, results):
    # Light.exposure (x 2^exposure): in Blender 5.0, not in 4.2 LTS or 3.4, where the case is
    # reported as skipped.
    if "exposure" not in bpy.types.Light.bl_rna.properties:
        results[name] = {"skipped": f"Blender {bpy.app.version_string} has no Light.exposure"}
        return
    room_scene()
    cal.add_light("POINT", (-0.6, -2.8, 2.8), energy=200.0, shadow_soft_size=0.1,
                  exposure=1.5)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def spot(name, tmpdir, results):
    room_scene()
    # Aimed at the box so that the cone edge and the blend cross the floor and the back wall.
    cal.add_light("SPOT", (-0.5, -3.0, 2.9), (math.radians(52), 0.0, math.radians(-15)),
                  energy=2000.0, shadow_soft_size=0.05, spot_size=math.radians(40),
                  spot_blend=0.3)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def sun(name, tmpdir, results):
    room_scene()
    cal.add_light("SUN", (0.0, 0.0, 5.0), (math.radians(40), 0.0, math.radians(150)),
                  energy=3.0, angle=math.radians(5))
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def area(name, tmpdir, results):
    room_scene()
    cal.add_light("AREA", (-0.3, -2.6, 3.0), (INTO_ROOM, 0.0, 0.0), shape="RECTANGLE",
                  size=1.0, size_y=0.5, energy=400.0)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def area_disk(name, tmpdir, results):
    room_scene()
    cal.add_light("AREA", (0.5, -2.6, 3.0), (INTO_ROOM, 0.0, 0.0), shape="DISK", size=0.8,
                  energy=400.0)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def emissive_mesh(name, tmpdir, results):
    room_scene()
    # A 0.6 m square emitter in front of the room, above the frame (emission is two-sided).
    emitter = cal.principled("emitter", (0.0, 0.0, 0.0), emission=(1.0, 0.9, 0.8),
                             emission_strength=40.0)
    cal.add_quad("emitter", (-0.9, -3.1, 2.9), (0.6, 0.0, 0.0), (0.0, 0.6, 0.0), emitter)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def world(name, tmpdir, results):
    room_scene(world_color=(0.6, 0.7, 1.0), world_strength=1.0)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


def _lights_in_view(visible_camera):
    """An area light and a point light inside the frame, facing the camera, over the room."""
    room_scene()
    facing_camera = (math.radians(-80), 0.0, 0.0)
    for light in (cal.add_light("AREA", (-0.6, 0.5, 1.9), facing_camera, shape="SQUARE",
                                size=0.5, energy=100.0),
                  cal.add_light("POINT", (0.8, 0.0, 1.9), energy=100.0, shadow_soft_size=0.15)):
        light.visible_camera = visible_camera


def light_camera_visible(name, tmpdir, results):
    # Ray Visibility > Camera switched on: Cycles' camera sees the lights (Emit pass).
    _lights_in_view(True)
    cal.compare(name, DIFFUSE_PASSES + ("Emit",), SAMPLES, SAMPLES, tmpdir, results)


def light_camera_default(name, tmpdir, results):
    # Blender 3.4's default (visible_camera False): Cycles' camera does not see the lights.
    _lights_in_view(False)
    cal.compare(name, DIFFUSE_PASSES, SAMPLES, SAMPLES, tmpdir, results)


CASES = {"point": point, "point_exposure": point_exposure, "spot": spot, "sun": sun, "area": area, "area_disk": area_disk,
         "emissive_mesh": emissive_mesh, "world": world,
         "light_camera_visible": light_camera_visible,
         "light_camera_default": light_camera_default}

if __name__ == "__main__":
    cal.run_cases(CASES, "CALIBRATION_LIGHTS_DONE")
