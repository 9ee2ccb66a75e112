"""Baked lightmaps into Blender: images, and optionally nodes that show them in materials (bpy).

Images: ``<object>_shgi_lightmap``, float RGBA (alpha 1), filled from shgi.bake's Lightmap
array (engine/lightmap_bake.rgba_pixels: rows already in Image.pixels' order), packed into the
.blend file (as OpenEXR, float exact) with a fake user so that they survive saving and
reopening, as the EXR files beside the .blend file do.

Material nodes ("Show in Materials"): every node the bake adds is named "SHGI Lightmap..." and
sits between the material's surface shader and its output, so removing them
(remove_lightmap_nodes) gives back the material as it was:

    UV Map (the lightmap UV map) -> Image Texture "SHGI Lightmap"
        -> x base colour (Vector Math "SHGI Lightmap Albedo"; not for content FULL, which holds
           the colour already) -> Emission "SHGI Lightmap Emission"
    Mix Shader "SHGI Lightmap Mix" (Fac 1): the original surface | the lightmap's emission

SHGI's export reads the original surface through that Mix Shader, so later bakes and renders
see the material as it was. A material that other objects use too gets the nodes only in a
copy made for the object ("Make Materials Single-User"), else it is left alone with a warning.

Undo: the bake makes these images and nodes in one go at its end, inside its one undo step.
Should a "SHGI Lightmap" node still lose its image (an undo that keeps the material but drops
the image, a file saved so), the handlers registered here take the lightmap nodes out of that
material after every undo, redo and file load, so no image-less lightmap node reaches a
renderer.

The lightmap's texels are irradiance / pi (Cycles' Diffuse bake units), so times the base
colour they are the diffuse radiance a Lambert surface sends out, which an Emission of strength
1 shows: EEVEE draws the baked light (Fac blends back to the live shading), and the Image
Texture is the material's active node, which Workbench's Texture colour shows.
"""

from dataclasses import dataclass, field

import bpy
from bpy.app.handlers import persistent

from ..bake_settings import LIGHTMAP_MIX_NODE
from ..engine.lightmap_bake import rgba_pixels

IMAGE_SUFFIX = "_shgi_lightmap"
NODE_PREFIX = "SHGI Lightmap"
TEXTURE_NODE = NODE_PREFIX
UV_NODE = f"{NODE_PREFIX} UV"
ALBEDO_NODE = f"{NODE_PREFIX} Albedo"
EMISSION_NODE = f"{NODE_PREFIX} Emission"
MIX_NODE = LIGHTMAP_MIX_NODE  # SHGI's export reads the surface through it
# Inputs that hold a surface shader's diffuse colour (Principled, Diffuse and most BSDFs).
BASE_COLOR_INPUTS = ("Base Color", "Color")
# Node editor spacing of the added nodes (px), left of and below the output node.
NODE_STEP_X, NODE_STEP_Y = 220.0, 300.0


def image_name(object_name):
    return f"{object_name}{IMAGE_SUFFIX}"


def store_lightmap_image(lightmap):
    """The image ``<lightmap.name>_shgi_lightmap`` holding the lightmap's colour (made or
    updated in place, so materials showing it keep showing it)."""
    height, width = lightmap.color.shape[:2]
    name = image_name(lightmap.name)
    image = bpy.data.images.get(name)
    if image is not None and not image.is_float:  # an 8-bit image of that name: replace it
        image.name = f"{name}.old"
        image = None
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    elif tuple(image.size) != (width, height):
        image.scale(width, height)
    image.pixels.foreach_set(rgba_pixels(lightmap.color))
    image.update()
    image.use_fake_user = True
    image.pack()
    return image


@dataclass
class HookUps:
    """What "Show in Materials" did over a bake: the materials now showing a lightmap, how many
    of them are copies made single-user, and warnings about the materials left alone."""

    materials: list = field(default_factory=list)
    copies: int = 0
    warnings: list = field(default_factory=list)


def hook_up_lightmap(obj, image, uv_map, multiply_by_base_color, single_user, hook_ups):
    """Shows `image` through `uv_map` in the object's materials, recorded in `hook_ups`
    (HookUps). A material other objects use too is first copied for this object when
    `single_user`, else left alone with a warning."""
    materials = {slot.material for slot in obj.material_slots if slot.material is not None}
    if not materials:
        hook_ups.warnings.append(f"object {obj.name!r} has no material to show its lightmap in")
    for material in sorted(materials, key=lambda m: m.name):
        others = _other_users(obj, material)
        if others and single_user:
            material, others = _single_user_copy(obj, material), []
            hook_ups.copies += 1
        if others:
            hook_ups.warnings.append(
                f"material {material.name!r} of {obj.name!r} is also used by "
                f"{', '.join(others)}: its lightmap is not shown there (turn on Make Materials "
                "Single-User, or Object > Relations > Make Single User)")
        elif not material.use_nodes or material.node_tree.get_output_node("ALL") is None:
            hook_ups.warnings.append(f"material {material.name!r} has no node tree with a "
                                     "Material Output: its lightmap is not shown there")
        else:
            _add_lightmap_nodes(material.node_tree, image, uv_map, multiply_by_base_color)
            hook_ups.materials.append(material.name)


