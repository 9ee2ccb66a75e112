"""A glTF with a normalTexture loads and renders as the .blend it was exported from.

The normal-mapped plane of calibration_normal_maps.py under a sun is exported by the add-on
(Blender's MikkTSpace tangents) and rendered by SHGI's path tracer; then Blender's glTF exporter
writes it with and without TANGENT attributes, shgi.load_gltf reads each file and SHGI renders
it with the same settings. The camera rays are the same, so the Normal pass (the shading normal)
must agree pixel by pixel (up to the 8-bit PNG the exporter writes the normal map to) and
Combined's mean within 1%; the plain plane (no normal map) must not (the check has teeth).

Run with ``blender -b --factory-startup --python-exit-code 1 --python <this> -- <build python
dir> <addon dir>``; prints GLTF_NORMAL_MAP_OK.
"""

import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import calibration_common as cal  # noqa: E402
import calibration_normal_maps as maps  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

SAMPLES = 64
# Combined means of the same scene from two loaders, same camera rays and seeds: they differ by
# the 8-bit quantisation of the normal map in the glTF (a slope step of 1/127) and by the order
# of random numbers where triangles are numbered differently.
COMBINED_TOLERANCE = 0.01
# Per-pixel mean shading normal (components): 8-bit normal map texels are within 1/255 of the
# float ones, and tangents differ between MikkTSpace and the glTF's (or SHGI's) by float noise.
NORMAL_TOLERANCE = 0.02


def render(scene):
    scene.commit()
    settings = shgi.PathTracerSettings(samples=SAMPLES, seed=3, **cal.BOUNCES)
    return {name: np.asarray(pixels, np.float64)
            for name, pixels in shgi.render_path_traced(scene, settings).items()}


def gltf_render(folder, tangents, blend_scene):
    path = os.path.join(folder, f"plane_{'tangents' if tangents else 'plain'}.gltf")
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_SEPARATE",
                              export_tangents=tangents, export_lights=True, export_cameras=True)
    scene = shgi.load_gltf(path)
    camera = scene.camera  # glTF keeps the aspect ratio, not the render size
    camera.resolution_x = camera.resolution_y = cal.RESOLUTION
    scene.set_camera(camera)
    scene.set_world(blend_scene.world)  # glTF has none (load_gltf gives Blender's default grey)
    # load_gltf's materials follow Blender 3.4's Principled BSDF; on Blender 4+ the exporter's
    # follow that Blender's (PrincipledModel V2, Lambert diffuse, multiscatter GGX).
    material = scene.materials[0]
    reference = blend_scene.materials[0]
    for field in ("principled_model", "diffuse_model", "distribution"):
        setattr(material, field, getattr(reference, field))
    scene.set_material(0, material)
    return render(scene)


def compare(what, passes, reference):
    combined = passes["Combined"][..., :3].mean() / reference["Combined"][..., :3].mean() - 1.0
    normal = np.abs(passes["Normal"][..., :3] - reference["Normal"][..., :3]).max()
    print(f"   {what}: Combined {100 * combined:+.3f}%, largest Normal difference {normal:.4f}",
          flush=True)
    return combined, normal


def main():
    shgi.set_max_threads(cal.THREADS)
    maps.plane_scene()
    # Specular 0.5, Blender's default and glTF's (no KHR_materials_specular, which load_gltf
    # does not read): the two files then describe the same material.
    cal.setup.set_principled_inputs(bpy.data.materials["plane"].node_tree.nodes["Principled BSDF"],
                                    specular=0.5)
    cal.add_light("SUN", (0.0, 0.0, 5.0), (math.radians(45), 0.0, math.radians(120)),
                  energy=3.0, angle=math.radians(2))
    blend_scene = export_scene(bpy.context.evaluated_depsgraph_get(), bpy.context.scene).scene
    blend = render(blend_scene)
    assert blend["Normal"][..., :3].std() > 0.05, "the normal map must show in the Normal pass"
    with tempfile.TemporaryDirectory(prefix="shgi_gltf_nmap_") as folder:
        for tangents in (True, False):
            combined, normal = compare(f"glTF {'with' if tangents else 'without'} TANGENT",
                                       gltf_render(folder, tangents, blend_scene), blend)
            assert abs(combined) <= COMBINED_TOLERANCE, combined
            assert normal <= NORMAL_TOLERANCE, normal
        # Teeth: the same glTF without its normal map is far from the .blend.
        plane = bpy.data.materials["plane"]
        plane.node_tree.links.remove(plane.node_tree.nodes["Principled BSDF"]
                                     .inputs["Normal"].links[0])
        combined, normal = compare("glTF without normal map", gltf_render(folder, False, blend_scene),
                                   blend)
        assert abs(combined) > 5 * COMBINED_TOLERANCE and normal > 10 * NORMAL_TOLERANCE
    print("GLTF_NORMAL_MAP_OK", flush=True)


if __name__ == "__main__":
    main()
