"""The add-on exports Blender's Bump node: its Height from an Image Texture's Color, Strength,
Distance and Invert, over a Normal Map node on the Bump node's own Normal input, and refuses (with
a warning naming the material) a Height it cannot evaluate.

Run with ``blender -b --factory-startup --python-exit-code 1 --python <this> -- <build python
dir> <addon dir>``; prints BUMP_EXPORT_OK.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import calibration_common as cal  # noqa: E402
import calibration_normal_maps as maps  # noqa: E402

import bpy  # noqa: E402
import shgi  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402


def bumped_quad(name, x, strength=1.0, distance=1.0, invert=False, height_from="Color",
                normal_map=False):
    """A UV-mapped quad at x with a material whose Normal is a Bump node; the Bump's Height comes
    from the height image's `height_from` output ("Color", "Alpha") or a Noise Texture ("Noise")."""
    material = cal.principled(name, (0.8, 0.8, 0.8))
    tree = material.node_tree
    bump = tree.nodes.new("ShaderNodeBump")
    bump.invert = invert
    bump.inputs["Strength"].default_value = strength
    bump.inputs["Distance"].default_value = distance
    if height_from == "Noise":
        source = tree.nodes.new("ShaderNodeTexNoise").outputs["Fac"]
    else:
        texture = tree.nodes.new("ShaderNodeTexImage")
        texture.image = maps.height_image()
        source = texture.outputs[height_from]
    tree.links.new(source, bump.inputs["Height"])
    if normal_map:
        texture = tree.nodes.new("ShaderNodeTexImage")
        texture.image = maps.bump_image()
        node = tree.nodes.new("ShaderNodeNormalMap")
        node.uv_map = "UVMap"
        tree.links.new(texture.outputs["Color"], node.inputs["Color"])
        tree.links.new(node.outputs["Normal"], bump.inputs["Normal"])
    tree.links.new(bump.outputs["Normal"], tree.nodes["Principled BSDF"].inputs["Normal"])
    maps.add_uvs(cal.add_quad(name, (x, 0, 0), (1, 0, 0), (0, 1, 0), material))


def main():
    cal.reset_scene()
    bumped_quad("plain_bump", 0.0)
    bumped_quad("inverted_half", 2.0, strength=0.3, distance=0.25, invert=True)
    bumped_quad("over_normal_map", 4.0, normal_map=True)
    bumped_quad("alpha_height", 6.0, height_from="Alpha")
    bumped_quad("noise_height", 8.0, height_from="Noise")
    cal.add_camera(location=(4.0, -6.0, 4.0), target=(4.0, 0.5, 0.0))
    result = export_scene(bpy.context.evaluated_depsgraph_get(), bpy.context.scene)
    materials = {m.name: m for m in result.scene.materials}

    plain = materials["plain_bump"]
    assert plain.bump_texture >= 0 and plain.normal_texture == -1, plain
    # An Image Texture without a UV Map node reads the active render UV map: "" (the first).
    assert (plain.bump_strength, plain.bump_distance, plain.bump_uv_set) == (1.0, 1.0, ""), \
        (plain.bump_strength, plain.bump_distance, plain.bump_uv_set)
    inverted = materials["inverted_half"]
    assert inverted.bump_texture >= 0
    assert abs(inverted.bump_strength - 0.3) < 1e-6 and inverted.bump_distance == -0.25, \
        (inverted.bump_strength, inverted.bump_distance)
    chained = materials["over_normal_map"]
    assert chained.bump_texture >= 0 and chained.normal_texture >= 0, chained
    assert chained.normal_space == shgi.NormalMapSpace.TANGENT
    for name in ("alpha_height", "noise_height"):
        assert materials[name].bump_texture == -1, name
        assert any(f"material {name!r}: the Bump node's Height is not an Image Texture's Color"
                   in w for w in result.warnings), (name, result.warnings)
    # No warning for the materials SHGI evaluates.
    for name in ("plain_bump", "inverted_half", "over_normal_map"):
        assert not any(f"material {name!r}" in w for w in result.warnings), \
            (name, result.warnings)
    # The exported scene renders (the bumps reach the shading) without errors.
    result.scene.commit()
    shgi.render_path_traced(result.scene, shgi.PathTracerSettings(samples=2, seed=1))
    print("BUMP_EXPORT_OK", flush=True)


if __name__ == "__main__":
    main()