def _other_users(obj, material):
    """Names of the other objects whose material slots hold `material`."""
    return sorted(other.name for other in bpy.data.objects if other != obj and any(
        slot.material == material for slot in other.material_slots))


def _single_user_copy(obj, material):
    """A copy of `material` ("<material> <object>") in the object's slots that held it; a slot
    linked to a mesh other objects share is linked to the object instead, so the copy reaches
    this object only."""
    copy = material.copy()
    copy.name = f"{material.name} {obj.name}"
    shared_mesh = obj.data.users > 1
    for slot in obj.material_slots:
        if slot.material == material:
            if shared_mesh and slot.link == "DATA":
                slot.link = "OBJECT"
            slot.material = copy
    return copy


def _add_lightmap_nodes(tree, image, uv_map, multiply_by_base_color):
    remove_lightmap_nodes_from_tree(tree)
    output = tree.get_output_node("ALL")
    surface = output.inputs["Surface"]
    original = surface.links[0].from_socket if surface.is_linked else None
    x, y = output.location.x, output.location.y - NODE_STEP_Y

    def add(kind, name, column):
        node = tree.nodes.new(kind)
        node.name = node.label = name
        node.location = (x - column * NODE_STEP_X, y)
        return node

    uv = add("ShaderNodeUVMap", UV_NODE, 4)
    uv.uv_map = uv_map
    texture = add("ShaderNodeTexImage", TEXTURE_NODE, 3)
    texture.image = image
    tree.links.new(uv.outputs["UV"], texture.inputs["Vector"])
    radiance = texture.outputs["Color"]
    if multiply_by_base_color:
        albedo = add("ShaderNodeVectorMath", ALBEDO_NODE, 2)
        albedo.operation = "MULTIPLY"
        tree.links.new(radiance, albedo.inputs[0])
        _connect_base_color(tree, original, albedo.inputs[1])
        radiance = albedo.outputs["Vector"]
    emission = add("ShaderNodeEmission", EMISSION_NODE, 1)
    emission.inputs["Strength"].default_value = 1.0
    tree.links.new(radiance, emission.inputs["Color"])
    mix = add("ShaderNodeMixShader", MIX_NODE, 0)
    mix.inputs["Fac"].default_value = 1.0
    if original is not None:
        tree.links.new(original, mix.inputs[1])
    tree.links.new(emission.outputs["Emission"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], surface)
    tree.nodes.active = texture


def _connect_base_color(tree, shader_socket, target):
    """Feeds the surface shader's base colour (its link, else its value) into `target`; white
    when the surface has no colour input."""
    node = shader_socket.node if shader_socket is not None else None
    inputs = [node.inputs[name] for name in BASE_COLOR_INPUTS
              if node is not None and name in node.inputs]
    if not inputs:
        target.default_value = (1.0, 1.0, 1.0)
    elif inputs[0].is_linked:
        tree.links.new(inputs[0].links[0].from_socket, target)
    else:
        target.default_value = tuple(inputs[0].default_value)[:3]


def remove_lightmap_nodes(material):
    """Removes the "SHGI Lightmap..." nodes, linking the original surface to the output again;
    True when there were some."""
    if not material.use_nodes:
        return False
    return remove_lightmap_nodes_from_tree(material.node_tree)


def remove_lightmap_nodes_from_tree(tree):
    mix = tree.nodes.get(MIX_NODE)
    if mix is not None and mix.inputs[1].is_linked:
        original = mix.inputs[1].links[0].from_socket
        for link in list(mix.outputs["Shader"].links):
            tree.links.new(original, link.to_socket)
    nodes = [node for node in tree.nodes if node.name.startswith(NODE_PREFIX)]
    for node in nodes:
        tree.nodes.remove(node)
    return bool(nodes)


def drop_imageless_lightmap_nodes():
    """Takes the lightmap nodes out of every local material whose "SHGI Lightmap" Image
    Texture has no image; the number of materials changed."""
    dropped = 0
    for material in bpy.data.materials:
        tree = material.node_tree
        if tree is None or material.library is not None:
            continue
        texture = tree.nodes.get(TEXTURE_NODE)
        if texture is not None and getattr(texture, "image", None) is None:
            remove_lightmap_nodes_from_tree(tree)
            dropped += 1
    return dropped


@persistent
def _drop_after_undo_or_load(*_args):
    drop_imageless_lightmap_nodes()


HANDLERS = ("undo_post", "redo_post", "load_post")


def register():
    for name in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if _drop_after_undo_or_load not in handlers:
            handlers.append(_drop_after_undo_or_load)


def unregister():
    for name in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if _drop_after_undo_or_load in handlers:
            handlers.remove(_drop_after_undo_or_load)
