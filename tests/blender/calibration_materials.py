"""Cycles calibration of the Principled BSDF: diffuse (with its dielectric specular), glossy
metal and rough glass, in the open-topped room of calibration_lights.py lit by an area light
in front of the room, above the frame (lights are invisible to Blender 3.4's camera by default).

Run by tests/python/test_cycles_calibration.py; prints CALIBRATION_MATERIALS_DONE and writes the
per-case results as JSON (see calibration_common.py).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import calibration_common as cal  # noqa: E402

SAMPLES = 1024


def lit_room(material=cal.principled):
    cal.reset_scene(world_color=(0.5, 0.6, 0.8), world_strength=0.2)
    cal.add_room(material=material)
    cal.add_camera(location=(0.0, -4.5, 1.4), target=(0.0, 0.0, 0.7))
    cal.add_light("AREA", (-0.4, -2.2, 3.0), (math.radians(35), 0.0, math.radians(-10)),
                  shape="RECTANGLE", size=1.2, size_y=0.6, energy=500.0)


def diffuse(name, tmpdir, results):
    # Blender's default Principled BSDF: diffuse plus a dielectric specular (Specular 0.5).
    lit_room()
    cal.add_sphere("sphere", (0.0, 0.0, 0.75), 0.75,
                   cal.principled("diffuse", (0.8, 0.5, 0.2), roughness=0.5, specular=0.5))
    cal.compare(name, ("DiffDir", "DiffInd", "GlossDir*GlossCol"), SAMPLES, SAMPLES, tmpdir,
                results, also={name + "_gloss_passes": ("GlossCol", "GlossDir")})


def diffuse_bsdf(name, tmpdir, results):
    # Blender's Diffuse BSDF at roughness 0 (Lambert) on every surface.
    lit_room(material=cal.diffuse_bsdf)
    cal.add_sphere("sphere", (0.0, 0.0, 0.75), 0.75, cal.diffuse_bsdf("diffuse", (0.8, 0.5, 0.2)))
    cal.compare(name, ("DiffDir", "DiffInd"), SAMPLES, SAMPLES, tmpdir, results)


def glossy_metal(name, tmpdir, results):
    lit_room()
    cal.add_sphere("sphere", (0.0, 0.0, 0.75), 0.75,
                   cal.principled("metal", (0.95, 0.64, 0.54), roughness=0.3, specular=0.5,
                                  metallic=1.0))
    # Highlights of the area light on the sphere are the noisiest pass: twice the samples.
    cal.compare(name, ("DiffDir", "DiffInd", "GlossDir*GlossCol", "GlossInd*GlossCol"),
                2 * SAMPLES, 2 * SAMPLES, tmpdir, results,
                also={name + "_gloss_passes": ("GlossCol", "GlossDir", "GlossInd")})


def glass(name, tmpdir, results):
    # A rough glass pane covering the whole frame, in front of the room; the room is lit by an
    # area light inside it (seen through the pane: transmission rays see lights).
    cal.reset_scene(world_color=(0.5, 0.6, 0.8), world_strength=0.2)
    cal.add_room()
    cal.add_camera(location=(0.0, -4.5, 1.4), target=(0.0, 0.0, 0.7))
    cal.add_box("box", (0.4, 0.3, 0.45), (0.45, 0.45, 0.45),
                cal.principled("box", (0.6, 0.6, 0.8)))
    cal.add_light("AREA", (-0.5, 0.6, 2.2), (math.radians(-20), 0.0, 0.0), shape="SQUARE",
                  size=0.8, energy=300.0)
    glass_material = cal.principled("glass", (1.0, 1.0, 1.0), roughness=0.4, specular=0.5,
                                     transmission=1.0, ior=1.45)
    # Vertical pane at y = -3.5 facing the camera (front along -Y), much larger than the frame.
    cal.add_quad("pane", (-4.0, -3.5, -3.0), (8.0, 0.0, 0.0), (0.0, 0.0, 8.0), glass_material)
    cal.compare(name, ("TransDir", "TransInd", "GlossDir"), SAMPLES, SAMPLES, tmpdir, results)


CASES = {"diffuse": diffuse, "diffuse_bsdf": diffuse_bsdf, "glossy_metal": glossy_metal,
         "glass": glass}

if __name__ == "__main__":
    cal.run_cases(CASES, "CALIBRATION_MATERIALS_DONE")
